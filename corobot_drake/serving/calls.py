"""What the HTTP side asks of the simulation: functions of `(..., sim)` that a `Runner` calls
in the simulation thread (`submit`, `watch`). Module-level, so that bound with
`functools.partial` they pickle across the pipe to the simulation process; their results are
plain values (`readings.CommandResult`, numbers, numpy arrays) for the same reason.
"""

from __future__ import annotations

import math
from typing import Any

from corobot_drake import commands
from corobot_drake.readings import CommandResult


def issue(robot: str, command: str, arguments: dict, sim) -> tuple[int, float]:
    """Issues a simple drive command (`Robot.command("set_power", left=..., right=...)`, ...);
    returns (its sequence number, the simulated time)."""
    if commands.by_method(command).completing:
        raise ValueError(f"{command!r} is not a simple drive command")
    seq = sim.robot(robot).command(command, **arguments)
    return seq, sim.time


def start_operation(robot: str, command: str, arguments: dict, sim) -> CommandResult:
    """Starts a command that completes, without waiting; returns its record as of now."""
    if not commands.by_method(command).completing:
        raise ValueError(f"{command!r} is not a completing drive command")
    return sim.robot(robot).command(command, **arguments).result()


def command_result(robot: str, seq: int, sim) -> CommandResult:
    """The command log's record of the robot's command `seq`, as of now."""
    return sim.robot(robot).command_result(seq)


def ended_command(robot: str, seq: int, sim) -> CommandResult | None:
    """`command_result` once the command has ended; None while it runs (for `watch`)."""
    result = sim.robot(robot).command_result(seq)
    return None if result.end_time is None else result


def frame_time(robot: str, sim, camera: str | None = None) -> float:
    """Simulated time (s) of the latest frame the robot's camera (default: its front camera)
    has rendered, without fetching it; NaN before the first."""
    return sim.robot(robot).camera_image_time(camera)


def grab_frame(robot: str, sim, camera: str | None = None) -> tuple[float, float, Any]:
    """(sim time, frame time, RGB uint8 image h x w x 3) of the latest frame of the robot's
    camera (default: its front camera); (sim time, NaN, None) before the first."""
    import numpy as np

    r = sim.robot(robot)
    image = r.camera_image(camera)
    if image is None:  # before the first frame has come out of the camera
        return sim.time, math.nan, None
    return sim.time, r.camera_image_time(camera), np.ascontiguousarray(image[:, :, :3])
