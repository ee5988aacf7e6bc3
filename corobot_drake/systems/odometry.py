"""Odometry sensors and the drive state: wheel encoders, compass, GPS, the MRDS drive state.

- `ChassisPoses`: each robot's chassis pose X_WB picked from the plant's `body_poses` output
  (Drake makes it from the normalized state quaternion); the compass, the GPS, the tilt
  monitor and the run log read it.
- Encoders: Drake's `RotaryEncoders` on the front axles, 600 ticks per revolution (floor
  quantization of the integrated wheel angle), then a gain to ticks.
- `Compass`: chassis yaw about world z, radians in (-pi, pi] (a command that turns unwraps
  it from update to update, `motion.py`).
- `Gps`: chassis frame origin in the world, metres.
- `DriveStateReporter`: the four-wheel drive state (`DriveState`) with a two-wheel view.

They change only when the (discrete) plant steps.
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.common.value import AbstractValue, Value
from pydrake.math import RigidTransform
from pydrake.systems.framework import LeafSystem, ValueProducer
from pydrake.systems.primitives import Gain, MatrixGain
from pydrake.systems.sensors import RotaryEncoders

from corobot_drake.robots import corobot
from corobot_drake.systems.drive import DriveStatus

CHASSIS_STATE = ("qw", "qx", "qy", "qz", "x", "y", "z")
"""The chassis' floating-base positions in the plant's state, Drake's order: the quaternion of
R_WB (w first, not normalized by every integrator), then the origin in the world, m."""

ENCODED_WHEELS = ("front_left", "front_right")
"""The Corobot's wheels with an encoder (indices 0 and 1 of its wheels,
`RobotSpec.encoded`)."""


def add_wheel_encoders(builder, name: str, wheel_state_port, wheels: int = 4,
                       encoded: tuple[int, int] = (0, 1),
                       ticks: int = corobot.drive("encoder_ticks_per_revolution")):
    """Adds `<name>.encoders` (RotaryEncoders, radians quantized to `ticks` per revolution)
    and `<name>.encoder_ticks` (gain to ticks) fed by `wheel_state_port` ([q, v] of the
    `wheels` axles); returns the ticks output port of the `encoded` wheels [left, right]
    (`RobotSpec.encoded`; the Corobot's front_left and front_right)."""
    encoders = builder.AddNamedSystem(f"{name}.encoders", RotaryEncoders(
        2 * wheels, list(encoded), [ticks] * len(encoded)))
    to_ticks = builder.AddNamedSystem(f"{name}.encoder_ticks",
                                      Gain(ticks / (2 * math.pi), len(encoded)))
    builder.Connect(wheel_state_port, encoders.get_input_port())
    builder.Connect(encoders.get_output_port(), to_ticks.get_input_port())
    return to_ticks.get_output_port()


@dc.dataclass
class OdometryPorts:
    """Output ports of one robot's odometry."""

    encoder_ticks: object
    heading: object
    position: object
    drive_state: object


def add_chassis_poses(builder, plant, chassis: dict) -> dict:
    """Adds `chassis_poses` (`ChassisPoses` of the robots' `chassis` bodies, by robot name,
    fed by the plant's `body_poses`); returns {robot name: its `pose` output port}."""
    system = builder.AddNamedSystem("chassis_poses", ChassisPoses(
        {name: body.index() for name, body in chassis.items()}))
    builder.Connect(plant.get_body_poses_output_port(), system.get_input_port())
    return {name: system.GetOutputPort(name) for name in chassis}


def add_chassis_states(builder, plant, chassis: dict) -> dict:
    """Adds `<robot>.chassis_state` (a MatrixGain picking `CHASSIS_STATE` out of the plant's
    state: C++, no Python call when read) per robot's `chassis` body ({robot name: body});
    returns {robot name: its output port}."""
    ports = {}
    for name, body in chassis.items():
        pick = np.zeros((len(CHASSIS_STATE), plant.num_multibody_states()))
        start = body.floating_positions_start()
        pick[:, start:start + len(CHASSIS_STATE)] = np.eye(len(CHASSIS_STATE))
        gain = builder.AddNamedSystem(f"{name}.chassis_state", MatrixGain(pick))
        builder.Connect(plant.get_state_output_port(), gain.get_input_port())
        ports[name] = gain.get_output_port()
    return ports


def rotation_rows(quaternions: np.ndarray) -> np.ndarray:
    """[n, 3, 3]: the rotation matrices of `quaternions` [n, 4] (w, x, y, z; normalized
    here, as Drake does for the body poses)."""
    q = quaternions / np.linalg.norm(quaternions, axis=1, keepdims=True)
    w, x, y, z = q.T
    return np.stack([
        np.column_stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)]),
        np.column_stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)]),
        np.column_stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]),
    ], axis=1)


