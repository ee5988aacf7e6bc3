"""Meshcat drawings that ride on a robot's link, redrawn at a rate Meshcat shows.

`ThrottledDrawing` is the base of a sensor's drawing: drawn at initialization, then on the
simulator's steps at most every `MOVE_PERIOD` s. A kind draws its sensor's fixed shape once (a
camera's view frustum) in the sensor frame's coordinates under a Meshcat path, and
`FollowFrame` moves that path with the link as the robot drives.
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.geometry import Rgba
from pydrake.math import RigidTransform
from pydrake.systems.framework import LeafSystem

MOVE_PERIOD = 1.0 / 30.0
"""s: the least time between two moves (Meshcat shows at most about 30 frames a second)."""
FRUSTUM_DEPTH = 0.3
"""m: how far ahead of a camera its drawn view frustum reaches."""
_FRUSTUM_COLOR = Rgba(1.0, 0.8, 0.1, 0.8)


class ThrottledDrawing(LeafSystem):
    """A Meshcat drawing (`draw(context)`, the subclass's) made at initialization and then
    at most every `MOVE_PERIOD` s: it looks at every step (one comparison of times), with no
    event of its own, so a continuous plant's steps are not split. `draws` counts them."""

    def __init__(self):
        super().__init__()
        self._drawn = -math.inf
        self.draws = 0
        """How many times it has drawn (for tests)."""
        self.DeclareInitializationPublishEvent(self._draw_now)
        self.DeclarePerStepPublishEvent(self._draw_if_due)

    def draw(self, context) -> None:
        raise NotImplementedError

    def _draw_if_due(self, context) -> None:
        if context.get_time() >= self._drawn + MOVE_PERIOD * (1.0 - 1e-9):
            self._draw_now(context)

    def _draw_now(self, context) -> None:
        self.draw(context)
        self._drawn = context.get_time()
        self.draws += 1


class FollowFrame(ThrottledDrawing):
    """Sets the Meshcat transform of `path` to the world pose of a frame S fixed to a body,
    X_WS = X_WB X_BS, at initialization and then at most every `MOVE_PERIOD` s.

    .. pydrake_system::

        name: FollowFrame
        input_ports:
        - body_poses

    Input: the plant's `body_poses`.
    """

    def __init__(self, meshcat, path: str, body_index, X_BS: RigidTransform):
        super().__init__()
        self._meshcat, self.path = meshcat, path
        self._body, self._X_BS = int(body_index), X_BS
        self._poses = self.DeclareAbstractInputPort(
            "body_poses", AbstractValue.Make([RigidTransform()]))

    def draw(self, context) -> None:
        X_WB = self._poses.Eval(context)[self._body]
        # With the time, a recording (`--record`'s replay) animates it too.
        self._meshcat.SetTransform(self.path, X_WB.multiply(self._X_BS), context.get_time())


def frustum_segments(fov_x: float, fov_y: float, depth: float = FRUSTUM_DEPTH
                     ) -> tuple[np.ndarray, np.ndarray]:
    """(starts, ends), each 3 x 8, m, in a camera's optical frame (+z forward, +x right, +y
    down): the four edges from the centre of projection to the corners of the image plane
    `depth` ahead, then that rectangle; fov_x, fov_y: the full fields of view, rad."""
    x, y = depth * math.tan(fov_x / 2), depth * math.tan(fov_y / 2)
    corners = np.array([[x, y, depth], [-x, y, depth], [-x, -y, depth], [x, -y, depth]]).T
    starts = np.hstack([np.zeros((3, 4)), corners])
    ends = np.hstack([corners, np.roll(corners, -1, axis=1)])
    return starts, ends


def draw_frustum(meshcat, path: str, fov_x: float, fov_y: float) -> None:
    """A camera's view frustum under `path` (`frustum_segments`), in its optical frame."""
    starts, ends = frustum_segments(fov_x, fov_y)
    meshcat.SetLineSegments(f"{path}/frustum", np.asfortranarray(starts),
                            np.asfortranarray(ends), 2.0, _FRUSTUM_COLOR)
