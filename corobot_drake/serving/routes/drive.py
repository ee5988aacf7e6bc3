"""The drive contract: state, simple commands (answered at once), completing commands (held
until they end, or 202 with a status URL) and their operations."""

from __future__ import annotations

import asyncio
from functools import partial

from fastapi import APIRouter, HTTPException
from fastapi.responses import Response

from corobot_drake.readings import CommandResult
from corobot_drake.serving import calls, schemas
from corobot_drake.serving.routes.backend import (
    DRIVE_OPERATIONS,
    Backend,
    BackendDep,
    json_response,
)
from corobot_drake.serving.runner import SimulationStoppedError
from corobot_drake.serving.snapshots import two_wheel_view

router = APIRouter(tags=["drive"])
ERRORS = schemas.ERRORS
COMPLETING = {**ERRORS, 202: {"model": schemas.OperationState}}


@router.get("/robots/{robot}/drive", response_model=schemas.DriveState, responses=ERRORS,
            summary="Four-wheel drive state")
async def get_drive(robot: str, backend: BackendDep):
    return json_response(backend.snapshot_of(robot)["drive"])


@router.get("/robots/{robot}/drive/two_wheel", response_model=schemas.TwoWheelState,
            responses=ERRORS, summary="Two-wheel view (left = front left, right = front right)")
async def get_two_wheel(robot: str, backend: BackendDep):
    return json_response(two_wheel_view(backend.snapshot_of(robot)["drive"]))


# --- simple commands ---


async def simple_command(backend: Backend, robot: str, command: str, *args) -> Response:
    """Issues the command in the simulation thread; answers `schemas.Accepted`."""
    backend.robot(robot)
    seq, t = await backend.in_sim(partial(calls.issue, robot, command, args))
    return json_response({"robot": robot, "command": command, "seq": seq,
                          "status": "accepted", "time": t})


@router.post("/robots/{robot}/drive/set_power", response_model=schemas.Accepted,
             responses=ERRORS, summary="Power per side in [-1, 1]")
async def set_power(robot: str, body: schemas.PowerRequest, backend: BackendDep):
    return await simple_command(backend, robot, "set_power", body.left, body.right)


@router.post("/robots/{robot}/drive/set_speed", response_model=schemas.Accepted,
             responses=ERRORS, summary="Rim speed per side, m/s")
async def set_speed(robot: str, body: schemas.SpeedRequest, backend: BackendDep):
    return await simple_command(backend, robot, "set_speed", body.left, body.right)


@router.post("/robots/{robot}/drive/set_velocity", response_model=schemas.Accepted,
             responses=ERRORS,
             summary="Chassis velocity (cmd_vel): linear m/s, angular rad/s (positive left)")
async def set_velocity(robot: str, body: schemas.VelocityRequest, backend: BackendDep):
    return await simple_command(backend, robot, "set_velocity", body.linear, body.angular)


@router.post("/robots/{robot}/drive/all_stop", response_model=schemas.Accepted,
             responses=ERRORS, summary="Both sides to zero speed")
async def all_stop(robot: str, body: schemas.EmptyRequest, backend: BackendDep):
    return await simple_command(backend, robot, "all_stop")


@router.post("/robots/{robot}/drive/enable", response_model=schemas.Accepted,
             responses=ERRORS, summary="Enable or disable the drive")
async def enable(robot: str, body: schemas.EnableRequest, backend: BackendDep):
    return await simple_command(backend, robot, "enable", body.enabled)


# --- completing commands ---


async def completing(backend: Backend, robot: str, command: str, arguments: dict,
                     wait: bool, timeout: float) -> Response:
    """Starts the command; with `wait`, holds the request until it ends (up to `timeout` s).
    Answers its operation's state: 200 once ended, 202 while it runs."""
    backend.robot(robot)
    result = await backend.in_sim(partial(calls.start_operation, robot, command, arguments))
    operation = backend.operations.add(robot, command, arguments, result.seq)
    if wait and result.end_time is None:
        result = await _ended(backend, robot, result.seq, timeout) or result
    code = 200 if result.status != "running" else 202
    return json_response(operation.state(result), code,
                         headers={"Location": operation.status_url})


async def _ended(backend: Backend, robot: str, seq: int,
                 timeout: float) -> CommandResult | None:
    """The command's record once it has ended; None if it runs on after `timeout` s."""
    future = backend.runner.watch(partial(calls.ended_command, robot, seq))
    try:
        return await asyncio.wait_for(asyncio.wrap_future(future), timeout)
    except TimeoutError:
        return None  # wait_for cancelled the watch
    except SimulationStoppedError as e:  # the simulation stopped meanwhile
        raise HTTPException(503, str(e)) from None


@router.post("/robots/{robot}/drive/drive_distance", response_model=schemas.OperationState,
             responses=COMPLETING,
             summary="Drive straight |distance| m (negative: backwards); completes")
async def drive_distance(robot: str, body: schemas.DriveDistanceRequest, backend: BackendDep):
    args = {"distance": body.distance, "power": body.power}
    return await completing(backend, robot, "drive_distance", args, body.wait, body.timeout)


@router.post("/robots/{robot}/drive/rotate_degrees", response_model=schemas.OperationState,
             responses=COMPLETING,
             summary="Turn in place (positive: left, counter-clockwise); completes")
async def rotate_degrees(robot: str, body: schemas.RotateDegreesRequest, backend: BackendDep):
    args = {"degrees": body.degrees, "power": body.power}
    return await completing(backend, robot, "rotate_degrees", args, body.wait, body.timeout)


@router.post("/robots/{robot}/drive/set_pose", response_model=schemas.OperationState,
             responses=COMPLETING,
             summary="Teleport the robot to (x, y, yaw) on the ground; completes when settled")
async def set_pose(robot: str, body: schemas.SetPoseRequest, backend: BackendDep):
    args = {"x": body.x, "y": body.y, "yaw_deg": body.yaw_deg}
    return await completing(backend, robot, "set_pose", args, body.wait, body.timeout)


@router.get("/robots/{robot}/drive/operations/{op_id}", response_model=schemas.OperationState,
            responses=ERRORS, summary="A completing command's status")
async def operation(robot: str, op_id: int, backend: BackendDep):
    backend.robot(robot)
    op = backend.operations.get(robot, op_id)
    if op is None:
        raise HTTPException(404, f"no operation {op_id} on robot {robot!r}")
    return json_response(op.state(
        await backend.in_sim(partial(calls.command_result, robot, op.seq))))


@router.post("/robots/{robot}/drive/{command}", include_in_schema=False)
async def unknown_command(robot: str, command: str, backend: BackendDep):
    backend.robot(robot)
    raise HTTPException(404, f"the drive has no command {command!r}; commands: "
                        f"{', '.join(DRIVE_OPERATIONS)}")
