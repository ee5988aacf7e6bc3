"""A robot's commands: issue them, wait for them, read how they ended (`Robot` has these).

Every command is a scenario command dataclass (`commands.py`) issued to the robot's command
source; `CommandHandle` follows one issued without waiting.
"""

import functools
import logging
import math

from pydrake.math import RigidTransform
from pydrake.multibody.math import SpatialVelocity

from corobot_drake import commands, limits
from corobot_drake.config import scenario as sc
from corobot_drake.config.placement import Problem, overlap_problems
from corobot_drake.config.poses import ground_pose
from corobot_drake.readings import CommandResult
from corobot_drake.systems.drive import CommandRecord

_log = logging.getLogger("corobot_drake.simulation")
"""The Simulation's logger (a blocked SetPose is logged there, as before)."""


def _one_thread(method):
    """`method` (of a Simulation or a Robot) run holding its Simulation's lock; RuntimeError
    at once if another thread holds it. A Drake Context is not thread-safe: two threads
    advancing one simulation corrupt its time and state."""

    @functools.wraps(method)
    def guarded(self, *args, **kwargs):
        lock = getattr(self, "_sim", self)._thread_lock
        if not lock.acquire(blocking=False):
            raise RuntimeError(f"{method.__name__}: another thread is advancing or commanding "
                               "this Simulation; use it from one thread at a time")
        try:
            return method(self, *args, **kwargs)
        finally:
            lock.release()

    return guarded


class CommandHandle:
    """A command issued without waiting: poll `status()` / `done()` while the simulation
    advances (and other commands are issued), or `wait()` for it to end."""

    def __init__(self, robot, seq: int):
        """`robot`: the `simulation.Robot` that issued command `seq`."""
        self.robot, self.seq = robot, seq

    def __repr__(self) -> str:
        """E.g. `<CommandHandle corobot seq 3: DriveDistance succeeded, t = 0.500 to 2.310 s>`."""
        head = f"<CommandHandle {self.robot.name} seq {self.seq}"
        try:
            r = self.result()
        except KeyError:  # the command log keeps the newest records only
            return f"{head}: no longer in the command log>"
        return f"{head}: {r.describe()}>"

    def result(self) -> CommandResult:
        """How the command has gone so far (`Robot.command_result`; KeyError once the
        command log has dropped it)."""
        return self.robot.command_result(self.seq)

    def status(self) -> str:
        """`running`, `succeeded` or `failed` (the reason: `result().reason`)."""
        return self.result().status

    def done(self) -> bool:
        """Whether the command has ended (succeeded or failed)."""
        return self.result().end_time is not None

    def wait(self, timeout: float | None = 300.0) -> CommandResult:
        """Advances the simulation (one control period at a time) until the command ends;
        TimeoutError after `timeout` simulated seconds (None: no limit)."""
        timeout = _check_timeout(timeout)
        sim = self.robot._sim
        period = self.robot._parts.motion.drive_period
        end = math.inf if timeout is None else sim.time + timeout
        while not self.done():
            if sim.time >= end:
                raise TimeoutError(f"{self.result().command} (seq {self.seq}) still running "
                                   f"after {timeout} s")
            sim.advance(period)
        return self.result()


def _check_timeout(timeout: float | None) -> float | None:
    """A command's wait limit: None (no limit) or a number of simulated s > 0."""
    if timeout is None:
        return None
    return limits.number("timeout", timeout, 0.0, low_open=True, finite=False)


