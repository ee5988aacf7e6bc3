"""The tip-over margin: how far the robot can still roll or pitch before it tips over.

The static stability margin of the support polygon: for each edge of the polygon the wheels'
ground contact points make (front, rear, left, right), the rotation about that edge that would
bring the robot's centre of mass (all its bodies, wheels included) into the vertical plane
through the edge; the margin is the least of them, deg. Upright at rest on level ground it is
the pitch one, atan(half wheelbase / CoM height) = 37.4 deg (the roll one, atan(half track /
CoM height), is 42.9); negative once the CoM is outside the polygon (tipping).

- Contact points: each wheel's lowest point, the bottom of its tyre's mid-plane circle (the
  wheel centre, one nominal radius down), from the poses alone: no contact results, so the
  margin is as cheap as a pose.
- Every wheel counts, in contact or not. A rigid robot tips about the edge between the wheels
  that still bear; lifting the others only turns it about that edge, whose margin the least
  already is, so the margin falls to 0 exactly as it goes over. (It would count a wheel that
  hangs over a drop, which the scenes here do not have.)
- A rigid measure, conservative: a round tyre rolls its contact point on under the axle as
  the chassis pitches (over a locked wheel the robot goes at atan(a / (h - R)) = 57 deg), and
  the rolled tyre's outer edge widens the track by its half width.
"""

import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform
from pydrake.systems.framework import LeafSystem

from corobot_drake.model import dimensions as dim

UP = np.array([0.0, 0.0, 1.0])
SUPPORT_ORDER = ("front_left", "rear_left", "rear_right", "front_right")
"""The wheels round the support polygon (anticlockwise seen from above, upright)."""


def wheel_bottom(X_WW: RigidTransform, radius: float = dim.WHEEL_RADIUS) -> np.ndarray:
    """The lowest point (world, m) of the circle of `radius` about the wheel frame's origin in
    its x-z plane (the axle is the wheel frame's y); the centre if the wheel lies flat."""
    n = X_WW.rotation().matrix()[:, 1]
    down = -(UP - (UP @ n) * n)
    length = np.linalg.norm(down)
    centre = X_WW.translation()
    return centre + radius * down / length if length > 1e-9 else centre


def tip_margin_deg(com: np.ndarray, contacts: np.ndarray) -> float:
    """The least rotation (deg) about an edge of the polygon through `contacts` ([k, 3], world,
    in order round it) that brings `com` (world) over that edge; negative outside it."""
    centre = contacts.mean(axis=0)
    margins = []
    for p, q in zip(contacts, np.roll(contacts, -1, axis=0), strict=True):
        axis = (q - p) / np.linalg.norm(q - p)
        vertical = UP - (UP @ axis) * axis  # the upward direction about this edge
        vertical /= np.linalg.norm(vertical)
        inward = np.cross(vertical, axis)
        if (centre - p) @ inward < 0:
            inward = -inward
        lever = com - p
        margins.append(math.atan2(lever @ inward, lever @ vertical))
    return math.degrees(min(margins))


class TipMargin(LeafSystem):
    """One robot's tip-over margin (module docstring) and the least of it over the run.

    .. pydrake_system::

        name: TipMargin
        input_ports:
        - body_poses
        output_ports:
        - tip_margin
        - min_tip_margin

    Input `body_poses` (the plant's, indexed by BodyIndex). Outputs (1-vectors, deg):
    `tip_margin` now; `min_tip_margin`, the least of it sampled every `period` s (discrete
    state, from time 0) and now. The robot's mass distribution is the plant's default (each
    body's mass and centre of mass, read once).
    """

    def __init__(self, plant, model_instance, wheels: dict, period: float):
        """`wheels`: {wheel name: its body}, `dimensions.WHEEL_NAMES`."""
        super().__init__()
        bodies = [plant.get_body(i) for i in plant.GetBodyIndices(model_instance)]
        self._bodies = [int(b.index()) for b in bodies]
        masses = np.array([b.default_mass() for b in bodies])
        self._weights = masses / masses.sum()
        self._coms = [np.asarray(b.default_com()) for b in bodies]
        self._support = [int(wheels[name].index()) for name in SUPPORT_ORDER]
        self._poses = self.DeclareAbstractInputPort("body_poses",
                                                    AbstractValue.Make([RigidTransform()]))
        self._least = self.DeclareDiscreteState([math.inf])
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._sample)
        self.DeclareVectorOutputPort("tip_margin", 1, lambda c, o: o.SetAtIndex(
            0, self.margin(c)))
        self.DeclareVectorOutputPort("min_tip_margin", 1, lambda c, o: o.SetAtIndex(
            0, min(c.get_discrete_state(self._least).GetAtIndex(0), self.margin(c))))

    def com(self, context) -> np.ndarray:
        """The robot's centre of mass in the world, m."""
        poses = self._poses.Eval(context)
        return sum(w * poses[i].multiply(p) for w, i, p in zip(self._weights, self._bodies,
                                                         self._coms, strict=True))

    def margin(self, context) -> float:
        poses = self._poses.Eval(context)
        contacts = np.array([wheel_bottom(poses[i]) for i in self._support])
        return tip_margin_deg(self.com(context), contacts)

    def _sample(self, context, discrete_state):
        least = context.get_discrete_state(self._least).GetAtIndex(0)
        discrete_state.set_value(self._least, [min(least, self.margin(context))])


def add_tip_margin(builder, name: str, plant, model_instance, wheels: dict, period: float):
    """Adds `<name>.tip_margin` (`TipMargin`) fed by the plant's body poses; returns it."""
    system = builder.AddNamedSystem(f"{name}.tip_margin",
                                    TipMargin(plant, model_instance, wheels, period))
    builder.Connect(plant.get_body_poses_output_port(), system.get_input_port())
    return system
