"""The drive contract: state, simple commands (answered at once), completing commands (held
until they end, or 202 with a status URL) and their operations."""

import asyncio
from functools import partial

from fastapi import APIRouter, HTTPException
from fastapi.responses import Response

from corobot_drake import commands
from corobot_drake.readings import CommandResult
from corobot_drake.serving import calls, schemas
from corobot_drake.serving.routes.backend import (
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


# --- the commands: one route each, made of its declaration (`commands.py`) ---


async def simple_command(backend: Backend, robot: str, command: str, arguments: dict
                         ) -> Response:
    """Issues the command in the simulation thread; answers `schemas.Accepted`."""
    backend.robot(robot)
    seq, t = await backend.in_sim(partial(calls.issue, robot, command, arguments))
    return json_response({"robot": robot, "command": command, "seq": seq,
                          "status": "accepted", "time": t})


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


def add_command_route(spec: commands.CommandSpec) -> None:
    """`POST /robots/{robot}/drive/<method>` for one command, its body `schemas.REQUESTS`'
    model: a simple command answers `Accepted`, a completing one its operation's state."""
    request = schemas.REQUESTS[spec.method]
    names = [arg.name for arg in spec.args]

    async def endpoint(robot: str, body: request, backend: BackendDep):  # type: ignore[valid-type]
        arguments = {name: getattr(body, name) for name in names}
        if spec.completing:
            return await completing(backend, robot, spec.method, arguments, body.wait,
                                    body.timeout)
        return await simple_command(backend, robot, spec.method, arguments)

    router.add_api_route(
        f"/robots/{{robot}}/drive/{spec.method}", endpoint, methods=["POST"], name=spec.method,
        response_model=schemas.OperationState if spec.completing else schemas.Accepted,
        responses=COMPLETING if spec.completing else ERRORS, summary=spec.summary)


for _spec in commands.ISSUABLE:
    add_command_route(_spec)


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
                        f"{', '.join(commands.BY_METHOD)}")
