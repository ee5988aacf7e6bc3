"""The HTTP contract's pydantic models: request bodies (validated) and response descriptions
(for the OpenAPI document; responses are built as dicts by `snapshots` and the routes).

The class names are the OpenAPI document's schema names, which clients generate code from, so
they stay as published; refer to them as `schemas.DriveState` etc., distinct from the domain
types (`systems.odometry.DriveState`, `systems.drive.CommandStatus`). Models carry no
docstrings unless their schema has a description.
"""

from __future__ import annotations

import dataclasses as dc
from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field, create_model

from corobot_drake import commands, signals

DEFAULT_WAIT_TIMEOUT = 120.0
"""s a completing command may hold its request open before answering 202 with a status URL."""

# --- request bodies ---------------------------------------------------------------------


class _Body(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)


WaitTimeout = Annotated[float, Field(gt=0.0, le=600.0,
                                     description="s to hold the request open (wall clock)")]


class _Completing(_Body):
    wait: bool = Field(True, description="hold the request until the command ends; false: "
                       "answer 202 at once with the operation's status URL")
    timeout: WaitTimeout = DEFAULT_WAIT_TIMEOUT


def _argument(spec: commands.CommandSpec, arg: commands.Arg) -> tuple[Any, Any]:
    """An argument's pydantic field: its type, range (`limits`), description and default."""
    default = spec.http_defaults.get(arg.name, arg.default)
    default = ... if default is dc.MISSING else default
    if arg.range is None:
        return arg.type, Field(default, description=arg.doc or None)
    r = arg.range
    bounds = {"gt" if r.low_open else "ge": r.low, "lt" if r.high_open else "le": r.high}
    description = "; ".join(filter(None, (arg.doc, r.text())))
    return Annotated[arg.type, Field(**bounds, description=description)], default


def request_model(spec: commands.CommandSpec) -> type[BaseModel]:
    """The request body of a command's route, made of its declaration (`commands.py`): its
    arguments (all required but those with defaults), plus `wait` and `timeout` for a command
    that completes. Named as published (`spec.http_request`)."""
    base = _Completing if spec.completing else _Body
    fields = {arg.name: _argument(spec, arg) for arg in spec.args}
    return create_model(spec.http_request, __base__=base, __module__=__name__, **fields)


REQUESTS: dict[str, type[BaseModel]] = {s.method: request_model(s) for s in commands.ISSUABLE}
"""Each issuable command's request model by its route name (`set_power`: `PowerRequest`)."""


# --- response descriptions (for the OpenAPI document) --------------------------------------


def _with_signals(base: type[BaseModel], name: str, prefix: str) -> type[BaseModel]:
    """`base` as the model `name`, with a field for each signal placed at `<prefix><field>` in
    the HTTP state (`signals.Signal.http`) that it does not declare (null when missing)."""
    fields = {}
    for spec in signals.SIGNALS.values():
        for place in spec.http:
            path = place.partition("|")[0]
            field = path.removeprefix(prefix)
            if (not path.startswith(prefix) or "." in field or field in base.model_fields
                    or field in fields):
                continue
            kind = int if spec.integer else float
            if "*" not in prefix and (spec.keys or spec.reader):  # a dict by key
                kind = dict[str, kind]
            unit = f"{spec.unit}: " if spec.unit else ""
            fields[field] = (kind | None, Field(None, description=unit + spec.doc))
    return create_model(name, __base__=base, __module__=__name__, __doc__=base.__doc__,
                        **fields)


class _Wheel(BaseModel):
    side: str = Field(description="left or right")
    commanded_power: float = Field(description="in [-1, 1]")
    axle_speed: float = Field(description="measured, rad/s")
    encoder_ticks: int | None = Field(
        None, description="the wheels with an encoder only: the first of each side (the "
                          "Corobot's front wheels)")
    load: float | None = Field(None, description="N: the wheel's vertical contact force")
    slip_ratio: float | None = Field(
        None, description="(rim speed - ground speed) / the faster: + traction, - braking")
    slip_angle_deg: float | None = Field(
        None, description="deg: the wheel's travel from its heading, + to the left")


Wheel = _with_signals(_Wheel, "Wheel", "drive.wheels.*.")


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


class _DriveState(BaseModel):
    """Drive state (MRDS DriveDifferentialFourWheelState in SI units, for the robot's
    wheels)."""

    time_stamp: float = Field(description="simulation time, s")
    is_enabled: bool
    power_scaling_factor: float = Field(description="MotorTorqueScaling: rad/s at power 1")
    distance_between_wheels: float
    wheel_radius: float
    encoder_ticks_per_revolution: int
    wheels: dict[str, Wheel] = Field(
        description="by wheel name, in the robot's wheel order (the Corobot's front_left, "
                    "front_right, rear_left, rear_right)")
    position: Position
    heading: float = Field(description="rad, counter-clockwise from +x")
    heading_deg: float
    pose: dict[str, float]
    velocity: dict[str, float]
    command: CommandStatus | None
    tip_margin_deg: float = Field(
        description="deg: the roll or pitch left before the centre of mass passes an edge of "
                    "the wheels' support (37.4 upright on level ground)")


DriveState = _with_signals(_DriveState, "DriveState", "drive.")


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
    """The ticks of the wheels with an encoder, by wheel name (left, then right; the
    Corobot's front_left and front_right)."""

    model_config = ConfigDict(extra="allow")
    time_stamp: float
    ticks_per_revolution: int
    front_left: int | None = None
    front_right: int | None = None


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
