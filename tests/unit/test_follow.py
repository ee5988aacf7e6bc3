"""Meshcat drawings that ride on a link (`sensors/follow.py`): the FollowFrame system alone,
its inputs fixed, and the camera frustum's geometry against its field of view."""

import math

import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.systems.analysis import Simulator

from corobot_drake.sensors.follow import (
    FRUSTUM_DEPTH,
    MOVE_PERIOD,
    FollowFrame,
    frustum_segments,
)


class TransformRecorder:
    """Meshcat's SetTransform recorded: {path: the last transform set}."""

    def __init__(self):
        self.transforms = {}

    def SetTransform(self, path, X, time_in_recording):
        self.transforms[path] = X
        self.time = time_in_recording


def test_the_path_follows_the_frame_on_its_body_at_most_30_times_a_second():
    X_WB = RigidTransform(RollPitchYaw(0, 0, math.pi / 2), [1.0, 2.0, 0.0])
    X_BS = RigidTransform([0.1, 0.0, 0.05])
    meshcat = TransformRecorder()
    follow = FollowFrame(meshcat, "/camera/bot/front", 1, X_BS)
    context = follow.CreateDefaultContext()
    follow.get_input_port().FixValue(context, AbstractValue.Make([RigidTransform(), X_WB]))
    simulator = Simulator(follow, context)
    for k in range(1, 101):  # 10 ms steps, as the plant's (a stateless system takes one each)
        simulator.AdvanceTo(k * 0.01)
    X = meshcat.transforms["/camera/bot/front"]
    # Body 1's frame turned 90 deg: S's 0.1 m ahead is +y in the world.
    np.testing.assert_allclose(X.translation(), (1.0, 2.1, 0.05), atol=1e-12)
    assert X.IsNearlyEqualTo(X_WB.multiply(X_BS), 1e-12)
    assert meshcat.time == pytest.approx(1.0)  # stamped: a recording animates it
    # 10 ms steps: a move every 40 ms (the first step at or after 1/30 s), and the first.
    assert follow.draws == pytest.approx(1.0 / MOVE_PERIOD, abs=6)
    assert follow.draws < 1.0 / 0.01 / 2


def test_the_frustum_reaches_the_image_corners_at_its_depth():
    """A 40 x 30 deg view: the four edges from the origin end at (+-d tan 20, +-d tan 15, d)
    in the optical frame (+z forward), and the rectangle joins them corner to corner."""
    fov_x, fov_y = math.radians(40), math.radians(30)
    starts, ends = frustum_segments(fov_x, fov_y)
    assert starts.shape == ends.shape == (3, 8)
    np.testing.assert_array_equal(starts[:, :4], 0.0)
    d = FRUSTUM_DEPTH
    corners = {tuple(np.round(c, 12)) for c in ends[:, :4].T}
    assert corners == {(round(sx * d * math.tan(fov_x / 2), 12),
                        round(sy * d * math.tan(fov_y / 2), 12), d)
                       for sx in (1, -1) for sy in (1, -1)}
    np.testing.assert_array_equal(starts[:, 4:], ends[:, :4])  # the rectangle's corners
    assert {tuple(c) for c in ends[:, 4:].T} == {tuple(c) for c in ends[:, :4].T}
