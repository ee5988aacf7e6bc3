"""What the robot reports: plain values shared by the Python API and the HTTP client.

No Drake import here, so `corobot_drake.serving.client` works where pydrake is not installed.
"""

import dataclasses as dc


def _rounded_repr(reading, formats: dict[str, str]) -> str:
    """`Name(field=value unit, ...)`: each number of `formats` ({field: format spec and unit,
    e.g. ".4f m"}) rounded for a reader (0.1 mm, 0.1 mrad, 1 ms; the fields keep every
    digit), other fields as repr()."""
    parts = []
    for field in dc.fields(reading):
        value = getattr(reading, field.name)
        if field.name in formats and value is not None:
            spec, _, unit = formats[field.name].partition(" ")
            text = format(float(value), spec)
            if float(text) == 0.0:  # -1e-6 m is 0.0000 m, not -0.0000 m
                text = text.lstrip("-")
            value = f"{text} {unit}".rstrip()
        else:
            value = repr(value)
        parts.append(f"{field.name}={value}")
    return f"{type(reading).__name__}({', '.join(parts)})"


@dc.dataclass(frozen=True)
class BodyPose:
    """Chassis pose in the world: metres and radians (roll, pitch, yaw extrinsic x-y-z)."""

    x: float
    y: float
    z: float
    roll: float
    pitch: float
    yaw: float

    def __repr__(self) -> str:
        return _rounded_repr(self, {"x": ".4f m", "y": ".4f m", "z": ".4f m", "roll": ".4f rad",
                                    "pitch": ".4f rad", "yaw": ".4f rad"})


@dc.dataclass(frozen=True)
class BodyVelocity:
    """Chassis velocity in its own heading frame: forward, lateral (m/s), yaw_rate (rad/s)."""

    forward: float
    lateral: float
    yaw_rate: float

    def __repr__(self) -> str:
        return _rounded_repr(self, {"forward": ".4f m/s", "lateral": ".4f m/s",
                                    "yaw_rate": ".4f rad/s"})


@dc.dataclass(frozen=True)
class OdometryPose:
    """The dead-reckoned pose (`Robot.odometry()`): x, y in m (chassis origin, world frame),
    yaw in rad in (-pi, pi], integrated from the encoders since the start."""

    x: float
    y: float
    yaw: float

    def __repr__(self) -> str:
        return _rounded_repr(self, {"x": ".4f m", "y": ".4f m", "yaw": ".4f rad"})


@dc.dataclass(frozen=True)
class CommandResult:
    """How a command went: status running, succeeded or failed; reason when failed
    (superseded, disabled, stalled; not_applied for a SetPose); times in simulated s.
    `seq` is the command's sequence number (None when a server did not report it)."""

    seq: int | None
    command: str
    status: str
    reason: str
    start_time: float
    end_time: float | None

    @property
    def succeeded(self) -> bool:
        """Whether the command has ended and succeeded."""
        return self.status == "succeeded"

    def __repr__(self) -> str:
        return _rounded_repr(self, {"start_time": ".3f s", "end_time": ".3f s"})

    def describe(self) -> str:
        """E.g. `DriveDistance succeeded, t = 0.500 to 2.310 s` (a handle's repr)."""
        status = self.status + (f" ({self.reason})" if self.reason else "")
        times = (f"since t = {self.start_time:.3f} s" if self.end_time is None
                 else f"t = {self.start_time:.3f} to {self.end_time:.3f} s")
        return f"{self.command} {status}, {times}"


@dc.dataclass(frozen=True)
class IrReading:
    """An analog-sensor view of one scan (MRDS AnalogSensorState): metres and seconds."""

    raw: float
    """The reading: the distance to the nearest hit, maximum_range when nothing is hit."""
    range: float
    """maximum_range."""
    normalized: float
    """raw / range, in [0, 1]."""
    time: float
    """Simulated time of the scan."""

    def __repr__(self) -> str:
        return _rounded_repr(self, {"raw": ".4f m", "range": ".4f m", "normalized": ".3f",
                                    "time": ".3f s"})


@dc.dataclass(frozen=True, repr=False)
class CameraImage:
    """A camera's latest frame (its reading; field names those of sensor_msgs/Image): `data`
    a numpy array height x width x 4 (RGBA, uint8, a copy; None before the first frame),
    `time` the simulated time (s) it was captured (NaN before the first)."""

    width: int
    height: int
    encoding: str
    data: object
    time: float

    def __repr__(self) -> str:
        return (f"CameraImage({self.width} x {self.height} {self.encoding}, "
                f"time={self.time:.3f} s{'' if self.data is not None else ', no frame yet'})")
