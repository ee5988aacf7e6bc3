"""The tip-over margin: how far the robot can still roll or pitch before it tips over.

The static stability margin of the support polygon: for each edge of the rectangle the
wheels' ground contact points make (front, rear, left, right), the rotation about that edge
that would bring the robot's centre of mass (all its bodies, wheels included) into the vertical
plane through the edge; the margin is the least of them, deg. Upright at rest on level ground it
is the pitch one, atan(half wheelbase / CoM height) = 37.4 deg (the roll one, atan(half track /
CoM height), is 42.9); 0 as the CoM passes over an edge, negative beyond (tipping).

- Contact points: each wheel's lowest point, the bottom of its tyre's mid-plane circle (one
  nominal radius from the wheel centre, straight down in the plane of the wheel), from the
  chassis pose alone: no contact results, so the margin costs what a pose does.
- Every wheel counts, in contact or not. A rigid robot tips about the edge between the wheels
  that still bear; lifting the others only turns it about that edge, whose margin the least
  already is. (It would count a wheel that hangs over a drop, which the scenes here do not
  have.)
- An instantaneous measure: the rotation about the present edge. Pitching, a round tyre rolls
  its contact point on under the axle, so the margin falls by ~0.68 deg per degree of pitch at
  first and reaches 0 where the robot really goes over (CoM above the axle: 57 deg from rest).
  Rolling, the tyre's outer edge bears, not its mid-plane: the margin is 0 a half tyre width
  (28 mm) early, conservative.
"""


import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform
from pydrake.systems.framework import LeafSystem

from corobot_drake.robots import corobot


class TipMargin(LeafSystem):
    """One robot's tip-over margin (module docstring).

    .. pydrake_system::

        name: TipMargin
        input_ports:
        - chassis_pose
        output_ports:
        - tip_margin

    Input `chassis_pose` (abstract RigidTransform X_WC, e.g. from `odometry.ChassisPoses`).
    Output `tip_margin` (1-vector, deg), evaluated only when read. No state: the least over
    the run is the run log's (`runlog`: its rows' margins, every 10 ms, made by
    `margin_of_up` from the logged chassis state when the log is read).

    The robot is rigid but for its wheels turning on their axles, which pass through their
    centres of mass: its centre of mass `com_C` and the wheel centres `wheel_centers_C` (m)
    are fixed in the chassis frame C, the centres make a rectangle square to C's axes and the
    axles lie along C's y (`of_robot` reads them from a plant). So the chassis' tilt alone
    places the support and the CoM, and the margin is a few sums in C.
    """

    def __init__(self, com_C, wheel_centers_C: dict, wheel_radius: float = corobot.wheels("radius"),
                 casters_C=()):
        """`wheel_centers_C`: {wheel name: centre}; `casters_C`: the (x, y) of each caster's
        contact (m, C): the support's edges are the outermost of both."""
        super().__init__()
        self._com_C = [float(x) for x in com_C]
        c = {name: [float(x) for x in p] for name, p in wheel_centers_C.items()}
        xs = [p[0] for p in c.values()] + [float(p[0]) for p in casters_C]
        ys = [p[1] for p in c.values()] + [float(p[1]) for p in casters_C]
        self._front, self._rear = max(xs), min(xs)  # edges' x and y, m
        self._left, self._right = max(ys), min(ys)
        self._axle_z = sum(p[2] for p in c.values()) / len(c)
        self._radius = wheel_radius
        self._pose = self.DeclareAbstractInputPort("chassis_pose",
                                                   AbstractValue.Make(RigidTransform()))
        self.DeclareVectorOutputPort("tip_margin", 1, lambda c, o: o.SetAtIndex(
            0, self.margin(c)), {self.input_port_ticket(self._pose.get_index())})

    @classmethod
    def of_robot(cls, plant, model_instance, chassis, wheels: dict, wheel_radius: float =
                 corobot.wheels("radius"), casters_C=()):
        """The TipMargin of the robot `model_instance` of the finalized `plant` (its bodies'
        default masses and the default poses of `chassis` and the `wheels`, {name: body});
        `casters_C` as the constructor's."""
        context = plant.CreateDefaultContext()
        # The chassis at the world origin: the figures in C are then exact whatever pose the
        # scenario starts it at (a reset to another start gives the same bits).
        plant.SetFreeBodyPose(context, chassis, RigidTransform())
        com_C = plant.CalcCenterOfMassPositionInWorld(context, [model_instance])
        centers = {name: plant.EvalBodyPoseInWorld(context, body).translation()
                   for name, body in wheels.items()}
        return cls(com_C, centers, wheel_radius, casters_C)

    def com(self, context) -> np.ndarray:
        """The robot's centre of mass in the world, m."""
        return self._pose.Eval(context) @ np.array(self._com_C)

    def margin(self, context) -> float:
        """The tip-over margin now, deg (`margin_of_up` of the chassis pose)."""
        ux, uy, uz = self._pose.Eval(context).rotation().matrix()[2]  # R^T z
        return float(self.margin_of_up(ux, uy, uz))

    def margin_of_up(self, ux, uy, uz):
        """The tip-over margin, deg, with the world's up (ux, uy, uz) in the chassis frame C
        (the last row of R_WC): floats or arrays (the run log's rows, `runlog.rows_of`).
        Each edge's margin is atan2(lever . inward, lever . up about the edge), the lever from
        the edge to the CoM, both directions in the plane square to the edge, unnormalized
        (atan2 needs no norm)."""
        across = np.hypot(ux, uz)
        # The tyres' bottoms: down in the wheel's plane (x-z of C), a radius from the axle;
        # 0: lying on its side.
        scale = np.where(across > 1e-9, self._radius / np.maximum(across, 1e-9), 0.0)
        cx, cy, cz = self._com_C
        lz = cz - (self._axle_z - scale * uz)  # CoM above the bottoms, along C's z
        front, rear = cx - (self._front - scale * ux), cx - (self._rear - scale * ux)
        left, right = cy - self._left, cy - self._right
        return np.degrees(np.minimum.reduce([
            np.arctan2(lz * ux - front * uz, front * ux + lz * uz),  # inward -x
            np.arctan2(rear * uz - lz * ux, rear * ux + lz * uz),  # inward +x
            np.arctan2(lz * uy - left * uz, left * uy + lz * uz),  # inward -y
            np.arctan2(right * uz - lz * uy, right * uy + lz * uz)]))  # inward +y


def add_tip_margin(builder, name: str, plant, model_instance, chassis, wheels: dict,
                   chassis_pose_port, wheel_radius: float = corobot.wheels("radius"), casters_C=()):
    """Adds `<name>.tip_margin` (`TipMargin.of_robot`) fed by `chassis_pose_port`; returns
    it."""
    system = builder.AddNamedSystem(f"{name}.tip_margin", TipMargin.of_robot(
        plant, model_instance, chassis, wheels, wheel_radius, casters_C))
    builder.Connect(chassis_pose_port, system.get_input_port())
    return system
