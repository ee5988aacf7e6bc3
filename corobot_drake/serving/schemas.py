"""The HTTP contract's pydantic models: request bodies (validated) and response descriptions
(for the OpenAPI document; responses are built as dicts by `snapshots` and the routes).

The class names are the OpenAPI document's schema names, which clients generate code from, so
they stay as published; refer to them as `schemas.DriveState` etc., distinct from the domain
types (`systems.odometry.DriveState`, `systems.drive.CommandStatus`). Models carry no
docstrings unless their schema has a description.
"""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field

from corobot_drake import limits

DEFAULT_WAIT_TIMEOUT = 120.0
"""s a completing command may hold its request open before answering 202 with a status URL."""

# --- request bodies ---------------------------------------------------------------------


class _Body(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)


Power = Annotated[float, Field(ge=limits.SIDE_POWER.low, le=limits.SIDE_POWER.high,
                               description="power in [-1, 1]")]
DrivePower = Annotated[float, Field(gt=limits.DRIVE_POWER.low, le=limits.DRIVE_POWER.high,
                                    description="power in (0, 1]")]
Speed = Annotated[float, Field(ge=limits.SIDE_SPEED.low, le=limits.SIDE_SPEED.high,
                               description="rim speed, m/s")]
WaitTimeout = Annotated[float, Field(gt=0.0, le=600.0,
                                     description="s to hold the request open (wall clock)")]


class PowerRequest(_Body):
    left: Power
    right: Power


class SpeedRequest(_Body):
    left: Speed
    right: Speed


class VelocityRequest(_Body):
    linear: Annotated[float, Field(ge=limits.LINEAR_SPEED.low, le=limits.LINEAR_SPEED.high,
                                   description="m/s forward (the drive clamps the axle speed)")]
    angular: Annotated[float, Field(ge=limits.YAW_RATE.low, le=limits.YAW_RATE.high,
                                    description="rad/s yaw rate, positive turns left")]


class EnableRequest(_Body):
    enabled: bool = True


class EmptyRequest(_Body):
    pass


class _Completing(_Body):
    wait: bool = Field(True, description="hold the request until the command ends; false: "
                       "answer 202 at once with the operation's status URL")
    timeout: WaitTimeout = DEFAULT_WAIT_TIMEOUT


class DriveDistanceRequest(_Completing):
    distance: Annotated[float, Field(ge=limits.DISTANCE.low, le=limits.DISTANCE.high,
                                     description="m; negative: backwards")]
    power: DrivePower = 0.2


class RotateDegreesRequest(_Completing):
    degrees: Annotated[float, Field(ge=limits.DEGREES.low, le=limits.DEGREES.high,
                                    description="degrees; positive turns left (CCW)")]
    power: DrivePower = 0.2


class SetPoseRequest(_Completing):
    x: Annotated[float, Field(ge=limits.POSITION.low, le=limits.POSITION.high, description="m")]
    y: Annotated[float, Field(ge=limits.POSITION.low, le=limits.POSITION.high, description="m")]
    yaw_deg: Annotated[float, Field(ge=limits.YAW_DEG.low, le=limits.YAW_DEG.high)] = 0.0


# --- response descriptions (for the OpenAPI document) --------------------------------------


class Wheel(BaseModel):
    commanded_power: float = Field(description="in [-1, 1]")
    axle_speed: float = Field(description="measured, rad/s")
    encoder_ticks: int | None = Field(None, description="front wheels only")
    load: float | None = Field(None, description="N: the wheel's vertical contact force")
    slip_ratio: float | None = Field(
        None, description="(rim speed - ground speed) / the faster: + traction, - braking")
    slip_angle_deg: float | None = Field(
        None, description="deg: the wheel's travel from its heading, + to the left")


class Position(BaseModel):
    x: float
    y: float
    z: float


class CommandStatus(BaseModel):
    seq: int
    command: str
    status: str
    reason: str
    start_time: float
    end_time: float | None


class DriveState(BaseModel):
    """Four-wheel drive state (MRDS DriveDifferentialFourWheelState in SI units)."""

    time_stamp: float = Field(description="simulation time, s")
    is_enabled: bool
    power_scaling_factor: float = Field(description="MotorTorqueScaling: rad/s at power 1")
    distance_between_wheels: float
    wheel_radius: float
    encoder_ticks_per_revolution: int
    wheels: dict[str, Wheel] = Field(description="front_left, front_right, rear_left, rear_right")
    position: Position
    heading: float = Field(description="rad, counter-clockwise from +x")
    heading_deg: float
    pose: dict[str, float]
    velocity: dict[str, float]
    command: CommandStatus | None
    tip_margin_deg: float = Field(
        description="deg: the roll or pitch left before the centre of mass passes an edge of "
                    "the wheels' support (37.4 upright on level ground)")


class TwoWheelState(BaseModel):
    time_stamp: float
    is_enabled: bool
    distance_between_wheels: float
    left: Wheel
    right: Wheel
    position: Position
    heading: float
    command: CommandStatus | None


class AnalogSensorState(BaseModel):
    raw: float = Field(description="distance, m")
    range: float = Field(description="maximum range, m")
    normalized: float = Field(description="raw / range")
    time_stamp: float = Field(description="simulation time of the scan, s")


class EncoderState(BaseModel):
    time_stamp: float
    ticks_per_revolution: int
    front_left: int | None
    front_right: int | None


class Accepted(BaseModel):
    robot: str
    command: str
    seq: int | None = None
    status: str
    time: float


class OperationState(BaseModel):
    id: int
    robot: str
    command: str
    arguments: dict[str, Any]
    seq: int | None
    status: str = Field(description="running, succeeded or failed")
    reason: str
    start_time: float
    end_time: float | None
    status_url: str


class ServiceEntry(BaseModel):
    robot: str
    name: str
    contract: str
    state_url: str
    subscribe_url: str | None = None
    operations: list[str] = []
    page_url: str | None = None


class Directory(BaseModel):
    services: list[ServiceEntry]
    simulation_url: str
    dashboard_url: str
    meshcat_url: str | None


class ErrorMessage(BaseModel):
    detail: str


ERRORS = {400: {"model": ErrorMessage}, 404: {"model": ErrorMessage},
          422: {"model": ErrorMessage}, 501: {"model": ErrorMessage},
          503: {"model": ErrorMessage}}
"""The error answers every resource documents: {"detail": "<one sentence>"}."""
