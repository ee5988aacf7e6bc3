"""Odometry sensors and the drive state: wheel encoders, compass, GPS, the MRDS drive state.

- Encoders: Drake's `RotaryEncoders` on the front axles, 600 ticks per revolution (floor
  quantization of the integrated wheel angle), then a gain to ticks.
- `Compass`: chassis yaw about world z, radians in (-pi, pi] (a command that turns unwraps
  it from update to update, `motion.py`).
- `Gps`: chassis frame origin in the world, metres.
- `DriveStateReporter`: the four-wheel drive state (`DriveState`) with a two-wheel view.

All read the plant's state vector: no kinematics evaluation, and they change only when the
(discrete) plant steps.
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.common.value import Value
from pydrake.systems.framework import LeafSystem
from pydrake.systems.primitives import Gain
from pydrake.systems.sensors import RotaryEncoders

from corobot_drake.model import dimensions as dim
from corobot_drake.systems.drive import DriveStatus

ENCODED_WHEELS = ("front_left", "front_right")
"""Wheels with an encoder (indices 0 and 1 in `dimensions.WHEEL_NAMES`)."""


def add_wheel_encoders(builder, name: str, wheel_state_port):
    """Adds `<name>.encoders` (RotaryEncoders, radians quantized to 600 ticks/rev) and
    `<name>.encoder_ticks` (gain to ticks) fed by `wheel_state_port` ([q, v] of the four
    axles); returns the ticks output port (front_left, front_right)."""
    ticks = dim.ENCODER_TICKS_PER_REVOLUTION
    encoders = builder.AddNamedSystem(f"{name}.encoders", RotaryEncoders(
        8, [dim.WHEEL_NAMES.index(w) for w in ENCODED_WHEELS], [ticks] * len(ENCODED_WHEELS)))
    to_ticks = builder.AddNamedSystem(f"{name}.encoder_ticks",
                                      Gain(ticks / (2 * math.pi), len(ENCODED_WHEELS)))
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


def add_odometry(builder, name: str, num_states: int, positions_start: int, plant_state_port,
                 wheel_state_port, drive_status_port, axle_speed_port,
                 power_scaling_factor: float) -> OdometryPorts:
    """Adds one robot's encoders, `<name>.compass`, `<name>.gps` and
    `<name>.drive_state` (DriveStateReporter); returns their output ports."""
    ticks = add_wheel_encoders(builder, name, wheel_state_port)
    compass = builder.AddNamedSystem(f"{name}.compass", Compass(num_states, positions_start))
    gps = builder.AddNamedSystem(f"{name}.gps", Gps(num_states, positions_start))
    for system in (compass, gps):
        builder.Connect(plant_state_port, system.GetInputPort("plant_state"))
    reporter = builder.AddNamedSystem(f"{name}.drive_state",
                                      DriveStateReporter(power_scaling_factor))
    for port_name, port in (("drive_status", drive_status_port), ("axle_speed", axle_speed_port),
                            ("encoder_ticks", ticks),
                            ("position", gps.GetOutputPort("position")),
                            ("heading", compass.GetOutputPort("heading"))):
        builder.Connect(port, reporter.GetInputPort(port_name))
    return OdometryPorts(ticks, compass.GetOutputPort("heading"), gps.GetOutputPort("position"),
                         reporter.GetOutputPort("drive_state"))


def yaw_from_quaternion(w: float, x: float, y: float, z: float) -> float:
    """Yaw (rad, (-pi, pi]) of the rotation given by a quaternion: the heading of body +x
    projected on the world's x-y plane. The quaternion need not be unit length: the discrete
    plant's state quaternion drifts from unit norm as it integrates (Drake normalizes only when
    it makes a pose), and `1 - 2 (y^2 + z^2)` would then bias the heading (0.3 deg seen)."""
    return math.atan2(2.0 * (w * z + x * y), w * w + x * x - y * y - z * z)


class _ChassisSensor(LeafSystem):
    """Input `plant_state` (the plant's state vector); the chassis's floating-base positions
    (quaternion w, x, y, z then x, y, z) start at `positions_start`."""

    def __init__(self, num_states: int, positions_start: int):
        super().__init__()
        self._start = positions_start
        self._state_port = self.DeclareVectorInputPort("plant_state", num_states)

    def _q(self, context) -> np.ndarray:
        return self._state_port.Eval(context)[self._start:self._start + 7]


class Compass(_ChassisSensor):
    """Output `heading` (1-vector): chassis yaw about world z, rad in (-pi, pi]."""

    def __init__(self, num_states: int, positions_start: int):
        super().__init__(num_states, positions_start)
        self.DeclareVectorOutputPort(
            "heading", 1, lambda c, o: o.SetFromVector([yaw_from_quaternion(*self._q(c)[:4])]))


class Gps(_ChassisSensor):
    """Output `position` (3-vector): the chassis frame's origin in the world, m."""

    def __init__(self, num_states: int, positions_start: int):
        super().__init__(num_states, positions_start)
        self.DeclareVectorOutputPort("position", 3,
                                     lambda c, o: o.SetFromVector(self._q(c)[4:7]))


@dc.dataclass(frozen=True)
class WheelState:
    """One wheel: commanded power in [-1, 1], measured axle speed (rad/s), encoder ticks
    (None: no encoder)."""

    commanded_power: float
    axle_speed: float
    encoder_ticks: int | None = None


@dc.dataclass(frozen=True)
class TwoWheelDriveState:
    """The generic differential-drive view: left = front left, right = front right."""

    time_stamp: float
    is_enabled: bool
    distance_between_wheels: float
    left: WheelState
    right: WheelState


@dc.dataclass(frozen=True)
class DriveState:
    """MRDS's four-wheel drive state in SI units. Position (m) and heading (rad) come from
    the GPS and the compass; time stamp is simulation time (s)."""

    time_stamp: float
    is_enabled: bool
    distance_between_wheels: float
    power_scaling_factor: float
    """MotorTorqueScaling: axle rad/s at power 1."""
    wheels: dict[str, WheelState]
    position: tuple[float, float, float]
    heading: float

    def two_wheel(self) -> TwoWheelDriveState:
        return TwoWheelDriveState(self.time_stamp, self.is_enabled,
                                  self.distance_between_wheels, self.wheels["front_left"],
                                  self.wheels["front_right"])

    def as_dict(self) -> dict:
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
    (4, rad/s, `dimensions.WHEEL_NAMES` order), `encoder_ticks` (2, front left and front
    right, rounded to whole ticks here), `position` (3, m, world frame), `heading` (1, rad).
    Output `drive_state` (abstract DriveState; its time stamp is the context time, s).
    `power_scaling_factor` is the drive's MotorTorqueScaling.
    """

    def __init__(self, power_scaling_factor: float):
        super().__init__()
        self._scaling = power_scaling_factor
        self._ports = {name: self.DeclareVectorInputPort(name, size) for name, size in (
            ("drive_status", len(DriveStatus.get_fields())), ("axle_speed", 4),
            ("encoder_ticks", 2), ("position", 3), ("heading", 1))}
        self.DeclareAbstractOutputPort("drive_state", self._default, self._calc)

    def _default(self):
        wheel = WheelState(0.0, 0.0)
        return Value(DriveState(0.0, True, dim.TRACK, self._scaling,
                                dict.fromkeys(dim.WHEEL_NAMES, wheel), (0.0, 0.0, 0.0), 0.0))

    def _calc(self, context, output):
        axle, ticks, position, heading = (
            self._ports[n].Eval(context) for n in (
                "axle_speed", "encoder_ticks", "position", "heading"))
        status = DriveStatus(self._ports["drive_status"].Eval(context))
        wheels = {}
        for i, name in enumerate(dim.WHEEL_NAMES):
            power = float(status.power_left if name.endswith("left") else status.power_right)
            encoder = (round(ticks[ENCODED_WHEELS.index(name)])
                       if name in ENCODED_WHEELS else None)
            wheels[name] = WheelState(power, float(axle[i]), encoder)
        output.set_value(DriveState(
            context.get_time(), bool(status.enabled), dim.TRACK, self._scaling, wheels,
            tuple(float(v) for v in position), float(heading[0])))