def add_odometry(builder, name: str, chassis_pose_port, wheel_state_port, drive_status_port,
                 axle_speed_port, power_scaling_factor: float, spec=None) -> OdometryPorts:
    """Adds one robot's encoders, `<name>.compass` and `<name>.gps` (fed by
    `chassis_pose_port`) and `<name>.drive_state` (DriveStateReporter); returns their output
    ports. `spec`: the robot's `RobotSpec` (None: the Corobot's)."""
    if spec is None:
        from corobot_drake.robots import robot_spec

        spec = robot_spec()
    ticks = add_wheel_encoders(builder, name, wheel_state_port, len(spec.wheels), spec.encoded,
                               spec.encoder_ticks_per_revolution)
    compass = builder.AddNamedSystem(f"{name}.compass", Compass())
    gps = builder.AddNamedSystem(f"{name}.gps", Gps())
    for system in (compass, gps):
        builder.Connect(chassis_pose_port, system.GetInputPort("chassis_pose"))
    reporter = builder.AddNamedSystem(f"{name}.drive_state",
                                      DriveStateReporter(power_scaling_factor, spec.wheel_names,
                                                         spec.sides, spec.encoded, spec.track))
    for port_name, port in (("drive_status", drive_status_port), ("axle_speed", axle_speed_port),
                            ("encoder_ticks", ticks),
                            ("position", gps.GetOutputPort("position")),
                            ("heading", compass.GetOutputPort("heading"))):
        builder.Connect(port, reporter.GetInputPort(port_name))
    return OdometryPorts(ticks, compass.GetOutputPort("heading"), gps.GetOutputPort("position"),
                         reporter.GetOutputPort("drive_state"))


def heading_of(X_WB: RigidTransform) -> float:
    """Yaw (rad, (-pi, pi]) of a pose: the heading of body +x projected on the world's x-y
    plane, atan2(R[1, 0], R[0, 0])."""
    X = X_WB.GetAsMatrix34()  # [R | p]: one call, cheaper than rotation().matrix()
    return math.atan2(X[1, 0], X[0, 0])


class ChassisPoses(LeafSystem):
    """Picks the robots' chassis poses out of the plant's `body_poses` (as manipulation's
    `ExtractPose` does, for several bodies at once).

    .. pydrake_system::

        name: ChassisPoses
        input_ports:
        - body_poses
        output_ports:
        - <robot name> ...

    Input `body_poses` (abstract list of RigidTransform: the MultibodyPlant output, indexed by
    BodyIndex). One output per robot, named by it (abstract RigidTransform): X_WB, the pose of
    its chassis frame B in the world frame W; translation in m. The list (every body of every
    robot) is converted to Python once per plant step, in a cache entry, not once per robot:
    the cost per robot stays flat however many share the plant.
    """

    def __init__(self, body_indices: dict[str, int]):
        super().__init__()
        self._poses = self.DeclareAbstractInputPort("body_poses",
                                                    AbstractValue.Make([RigidTransform()]))
        self._list = self.DeclareCacheEntry(
            "body_poses_list", ValueProducer(allocate=lambda: Value(object()),
                                             calc=lambda c, v: v.set_value(self._poses.Eval(c))),
            {self.input_port_ticket(self._poses.get_index())})
        for name, index in body_indices.items():
            self.DeclareAbstractOutputPort(
                name, lambda: AbstractValue.Make(RigidTransform()),
                lambda c, o, i=int(index): o.set_value(self._list.Eval(c)[i]),
                {self._list.ticket()})


class _ChassisSensor(LeafSystem):
    """Input `chassis_pose` (abstract RigidTransform X_WB, from `ChassisPoses`)."""

    def __init__(self):
        super().__init__()
        self._pose_port = self.DeclareAbstractInputPort("chassis_pose",
                                                        AbstractValue.Make(RigidTransform()))
        self._ticket = {self.input_port_ticket(self._pose_port.get_index())}
        """Outputs are functions of the pose alone (not of time)."""

    def _pose(self, context) -> RigidTransform:
        return self._pose_port.Eval(context)


class Compass(_ChassisSensor):
    """The chassis heading.

    .. pydrake_system::

        name: Compass
        input_ports:
        - chassis_pose
        output_ports:
        - heading

    Input `chassis_pose` (abstract RigidTransform X_WB). Output `heading` (1-vector): chassis
    yaw about world z, rad in (-pi, pi] (`heading_of`).
    """

    def __init__(self):
        super().__init__()
        self.DeclareVectorOutputPort(
            "heading", 1, lambda c, o: o.SetFromVector([heading_of(self._pose(c))]),
            self._ticket)


class Gps(_ChassisSensor):
    """The chassis position.

    .. pydrake_system::

        name: Gps
        input_ports:
        - chassis_pose
        output_ports:
        - position

    Input `chassis_pose` (abstract RigidTransform X_WB). Output `position` (3-vector): the
    chassis frame's origin in the world frame, m.
    """

    def __init__(self):
        super().__init__()
        self.DeclareVectorOutputPort(
            "position", 3, lambda c, o: o.SetFromVector(self._pose(c).translation()),
            self._ticket)


