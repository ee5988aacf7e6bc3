"""What the robot reports: plain values shared by the Python API and the HTTP client.

No Drake import here, so `corobot_drake.serving.client` works where pydrake is not installed.
"""

import dataclasses as dc


@dc.dataclass(frozen=True)
class BodyPose:
    """Chassis pose in the world: metres and radians (roll, pitch, yaw extrinsic x-y-z)."""

    x: float
    y: float
    z: float
    roll: float
    pitch: float
    yaw: float


@dc.dataclass(frozen=True)
class BodyVelocity:
    """Chassis velocity in its own heading frame: forward, lateral (m/s), yaw_rate (rad/s)."""

    forward: float
    lateral: float
    yaw_rate: float


@dc.dataclass(frozen=True)
class OdometryPose:
    """The dead-reckoned pose (`Robot.odometry()`): x, y in m (chassis origin, world frame),
    yaw in rad in (-pi, pi], integrated from the encoders since the start."""

    x: float
    y: float
    yaw: float


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
        return self.status == "succeeded"


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
