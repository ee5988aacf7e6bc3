"""The tip-over margin: how far the robot can still roll or pitch before it tips over.

The static stability margin of the support polygon: for each edge of the polygon the wheels'
ground contact points make (front, rear, left, right), the rotation about that edge that would
bring the robot's centre of mass (all its bodies, wheels included) into the vertical plane
through the edge; the margin is the least of them, deg. Upright at rest on level ground it is
the pitch one, atan(half wheelbase / CoM height) = 37.4 deg (the roll one, atan(half track /
CoM height), is 42.9); negative once the CoM is outside the polygon (tipping).

- Contact points: each wheel's lowest point, the bottom of its tyre's mid-plane circle (the
  wheel centre, one nominal radius down), from the chassis pose alone: no contact results, so
  the margin costs what a pose does.
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

SUPPORT_ORDER = ("front_left", "rear_left", "rear_right", "front_right")
"""The wheels round the support polygon (anticlockwise seen from above, upright)."""


def tip_margin_deg(com, contacts) -> float:
    """The least rotation (deg) about an edge of the polygon through `contacts` (k points,
    world, in order round it) that brings `com` (world) over that edge; negative outside it.
    Plain floats (lists are fastest): on four 3-vectors numpy's per-call overhead costs more
    than the sums, and this runs every step."""
    cx, cy, cz = com
    points = [tuple(p) for p in contacts]
    mx, my, mz = (sum(p[i] for p in points) / len(points) for i in range(3))
    least = math.inf
    for (px, py, pz), (qx, qy, qz) in zip(points, points[1:] + points[:1], strict=True):
        ax, ay, az = qx - px, qy - py, qz - pz
        norm = math.sqrt(ax * ax + ay * ay + az * az)
        ax, ay, az = ax / norm, ay / norm, az / norm
        vx, vy, vz = -az * ax, -az * ay, 1.0 - az * az  # the upward direction about the edge
        norm = math.sqrt(vx * vx + vy * vy + vz * vz)
        vx, vy, vz = vx / norm, vy / norm, vz / norm
        ix, iy, iz = vy * az - vz * ay, vz * ax - vx * az, vx * ay - vy * ax  # vertical x axis
        if (mx - px) * ix + (my - py) * iy + (mz - pz) * iz < 0:  # towards the inside
            ix, iy, iz = -ix, -iy, -iz
        lx, ly, lz = cx - px, cy - py, cz - pz
        least = min(least, math.atan2(lx * ix + ly * iy + lz * iz, lx * vx + ly * vy + lz * vz))
    return math.degrees(least)


class TipMargin(LeafSystem):
    """One robot's tip-over margin (module docstring) and the least of it over the run.

    .. pydrake_system::

        name: TipMargin
        input_ports:
        - chassis_pose
        output_ports:
        - tip_margin
        - min_tip_margin

    Input `chassis_pose` (abstract RigidTransform X_WC, e.g. from `odometry.ChassisPoses`).
    Outputs (1-vectors, deg): `tip_margin` now; `min_tip_margin`, the least of it sampled every
    `period` s (discrete state, from time 0) and now.

    The robot is rigid but for its wheels turning on their axles, which pass through their
    centres of mass: its centre of mass `com_C` and the wheel centres `wheel_centers_C` (m)
    are fixed in the chassis frame C, and the axles lie along C's y (`of_robot` reads them
    from a plant). So the chassis pose alone places them, as cheaply as the tilt monitor's.
    """

    def __init__(self, com_C, wheel_centers_C, period: float,
                 wheel_radius: float = dim.WHEEL_RADIUS):
        """`wheel_centers_C`: {wheel name: centre} (`dimensions.WHEEL_NAMES`)."""
        super().__init__()
        self._com_C = np.asarray(com_C, dtype=float).tolist()
        self._centers_C = [np.asarray(wheel_centers_C[name], dtype=float).tolist()
                           for name in SUPPORT_ORDER]
        self._radius = wheel_radius
        self._pose = self.DeclareAbstractInputPort("chassis_pose",
                                                   AbstractValue.Make(RigidTransform()))
        self._least = self.DeclareDiscreteState([math.inf])
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._sample)
        # A function of the pose alone: cached until the pose changes, so the sample, the
        # run log and the summary share one computation a step.
        self._margin = self.DeclareVectorOutputPort(
            "tip_margin", 1, lambda c, o: o.SetAtIndex(0, self.margin(c)),
            {self.input_port_ticket(self._pose.get_index())})
        self.DeclareVectorOutputPort("min_tip_margin", 1, lambda c, o: o.SetAtIndex(
            0, min(c.get_discrete_state(self._least).GetAtIndex(0), self._margin.Eval(c)[0])))

    @classmethod
    def of_robot(cls, plant, model_instance, chassis, wheels: dict, period: float):
        """The TipMargin of the robot `model_instance` of the finalized `plant` (its bodies'
        default masses and the default poses of `chassis` and the `wheels`, {name: body})."""
        context = plant.CreateDefaultContext()
        X_CW = plant.EvalBodyPoseInWorld(context, chassis).inverse()
        com_C = X_CW @ plant.CalcCenterOfMassPositionInWorld(context, [model_instance])
        centers = {name: (X_CW @ plant.EvalBodyPoseInWorld(context, body)).translation()
                   for name, body in wheels.items()}
        return cls(com_C, centers, period)

    def com(self, context) -> np.ndarray:
        """The robot's centre of mass in the world, m."""
        return self._pose.Eval(context) @ np.array(self._com_C)

    def margin(self, context) -> float:
        """The tip-over margin now, deg (plain floats, as `tip_margin_deg`)."""
        R = self._pose.Eval(context).rotation().matrix().tolist()

        def rotate(p):  # about the chassis origin: the margin needs no translation
            return [R[0][0] * p[0] + R[0][1] * p[1] + R[0][2] * p[2],
                    R[1][0] * p[0] + R[1][1] * p[1] + R[1][2] * p[2],
                    R[2][0] * p[0] + R[2][1] * p[1] + R[2][2] * p[2]]

        ax, ay, az = R[0][1], R[1][1], R[2][1]  # the axles' direction
        dx, dy, dz = az * ax, az * ay, az * az - 1.0  # towards each tyre's bottom, in its plane
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        scale = self._radius / length if length > 1e-9 else 0.0  # 0: lying on its side
        bottoms = [[x + scale * dx, y + scale * dy, z + scale * dz]
                   for x, y, z in map(rotate, self._centers_C)]
        return tip_margin_deg(rotate(self._com_C), bottoms)

    def _sample(self, context, discrete_state):
        least = context.get_discrete_state(self._least).GetAtIndex(0)
        discrete_state.set_value(self._least, [min(least, self._margin.Eval(context)[0])])


def add_tip_margin(builder, name: str, plant, model_instance, chassis, wheels: dict,
                   chassis_pose_port, period: float):
    """Adds `<name>.tip_margin` (`TipMargin.of_robot`) fed by `chassis_pose_port`; returns
    it."""
    system = builder.AddNamedSystem(f"{name}.tip_margin", TipMargin.of_robot(
        plant, model_instance, chassis, wheels, period))
    builder.Connect(chassis_pose_port, system.get_input_port())
    return system