@dc.dataclass(frozen=True)
class WheelState:
    """One wheel: commanded power in [-1, 1], measured axle speed (rad/s), encoder ticks
    (None: no encoder)."""

    commanded_power: float
    axle_speed: float
    encoder_ticks: int | None = None


@dc.dataclass(frozen=True)
class TwoWheelDriveState:
    """The generic differential-drive view (`DriveState.two_wheel()`): `left` and `right` are
    the encoded wheels (the Corobot's front left and front right); time stamp: simulation
    time (s); `distance_between_wheels`: the track (m)."""

    time_stamp: float
    is_enabled: bool
    distance_between_wheels: float
    left: WheelState
    right: WheelState


@dc.dataclass(frozen=True)
class DriveState:
    """MRDS's four-wheel drive state in SI units (`Robot.drive_state()`). Time stamp:
    simulation time (s); `distance_between_wheels`: the track (m); `wheels`: each wheel's
    state by wheel name (`RobotSpec.wheel_names`); `position` (x, y, z; m, world frame) and
    `heading` (rad) come from the GPS and the compass."""

    time_stamp: float
    is_enabled: bool
    distance_between_wheels: float
    power_scaling_factor: float
    """MotorTorqueScaling: axle rad/s at power 1."""
    wheels: dict[str, WheelState]
    position: tuple[float, float, float]
    heading: float

    encoded: tuple[str, str] = ("front_left", "front_right")
    """The wheels [left, right] with an encoder: the differential-drive view's."""

    def two_wheel(self) -> TwoWheelDriveState:
        """The differential-drive view: the `encoded` wheels as left and right."""
        left, right = self.encoded
        return TwoWheelDriveState(self.time_stamp, self.is_enabled,
                                  self.distance_between_wheels, self.wheels[left],
                                  self.wheels[right])

    def as_dict(self) -> dict:
        """The state as plain dicts, lists and numbers (`dataclasses.asdict`)."""
        return dc.asdict(self)


class DriveStateReporter(LeafSystem):
    """Assembles the `drive_state` output (DriveState) from the drive and the odometry.

    .. pydrake_system::

        name: DriveStateReporter
        input_ports:
        - drive_status
        - axle_speed
        - encoder_ticks
        - position
        - heading
        output_ports:
        - drive_state

    Inputs: `drive_status` (5, `drive.DriveStatus`, from the DriveController), `axle_speed`
    (n, rad/s, the robot's wheel order, `RobotSpec.wheels`), `encoder_ticks` (2, the
    encoded left and right wheels: the Corobot's front left and front
    right, rounded to whole ticks here), `position` (3, m, world frame), `heading` (1, rad).
    Output `drive_state` (abstract DriveState; its time stamp is the context time, s).
    `power_scaling_factor` is the drive's MotorTorqueScaling.
    """

    def __init__(self, power_scaling_factor: float, wheel_names=None,
                 sides=(1, -1, 1, -1), encoded: tuple[int, int] = (0, 1),
                 track: float = corobot.wheels("track")):
        """`wheel_names`, `sides` (+1 left, -1 right) and the `encoded` wheels' indices in
        wheel order, and the `track` (m): the robot's (`RobotSpec`; the Corobot's)."""
        super().__init__()
        if wheel_names is None:
            wheel_names = corobot.spec().wheel_names
        self._scaling = power_scaling_factor
        self._names, self._track = tuple(wheel_names), track
        self._left = tuple(s > 0 for s in sides)
        self._encoded = {k: j for j, k in enumerate(encoded)}
        self._ports = {name: self.DeclareVectorInputPort(name, size) for name, size in (
            ("drive_status", len(DriveStatus.get_fields())), ("axle_speed", len(sides)),
            ("encoder_ticks", 2), ("position", 3), ("heading", 1))}
        # Its time and inputs only: every subsystem's state changes at every step.
        self.DeclareAbstractOutputPort("drive_state", self._default, self._calc,
                                       {self.time_ticket(), self.all_input_ports_ticket()})

    def _default(self):
        wheel = WheelState(0.0, 0.0)
        return Value(DriveState(0.0, True, self._track, self._scaling,
                                dict.fromkeys(self._names, wheel), (0.0, 0.0, 0.0), 0.0,
                                self._encoded_names()))

    def _encoded_names(self) -> tuple[str, str]:
        return tuple(self._names[k] for k in self._encoded)

    def _calc(self, context, output):
        axle, ticks, position, heading = (
            self._ports[n].Eval(context) for n in (
                "axle_speed", "encoder_ticks", "position", "heading"))
        status = DriveStatus(self._ports["drive_status"].Eval(context))
        wheels = {}
        for i, name in enumerate(self._names):
            power = float(status.power_left if self._left[i] else status.power_right)
            j = self._encoded.get(i)
            wheels[name] = WheelState(power, float(axle[i]),
                                      None if j is None else round(ticks[j]))
        output.set_value(DriveState(
            context.get_time(), bool(status.enabled), self._track, self._scaling, wheels,
            tuple(float(v) for v in position), float(heading[0]), self._encoded_names()))