class RobotCommands:
    """Commands: issue, wait, teleport, and the command log."""

    @_one_thread
    def issue(self, command) -> int:
        """Issues a scenario command dataclass now; returns its sequence number. ValueError
        (naming the allowed range) for a command the API does not take or an argument out of
        its range (`commands.check`)."""
        return self._issue_checked(commands.check(command))

    def _issue_checked(self, command) -> int:
        source = self._parts.command_source
        seq = source.Issue(source.GetMyMutableContextFromRoot(self._sim.context), command)
        self._apply_teleport()  # a SetPose takes the robot there now
        return seq

    @_one_thread
    def command(self, method: str, *args, **kwargs):
        """Issues the command `method` names (`commands.COMMANDS`: `set_power`, ...) with its
        arguments, as the methods below do: returns its sequence number, or a `CommandHandle`
        for a command that completes (without waiting). ValueError for an unknown command or
        an argument out of its range, TypeError for arguments it does not take."""
        spec = commands.by_method(method)
        seq = self._issue_checked(commands.make(method, *args, **kwargs))  # make checks it
        return CommandHandle(self, seq) if spec.completing else seq

    def set_power(self, left: float, right: float) -> int:
        """Power per side in [-1, 1]: axle speed = power x MotorTorqueScaling."""
        return self.command("set_power", left, right)

    def set_speed(self, left: float, right: float) -> int:
        """Rim speed per side, m/s, in [-5, 5] (`limits.SIDE_SPEED`; the drive clamps the axle
        speed to its max axle speed)."""
        return self.command("set_speed", left, right)

    def set_velocity(self, linear: float, angular: float) -> int:
        """Chassis velocity, ROS `cmd_vel` style: `linear` m/s forward, `angular` rad/s
        (positive: left), through the skid-steer kinematics (`commands.SetVelocity`); in
        [-5, 5] m/s and [-50, 50] rad/s (`limits`; ValueError otherwise)."""
        return self.command("set_velocity", linear, angular)

    def all_stop(self) -> int:
        """Commands both sides to zero speed (the drive slews down to it); a running
        drive_distance, rotate_degrees or set_pose fails, `superseded` (as with any new
        command). Returns its sequence number."""
        return self.command("all_stop")

    def enable(self, enabled: bool = True) -> int:
        """Enables (True) or disables (False) the drive (disabled: the wheels held at zero
        speed, motion commands ignored); a running drive_distance, rotate_degrees or set_pose
        fails, `disabled` (`superseded` when enabling). Returns its sequence number."""
        return self.command("enable", enabled)

    def drive_distance_async(self, distance: float, power: float = 0.5) -> CommandHandle:
        """Starts driving straight |distance| m (distance in [-100, 100]; negative: backwards)
        at `power` in (0, 1]."""
        return self.command("drive_distance", distance, power)

    def drive_distance(self, distance: float, power: float = 0.5,
                       timeout: float | None = 300.0) -> CommandResult:
        """Drives straight |distance| m (negative: backwards) at `power`, advancing the
        simulation until the command ends; returns how it ended. `timeout`: simulated s > 0,
        or None for no limit."""
        _check_timeout(timeout)
        return self.drive_distance_async(distance, power).wait(timeout)

    def rotate_degrees_async(self, degrees: float, power: float = 0.5) -> CommandHandle:
        """Starts turning in place by `degrees` in [-3600, 3600] (positive: counter-clockwise,
        left) at `power` in (0, 1]."""
        return self.command("rotate_degrees", degrees, power)

    def rotate_degrees(self, degrees: float, power: float = 0.5,
                       timeout: float | None = 300.0) -> CommandResult:
        """Turns in place by `degrees` (positive: left), advancing the simulation until the
        command ends; returns how it ended."""
        _check_timeout(timeout)
        return self.rotate_degrees_async(degrees, power).wait(timeout)

    @_one_thread
    def set_pose(self, x: float, y: float, yaw_deg: float = 0.0) -> CommandHandle:
        """Teleports the robot now to (x, y) m facing `yaw_deg`, on the ground, at rest, the
        wheels stopped; a running command fails as superseded. The returned handle ends
        (succeeded) once the robot has settled there (`motion.POSE_SETTLE_TIME`), or at once
        failed, reason `blocked`, if the robot there would be inside another body
        (`obstacle_at`, logged in the loader's words): then it stays where it was (its drive
        stopping). x, y in [-10000, 10000] m, yaw_deg in [-3600, 3600] (ValueError
        otherwise)."""
        return self.command("set_pose", x, y, yaw_deg)

    def _apply_teleport(self) -> bool:
        """Applies a pending SetPose to the plant (and stops the drive); True if there was one."""
        parts, root = self._parts, self._sim.context
        source = parts.command_source
        request = source.TakeTeleport(source.GetMyMutableContextFromRoot(root))
        if request is None:
            return False
        pose = request.command
        X_WB = ground_pose(pose.x, pose.y, pose.yaw_deg).GetDeterministicValue()
        problem = self.obstacle_at(X_WB)
        if problem is not None:
            _log.warning("SetPose %s blocked: %s", request.seq, problem.message)
            source.Fail(source.GetMyMutableContextFromRoot(root), request.seq, "blocked")
            return True
        plant = self._sim.station.plant
        plant_context = plant.GetMyMutableContextFromRoot(root)
        plant.SetFreeBodyPose(plant_context, parts.chassis, X_WB)
        plant.SetFreeBodySpatialVelocity(plant_context, parts.chassis, SpatialVelocity.Zero())
        for joint in parts.wheel_joints:
            joint.set_angular_rate(plant_context, 0.0)
        controller = parts.drive_controller
        controller.Halt(controller.GetMyMutableContextFromRoot(root))
        odometry = self._sim._dead_reckoning(self.name)  # reset there, as a driver's would be
        odometry.Teleport(odometry.GetMyMutableContextFromRoot(root), pose.x, pose.y,
                          math.radians(pose.yaw_deg))
        return True

    def obstacle_at(self, X_WB: RigidTransform) -> Problem | None:
        """What the robot would overlap with its chassis at `X_WB`, by the loader's check of
        a start pose (`placement.overlap_problems`: more than `OVERLAP_TOLERANCE`; what loads,
        SetPose accepts), in its words: the `Problem` (`.message`; `.obstacle.name`: `world
        body 'giant_box'`, a model's body, another robot), or None if the pose is clear. The
        ground (any half-space) does not count: a SetPose stands the robot on it. The Context
        is left as it was (the pose is tried, then the plant's positions are put back
        exactly)."""
        plant = self._sim.station.plant
        plant_context = plant.GetMyMutableContextFromRoot(self._sim.context)
        q = plant.GetPositions(plant_context)
        try:
            plant.SetFreeBodyPose(plant_context, self._parts.chassis, X_WB)
            query = plant.get_geometry_query_input_port().Eval(plant_context)
            me = self._sim._placement_owners()[1][self.name]
            problems = overlap_problems(query.ComputePointPairPenetration(),
                                        self._sim._placement_owners()[0].get)
            return next((p for p in problems
                         if p.subject == me and p.obstacle.kind != "ground"), None)
        finally:
            plant.SetPositions(plant_context, q)

    def continuation_commands(self) -> list:
        """Commands that carry on from now: the enable level, the running command (a
        DriveDistance/RotateDegrees carried on from where it is, the last
        SetPower/SetSpeed/SetVelocity, or an AllStop while the drive slews down to 0, also
        one not yet taken), then the script's unissued rest (after what is left of a running
        Wait, or a Wait of 0 s when it is due: it then starts at the update the saved run's
        would have)."""
        root = self._sim.context
        source, motion = self._parts.command_source, self._parts.motion
        state = source.current_state(source.GetMyContextFromRoot(root))
        commands = [] if state.request.enabled else [sc.Enable(False)]
        remaining = motion.remaining_command(motion.GetMyContextFromRoot(root))
        if remaining is not None:
            commands.append(remaining)
        elif isinstance(state.request.command, sc.SetPower | sc.SetSpeed | sc.SetVelocity):
            commands.append(state.request.command)
        else:
            target, commanded = self._parts.drive_controller.speeds(root)
            stopping = isinstance(state.request.command, sc.AllStop)  # maybe not yet taken
            if (stopping or not any(target)) and any(commanded):
                # Slewing down to 0 (an AllStop, an ended command): the reloaded drive starts
                # from the commanded speeds and must stop, not hold them.
                commands.append(sc.AllStop())
        script = source.script(source.GetMyContextFromRoot(root))
        if state.next_script_index < len(script):
            if state.script_blocked_until > self._sim.time:
                commands.append(sc.Wait(state.script_blocked_until - self._sim.time))
            elif remaining is None:
                # Due now: the source issues it at its next update (also one at this very
                # instant, not yet run), not with what is carried on at the start.
                commands.append(sc.Wait(0.0))
            commands += script[state.next_script_index:]
        return commands

    def command_result(self, seq: int) -> CommandResult:
        """How the command with sequence number `seq` has gone so far (its command-log
        record); KeyError if this robot issued no such command."""
        source = self._parts.command_source
        r = source.record(source.GetMyContextFromRoot(self._sim.context), seq)
        if r is None:
            raise KeyError(f"robot {self.name!r} issued no command {seq}")
        return CommandResult(r.seq, r.command, r.status, r.reason, r.start_time, r.end_time)

    def command_log(self) -> list[CommandRecord]:
        """Every command's record, oldest first (the newest `drive.COMMAND_LOG_CAPACITY`)."""
        source = self._parts.command_source
        return list(source.current_state(source.GetMyContextFromRoot(self._sim.context)).log)

    def last_command(self) -> CommandRecord | None:
        """The newest record of the command log (None before any), without copying the log."""
        source = self._parts.command_source
        log = source.current_state(source.GetMyContextFromRoot(self._sim.context)).log
        return log[-1] if log else None
