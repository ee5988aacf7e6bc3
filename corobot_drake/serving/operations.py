"""Operations: the completing drive commands (drive_distance, rotate_degrees, set_pose) started
over HTTP, each with an id and a status URL.

`Operations` remembers only what was asked (robot, command, arguments) and the command's
sequence number; how the command is going is its record in the command log, which lives in
the simulation's Context and is read there (`calls.command_result`, `calls.ended_command`)
whenever it is asked for. Used from the HTTP event loop's thread only.
"""

from __future__ import annotations

import dataclasses as dc
import itertools

from corobot_drake.readings import CommandResult
from corobot_drake.serving.snapshots import jsonable


@dc.dataclass(frozen=True)
class Operation:
    """A completing command started over HTTP (its status: the command log's record)."""

    id: int
    robot: str
    command: str
    """The HTTP command: drive_distance, rotate_degrees or set_pose."""
    arguments: dict
    seq: int
    """The command's sequence number in the robot's command log."""

    @property
    def status_url(self) -> str:
        return f"/robots/{self.robot}/drive/operations/{self.id}"

    def state(self, result: CommandResult) -> dict:
        """The operation's JSON (`schemas.OperationState`) given its command's record."""
        return jsonable({
            "id": self.id, "robot": self.robot, "command": self.command,
            "arguments": self.arguments, "seq": self.seq, "status": result.status,
            "reason": result.reason, "start_time": result.start_time,
            "end_time": result.end_time, "status_url": self.status_url,
        })


OPERATIONS_KEPT = 1000
"""The newest operations kept (their status URLs answer); older ones answer 404, as their
records leave the command log (`drive.COMMAND_LOG_CAPACITY`) too."""


class Operations:
    """The operations started over HTTP, by id (ids count from 1 across robots); the newest
    `OPERATIONS_KEPT`."""

    def __init__(self):
        self._operations: dict[int, Operation] = {}
        self._ids = itertools.count(1)

    def add(self, robot: str, command: str, arguments: dict, seq: int) -> Operation:
        operation = Operation(next(self._ids), robot, command, arguments, seq)
        self._operations[operation.id] = operation
        if len(self._operations) > OPERATIONS_KEPT:  # dicts keep insertion order
            del self._operations[next(iter(self._operations))]
        return operation

    def get(self, robot: str, op_id: int) -> Operation | None:
        """Operation `op_id` if it was started on `robot`."""
        operation = self._operations.get(op_id)
        return operation if operation is not None and operation.robot == robot else None
