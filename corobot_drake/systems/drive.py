"""The skid-steer drive: the command source (script + API inbox) and the drive controller.

Commands are the scenario's command dataclasses (`SetPower`, `SetSpeed`, ...). A `DriveRequest`
pairs one with a sequence number; a system acts on a request when it sees a new number, so a
request is a message, not a level, and every system's memory of it lives in the Context.
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.common.containers import namedview
from pydrake.common.value import Value
from pydrake.systems.framework import EventStatus, LeafSystem

from corobot_drake.config.scenario import (
    COMPLETING_COMMANDS,
    AllStop,
    Drive,
    Enable,
    SetPose,
    SetPower,
    SetSpeed,
    SetVelocity,
    Wait,
)
from corobot_drake.robots import corobot
from corobot_drake.systems.shared_state import SharedState


@dc.dataclass(frozen=True)
class DriveRequest(SharedState):
    """A command (a scenario command dataclass) stamped with its sequence number and time.

    The command is never mutated after it is issued."""

    seq: int = 0
    """Increases by one with every request; 0 means "nothing requested yet"."""
    command: object = None
    time: float = 0.0
    """Simulation time (s) at which it was issued."""
    enabled: bool = True
    """The drive's enable level (the last `Enable` issued) at this request: a level, so an
    Enable issued in the same instant as the next command is never lost."""
    immediate: bool = False
    """The drive sets the axle speeds to the command's at once, without the slew limit (the
    seed profile's stop: the book sets the axle speed to 0 when the goal is reached)."""


@dc.dataclass(frozen=True)
class CommandStatus(SharedState):
    """How a completing command (DriveDistance, RotateDegrees, SetPose) ended, reported by
    `motion.MotionCommands`: its request's seq, status and reason, end time (s)."""

    seq: int = 0
    status: str = "running"
    """running, succeeded or failed."""
    reason: str = ""
    """Why it failed: superseded, disabled, stalled (or, for a SetPose, not_applied or
    blocked)."""
    time: float = 0.0


@dc.dataclass(frozen=True)
class CommandRecord(SharedState):
    """One command's life, for the run summary. Times in s; end_time None while running."""

    seq: int
    command: str
    start_time: float
    end_time: float | None = None
    status: str = "running"
    """running, succeeded or failed."""
    reason: str = ""


WAIT_SLACK = 1e-12
"""s: a Wait has elapsed at an update this close before its end (the updates' times are
multiples of the period, a Wait's end a sum of seconds: one instant may differ in the last
bits)."""
COMMAND_LOG_CAPACITY = 10_000
"""Records the command log keeps (the newest; ~220 bytes each, so ~2.2 MB at most): a day of
driving from the dashboard must not fill the memory. Older records are dropped as new ones
come (a scripted run longer than this has its log's indices shifted from the script's)."""


def _bounded(log: list) -> tuple:
    """The newest `COMMAND_LOG_CAPACITY` records (running ones are always among them: only
    the latest command, and a completing one it superseded ends at once, run)."""
    return tuple(log[-COMMAND_LOG_CAPACITY:])


@dc.dataclass(frozen=True)
class CommandSourceState(SharedState):
    """The command source's whole memory (held as abstract state in the Context)."""

    request: DriveRequest = DriveRequest()
    next_script_index: int = 0
    script_blocked_until: float = 0.0
    """Simulation time before which the script issues nothing (a running Wait)."""
    log: tuple[CommandRecord, ...] = ()
    script_waits_for: int = 0
    """seq of the scripted completing command the script waits for (0: none)."""
    teleport: DriveRequest | None = None
    """A SetPose not yet applied to the plant (the Simulation applies it, `TakeTeleport`)."""
    quiet_until: float = 0.0
    """Simulation time before which an update changes nothing unless the status it reads is a
    new one (every level command ended, the script held by a Wait or a completing command):
    set by the update that made this state, 0 by anything else that changes the state."""
    status_seen: object = None
    """The CommandStatus that update read (already recorded)."""


def command_name(command) -> str:
    """The command's scenario tag, e.g. "SetPower"."""
    return type(command).__name__


def check_finite(command) -> None:
    """Rejects a command carrying a NaN or infinite number (ValueError naming the field)."""
    for field in dc.fields(command):
        value = getattr(command, field.name)
        if isinstance(value, float) and not math.isfinite(value):
            raise ValueError(f"{command_name(command)}.{field.name} must be a finite number, "
                             f"got {value}")


class CommandSource(LeafSystem):
    """Issues a robot's drive requests: its scenario script in order, and API commands.

    .. pydrake_system::

        name: CommandSource
        input_ports:
        - command_status
        output_ports:
        - request
        - command_log

    Output `request` (DriveRequest, abstract); output `command_log` (tuple of CommandRecord,
    abstract: every command so far, with the latest reported status recorded). Input
    `command_status` (CommandStatus, abstract, from `motion.MotionCommands`; may be left
    unconnected, then no completing command is ever reported ended): how completing commands
    end, recorded in the log.
    Abstract state `CommandSourceState`. At initialization it issues the script's commands
    up to the first Wait or completing command; then every `period` s it records that status
    and issues the next command; a `Wait` holds the script for its duration and a completing
    command holds it until it ends. `Issue()` writes a command into the Context directly
    (what the Python API, teleop and the server call between steps). A new command ends a
    running completing one as failed: `superseded`, or `disabled` when the new command is
    `Enable(false)`; a level command (SetPower, SetSpeed, AllStop, Enable) ends at the first
    update after it is issued, when the drive takes it (`_with_ended`), and a Wait when it has
    elapsed. An update that makes a change also notes until when the next ones can find
    nothing to do but for a new status (`quiet_until`): those read the status and return.
    """

    def __init__(self, script: list, period: float):
        super().__init__()
        for command in script:
            check_finite(command)
        # A parameter, not a constructor constant: a reset Context may run another script.
        self._script_index = self.DeclareAbstractParameter(Value(tuple(script)))
        self._state_index = self.DeclareAbstractState(Value(CommandSourceState()))
        self.DeclareAbstractOutputPort(
            "request", lambda: Value(DriveRequest()), self._calc_request,
            {self.abstract_state_ticket(self._state_index)})
        self._status_port = self.DeclareAbstractInputPort("command_status",
                                                          Value(CommandStatus()))
        self.DeclareAbstractOutputPort(
            "command_log", lambda: Value(()),
            lambda context, output: output.set_value(self.current_state(context).log),
            {self.abstract_state_ticket(self._state_index), self.all_input_ports_ticket()})
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._update)
        # The script's first commands are issued when the simulation starts, not at the
        # first period: a saved scene's script (what was running, what was left of a Wait)
        # then carries on at the very times the saved run would have.
        self.DeclareInitializationUnrestrictedUpdateEvent(self._initialize)

    def script(self, context) -> tuple:
        """The script this Context runs (the scenario's commands, in order)."""
        return context.get_abstract_parameter(self._script_index).get_value()

    def SetScript(self, context, script) -> None:
        """Runs `script` from the start of this Context (before the simulation starts)."""
        for command in script:
            check_finite(command)
        context.get_mutable_abstract_parameter(self._script_index).set_value(tuple(script))

    def _calc_request(self, context, output):
        output.set_value(self.get_state(context).request)

    def get_state(self, context) -> CommandSourceState:
        return context.get_abstract_state(self._state_index).get_value()

    def _set_state(self, state_or_context, value: CommandSourceState) -> None:
        state_or_context.get_mutable_abstract_state(self._state_index).set_value(value)

    @staticmethod
    def _with_command(state: CommandSourceState, command, time: float) -> CommandSourceState:
        check_finite(command)
        log = list(state.log)
        # The last issued command (a script's Wait records, seq 0, may follow it) ends now.
        last_index = next((i for i in range(len(log) - 1, -1, -1) if log[i].seq != 0), None)
        if last_index is not None and log[last_index].end_time is None:
            last = log[last_index]
            if last.command in _COMPLETING_NAMES:
                reason = ("disabled" if isinstance(command, Enable) and not command.enabled
                          else "superseded")
                log[last_index] = last.replace(end_time=time, status="failed",
                                               reason=reason)
            else:
                log[last_index] = last.replace(end_time=time, status="succeeded")
        seq = state.request.seq + 1
        log.append(CommandRecord(seq=seq, command=command_name(command), start_time=time))
        enabled = command.enabled if isinstance(command, Enable) else state.request.enabled
        request = DriveRequest(seq, command, time, enabled)
        teleport = request if isinstance(command, SetPose) else state.teleport
        return state.replace(request=request, log=_bounded(log), teleport=teleport,
                             quiet_until=0.0)

    @staticmethod
    def _with_status(state: CommandSourceState, status: CommandStatus) -> CommandSourceState:
        """Records a completing command's end (if its record is still running)."""
        if status.status == "running" or status.seq == 0:
            return state
        for i in range(len(state.log) - 1, -1, -1):
            record = state.log[i]
            if record.seq == status.seq:
                if record.end_time is not None:
                    return state
                log = list(state.log)
                log[i] = record.replace(end_time=status.time, status=status.status,
                                        reason=status.reason)
                return state.replace(log=tuple(log), quiet_until=0.0)
        return state

    @staticmethod
    def _with_ended(state: CommandSourceState, now: float) -> CommandSourceState:
        """Ends, at this control tick, the commands that end without a reported status: a
        level command (SetPower, SetSpeed, AllStop, Enable) issued before the tick is handed
        to the drive now, so it has `succeeded` (SetPower and SetSpeed `failed`, `disabled`,
        on a disabled drive, which ignores them); a script's Wait succeeds once it elapsed."""
        log = None
        # Only the last issued command and the last Wait can be running: look at the tail.
        for i in range(len(state.log) - 1, max(-1, len(state.log) - 4), -1):
            r = state.log[i]
            if r.end_time is not None or r.command in _COMPLETING_NAMES:
                continue
            if r.seq == 0:  # a Wait: the script is held until script_blocked_until
                if now < state.script_blocked_until - WAIT_SLACK:
                    continue
                ended = r.replace(end_time=state.script_blocked_until, status="succeeded")
            elif r.command in _MOTION_LEVEL_NAMES and not state.request.enabled:
                ended = r.replace(end_time=now, status="failed", reason="disabled")
            else:
                ended = r.replace(end_time=now, status="succeeded")
            log = log or list(state.log)
            log[i] = ended
        return state if log is None else state.replace(log=tuple(log))

    def _status(self, context) -> CommandStatus:
        if not self._status_port.HasValue(context):
            return CommandStatus()
        return self._status_port.Eval(context)

    def current_state(self, context) -> CommandSourceState:
        """The state with the latest reported command status recorded."""
        return self._with_status(self.get_state(context), self._status(context))

    def record(self, context, seq: int) -> CommandRecord | None:
        """The log record of the command with this seq, as of now."""
        for record in reversed(self.current_state(context).log):
            if record.seq == seq:
                return record
        return None

    def Issue(self, context, command) -> int:
        """Issues `command` now (context time); returns its sequence number."""
        state = self._with_command(self.current_state(context), command, context.get_time())
        self._set_state(context, state)
        return state.request.seq

    def Fail(self, context, seq: int, reason: str) -> None:
        """Ends command `seq` now as failed for `reason`, if it still runs: how the Simulation
        reports a SetPose it could not apply (`blocked`). `context` is this system's."""
        status = CommandStatus(seq, "failed", reason, context.get_time())
        self._set_state(context, self._with_status(self.current_state(context), status))

    def TakeTeleport(self, context) -> DriveRequest | None:
        """The pending SetPose request, cleared (the caller applies it to the plant)."""
        state = self.get_state(context)
        if state.teleport is None:
            return None
        self._set_state(context, state.replace(teleport=None))
        return state.teleport

    def has_teleport(self, context) -> bool:
        return self.get_state(context).teleport is not None

    @staticmethod
    def _script_waiting(state: CommandSourceState) -> bool:
        """True while the scripted completing command the script waits for runs."""
        if not state.script_waits_for:
            return False
        record = next((r for r in reversed(state.log) if r.seq == state.script_waits_for), None)
        return record is not None and record.end_time is None  # None: dropped, long over

    def _update(self, context, state):
        original = self.get_state(context)
        now = context.get_time()
        status = self._status(context)
        if now < original.quiet_until and (status is original.status_seen
                                           or status.seq == 0 or status.status == "running"):
            return EventStatus.DidNothing()  # what the updates below would find (most steps)
        current = self._with_ended(self._with_status(original, status), now)
        script = self.script(context)
        current = self._next_script_command(current, script, now)
        if current is original:
            # Drake then skips copying the state back (and what reads the request stays
            # valid), when no other system's update at this step changed anything either.
            return EventStatus.DidNothing()
        current = current.replace(quiet_until=self._quiet_until(current, script, now),
                                  status_seen=status)
        self._set_state(state, current)
        return EventStatus.Succeeded()

    def _quiet_until(self, current: CommandSourceState, script: tuple, now: float) -> float:
        """The time until which updates after this one (at `now`) find nothing to do, as long
        as no new status comes: before it neither `_with_ended` nor `_next_script_command`
        changes `current`. Only a Wait's end (`script_blocked_until`) is a time they wait
        for, so each is asked whether it would change anything ever (at infinity) or at once
        (at minus infinity)."""
        if self._with_ended(current, -math.inf) is not current:
            return 0.0  # a level command issued now ends at the next update
        until = math.inf
        wait_end = current.script_blocked_until - WAIT_SLACK
        if self._with_ended(current, math.inf) is not current:
            until = wait_end  # a Wait's record ends at its end
        if self._next_script_command(current, script, math.inf) is not current:
            until = min(until, wait_end if current.script_blocked_until > now else 0.0)
        return until

    def _initialize(self, context, state):
        """The script's commands up to its first Wait (even of 0 s: what follows it is
        issued at an update, as a saved scene's rest was going to be) or completing command,
        at once."""
        original = current = self.get_state(context)
        script, now = self.script(context), context.get_time()
        while True:
            issued = self._next_script_command(current, script, now)
            if issued is current:
                break
            # Handed to the drive at this instant, as at an update (and so the tail that
            # `_with_ended` looks at never holds more than the last few running commands).
            current = self._with_ended(issued, now)
            if isinstance(script[issued.next_script_index - 1], Wait):
                break
        quiet_until = self._quiet_until(current, script, now)
        if current is not original or original.quiet_until != quiet_until:
            self._set_state(state, current.replace(quiet_until=quiet_until, status_seen=None))

    def _next_script_command(self, current: CommandSourceState, script: tuple,
                             now: float) -> CommandSourceState:
        """The state after issuing the script's next command, if it is due now."""
        if (current.next_script_index >= len(script) or now < current.script_blocked_until
                or self._script_waiting(current)):
            return current
        command = script[current.next_script_index]
        current = current.replace(next_script_index=current.next_script_index + 1)
        if isinstance(command, Wait):
            log = current.log
            if command.seconds > 0:  # a 0 s Wait only defers the rest to an update: no record
                log = _bounded([*log, CommandRecord(seq=0, command="Wait", start_time=now)])
            return current.replace(script_blocked_until=now + command.seconds, log=log)
        current = self._with_command(current, command, now)
        completing = isinstance(command, COMPLETING_COMMANDS)
        return current.replace(script_waits_for=current.request.seq if completing else 0)


_COMPLETING_NAMES = tuple(c.__name__ for c in COMPLETING_COMMANDS)
_MOTION_LEVEL_NAMES = (SetPower.__name__, SetSpeed.__name__)
"""Level commands that a disabled drive ignores (they fail `disabled`)."""


def velocity_track_width(drive: Drive) -> float:
    """m: the track that turns a yaw rate into rim speeds (`SetVelocity`): the drive's
    calibrated `effective_track_width` (`tools/calibrate_odometry.py`), so that a skid-steer
    robot, whose wheels slip sideways in a turn, turns at the commanded rate; the geometric
    track by default."""
    return drive.effective_track_width


def skid_steer_rim_speeds(linear: float, angular: float, track: float) -> tuple[float, float]:
    """(left, right) rim speeds, m/s, for a chassis `linear` speed (m/s, forward) and yaw rate
    `angular` (rad/s, positive left) on a drive of this track (m): v -+ w track / 2."""
    return linear - 0.5 * angular * track, linear + 0.5 * angular * track


DriveStatus = namedview("DriveStatus", (
    "enabled", "power_left", "power_right", "target_left", "target_right"))
"""The drive controller's `drive_status` output, read by name (``DriveStatus(vector)``):

- ``enabled``: 1 when the drive is enabled, else 0;
- ``power_left``, ``power_right``: the commanded power per side, in [-1, 1];
- ``target_left``, ``target_right``: the axle speed per side the drive is slewing towards,
  rad/s (before the slew limit; the rear axles follow the front).
"""

_TARGETS = slice(3, 5)
"""Where the targets sit in a `DriveStatus` vector."""
_TARGET_LEFT, _TARGET_RIGHT = range(_TARGETS.start, _TARGETS.stop)
assert DriveStatus.get_fields()[_TARGETS] == ("target_left", "target_right")
assert DriveStatus.get_fields()[1:] == ("power_left", "power_right", *DriveStatus.get_fields()[
    _TARGETS])  # the order of `DriveController.target_for`'s tuple


HOLD_SPEED = 1e-3
"""rad/s: a wheel turning slower than this is at rest, and can be held (the tyres' mesh rolls a
resting wheel at up to 3e-5 rad/s; a braking wheel turns far faster)."""
HOLD_SLACK = 1e-4
"""rad: a held wheel pushed further than this from its hold angle is held where it is now
instead (6 um at the rim: the most a hold ever pulls a wheel back)."""


class Tracking:
    """What the drive's hold knows (`DriveController`'s mode state, a float)."""

    TRACKING = 0.0
    """The hold angles are up to date: held wheels' hold angles, the others' angles at the
    last update."""
    UNTRACKED = 1.0
    """Both sides were commanded to turn at the last update (or the drive has no hold,
    `hold_gain` 0): no wheel held, hold angles not updated."""
    IDLE = 2.0
    """UNTRACKED, and the axles at their targets: nothing changes until a new request."""


def _clip(value: float, limit: float) -> float:
    """`value` within [-limit, limit], as a float."""
    return float(min(max(value, -limit), limit))


def _slew(axle: float, target: float, step: float) -> float:
    """`axle` moved towards `target` by at most `step` (rad/s)."""
    return axle + min(step, max(-step, target - axle))


class DriveController(LeafSystem):
    """Turns drive requests into the plant's desired wheel state (velocity servo).

    .. pydrake_system::

        name: DriveController
        input_ports:
        - request
        - wheel_state
        output_ports:
        - desired_state
        - axle_speed_command
        - drive_status
        - axle_speed

    Input `request` (DriveRequest, abstract); input `wheel_state` [q, v] of the robot's n
    wheels' axles in its wheel order (`RobotSpec.wheels`), rad, rad/s.
    Output `desired_state` [q_d, v_d] for the plant's desired-state input (actuator order;
    q_d = 0: the servo has kp = 0 and only v_d matters). v_d is the slewed axle speed of the
    wheel's side, and for a wheel at rest on a side commanded to 0 the hold's correction.
    Output `axle_speed_command` [left, right] rad/s after the slew limit; every wheel of a
    side follows it.
    Output `drive_status` (5, `DriveStatus`: read it by name).
    Output `axle_speed` (n) measured, rad/s, wheel order.
    Discrete state, updated every `drive.control_period` s: the seq of the last request acted
    on and the hold's `Tracking`, the `DriveStatus`, the slewed axle speeds (and the desired
    state made from them) and the wheels' hold angles.
    A new request sets the enable level and (when enabled) the motion target; disabled,
    everything is held at zero; the axle speeds then move towards the targets by at most
    `drive.slew_rate * drive.control_period`, or jump to them for a request marked
    `immediate` (the seed profile's stop).

    The hold: a wheel whose side is commanded to 0, turning slower than `HOLD_SPEED` and within
    `HOLD_SLACK` of its hold angle keeps that angle (any other wheel's hold angle is its angle
    now), and its v_d pulls it back there at `drive.hold_gain` x the angle error (at most
    HOLD_SPEED / 2, so it never looks like motion). The servo alone only damps: without the
    hold a robot at rest rolls, at up to ~2 um/s, into the nearest stable facet of its tyres'
    hydroelastic mesh, up to ~2 mm (docs/tuning.md, "At rest").

    While both sides are commanded to turn no wheel can be held, so the hold angles are not
    tracked (`Tracking.UNTRACKED`: a wheel on a side that stops is then held where it is at
    that update), and once the axles are at their targets an update reads only the request's
    seq until a new one comes (`Tracking.IDLE`): a steady drive costs no per-step work.
    """

    def __init__(self, drive: Drive, sides: tuple[int, ...] = (1, -1, 1, -1),
                 wheel_radius: float = corobot.wheels("radius")):
        """`sides`: each wheel's side, +1 left or -1 right, in wheel order (the Corobot's by
        default: `RobotSpec.sides`); `wheel_radius` (m) turns rim speeds to axle speeds."""
        super().__init__()
        self._drive = drive
        self._left = tuple(s > 0 for s in sides)
        n = self._n = len(sides)
        self._radius = wheel_radius
        self._zeros = (0.0,) * n
        self._step = drive.slew_rate * drive.control_period
        """rad/s: the most the axle speed moves per update."""
        self._request_port = self.DeclareAbstractInputPort("request", Value(DriveRequest()))
        self._wheel_state_port = self.DeclareVectorInputPort("wheel_state", 2 * n)
        # Each output is a state group of its own, so the ports are Drake's state output
        # ports (no Python call when the plant reads its desired state every step).
        enabled = DriveStatus.Zero()
        enabled.enabled = 1.0
        self._mode = self.DeclareDiscreteState(2)  # [seq, Tracking]
        self._status = self.DeclareDiscreteState(enabled[:])
        self._axle = self.DeclareDiscreteState(2)
        self._desired = self.DeclareDiscreteState(2 * n)
        self._hold_angle = self.DeclareDiscreteState(n)
        self.DeclarePeriodicDiscreteUpdateEvent(drive.control_period, 0.0, self._update)
        self.DeclareStateOutputPort("desired_state", self._desired)
        self.DeclareStateOutputPort("axle_speed_command", self._axle)
        self.DeclareStateOutputPort("drive_status", self._status)
        self.DeclareVectorOutputPort(
            "axle_speed", n, lambda c, o: o.SetFromVector(self._wheel_state_port.Eval(c)[n:]),
            {self.input_port_ticket(self._wheel_state_port.get_index())})

    def target_for(self, command, enabled: bool) -> tuple[float, float, float, float] | None:
        """(power_l, power_r, axle_l, axle_r) a motion command asks for; None if not motion."""
        d = self._drive
        # min/max, not np.clip: the same numbers at a sixtieth of the cost, and a closed-loop
        # command sends a new request every control period.
        if isinstance(command, SetPower):
            pl, pr = (_clip(p, 1.0) for p in (command.left, command.right))
            return pl, pr, pl * d.motor_torque_scaling, pr * d.motor_torque_scaling
        if isinstance(command, SetSpeed | SetVelocity):
            if isinstance(command, SetSpeed):
                al, ar = (_clip(v / self._radius, d.max_axle_speed)
                          for v in (command.left, command.right))
            else:
                al, ar = self._velocity_axle_speeds(command)
            # The power a SetSpeed amounts to; past full power (axle speed above the
            # scaling) it reports 1: power is a fraction of the motor's range.
            pl, pr = (_clip(a / d.motor_torque_scaling, 1.0) for a in (al, ar))
            return pl, pr, al, ar
        if isinstance(command, AllStop):
            return 0.0, 0.0, 0.0, 0.0
        return None

    def _velocity_axle_speeds(self, command: SetVelocity) -> tuple[float, float]:
        """Axle speeds (rad/s) for a SetVelocity: both scaled down together past the max axle
        speed, so the robot keeps the commanded path's curvature at a lower speed."""
        rims = skid_steer_rim_speeds(command.linear, command.angular,
                                     velocity_track_width(self._drive))
        left, right = (v / self._radius for v in rims)
        scale = min(1.0, self._drive.max_axle_speed / max(abs(left), abs(right), 1e-300))
        return left * scale, right * scale

    def _update(self, context, discrete_state):
        # Only the groups that change are written (the others keep their copied values).
        # Every read is a BasicVector's element and every write a numpy array: on vectors of
        # two to eight numbers pydrake's numpy views, input-port copies and list conversions
        # cost more than the update's arithmetic, and this runs every control period.
        request = self._request_port.Eval(context)
        mode = context.get_discrete_state(self._mode)
        seq, tracking = mode[0], mode[1]
        if request.seq == seq and tracking == Tracking.IDLE:
            return EventStatus.DidNothing()
        if request.seq != seq:
            target_left, target_right, jump = self._take(context, discrete_state, request)
        else:
            status = context.get_discrete_state(self._status)
            target_left, target_right, jump = status[_TARGET_LEFT], status[_TARGET_RIGHT], False
        axle = context.get_discrete_state(self._axle)
        left, right = axle[0], axle[1]
        if jump:
            new_left, new_right = target_left, target_right
        else:
            new_left = _slew(left, target_left, self._step)
            new_right = _slew(right, target_right, self._step)
        if self._holds_none(new_left, new_right):  # the desired state is the axles' alone
            correction = None
            new_tracking = (Tracking.IDLE if (new_left, new_right) == (target_left, target_right)
                            else Tracking.UNTRACKED)
        else:
            correction = self._hold(context, discrete_state, new_left, new_right,
                                    tracking != Tracking.TRACKING)
            new_tracking = Tracking.TRACKING
        if request.seq != seq or new_tracking != tracking:
            discrete_state.set_value(self._mode, np.array([float(request.seq), new_tracking]))
        if (new_left, new_right) != (left, right) or correction is not None:
            self._set_axle(discrete_state, new_left, new_right, correction)

    def _holds_none(self, left: float, right: float) -> bool:
        """Whether no wheel can be held at these slewed axle speeds (rad/s): both sides turn,
        or the drive has no hold."""
        return (left != 0.0 and right != 0.0) or self._drive.hold_gain == 0.0

    def _take(self, context, discrete_state, request) -> tuple[float, float, bool]:
        """Acts on a new request: writes its seq and the `DriveStatus` it makes; returns the
        axle speed targets (rad/s) and whether the axles jump to them (a request marked
        `immediate`, or a disabled drive, held at zero at once). The status as a plain list:
        a closed-loop command sends a request every period."""
        if not request.enabled:
            discrete_state.set_value(self._status, np.zeros(len(DriveStatus.get_fields())))
            return 0.0, 0.0, True
        target = self.target_for(request.command, True)
        if target is None:  # not motion (an Enable): the powers and targets stay
            status = context.get_discrete_state(self._status).get_value().tolist()
            target, jump = status[1:], False
        else:
            jump = request.immediate
        discrete_state.set_value(self._status, np.array([1.0, *target]))
        return float(target[2]), float(target[3]), jump

    def _hold(self, context, discrete_state, left: float, right: float, untracked: bool):
        """Updates the hold angles (`untracked`: they were not tracked at the last update, so
        no wheel is held and none is held where it was then); returns the wheels' v_d
        corrections (rad/s, actuator order), or None when there are none now and were none
        before (nothing to write)."""
        gain = self._drive.hold_gain
        # Plain floats: on four numbers numpy's per-call overhead costs more than the sums.
        wheel_state = self._wheel_state_port.EvalBasicVector(context).get_value().tolist()
        n = self._n
        q, v = wheel_state[:n], wheel_state[n:]
        held = (q if untracked
                else context.get_discrete_state(self._hold_angle).get_value().tolist())
        sides = [left if is_left else right for is_left in self._left]
        hold = [h if side == 0.0 and abs(w) < HOLD_SPEED and abs(a - h) <= HOLD_SLACK else a
                for side, w, a, h in zip(sides, v, q, held, strict=True)]
        if untracked or hold != held:
            discrete_state.set_value(self._hold_angle, np.array(hold))
        limit = 0.5 * HOLD_SPEED
        correction = [min(max(gain * (h - a), -limit), limit) for h, a in zip(hold, q, strict=True)]
        if not any(correction):
            desired = context.get_discrete_state(self._desired)
            if all(desired[n + k] == side for k, side in enumerate(sides)):
                return None
        return correction

    def _set_axle(self, state, left: float, right: float, correction=None) -> None:
        """Writes the slewed axle speeds (rad/s) and the desired state made from them (plus
        the hold's v_d `correction`, rad/s per wheel) into `state` (a Context or
        DiscreteValues)."""
        state.set_value(self._axle, np.array([left, right]))
        v_d = [left if is_left else right for is_left in self._left]
        if correction is not None:
            v_d = [v + c for v, c in zip(v_d, correction, strict=True)]
        state.set_value(self._desired, np.array([*self._zeros, *v_d]))

    def speeds(self, root_context) -> tuple[list[float], list[float]]:
        """(targets, commanded): the axle speeds [left, right] (rad/s) the drive slews towards
        now, and where the slew has brought them."""
        context = self.GetMyContextFromRoot(root_context)
        return ([float(v) for v in context.get_discrete_state(self._status).get_value()[
            _TARGETS]], [float(v) for v in context.get_discrete_state(self._axle).get_value()])

    def hold_angles(self, root_context) -> list[float]:
        """rad, per wheel (wheel order): where the hold keeps each wheel
        while it rests (a wheel not held: its angle at the last update; while both sides
        turn, when they are not tracked, its angle now)."""
        context = self.GetMyContextFromRoot(root_context)
        if context.get_discrete_state(self._mode).GetAtIndex(1) != Tracking.TRACKING:
            return self._wheel_state_port.Eval(context)[:self._n].tolist()
        return [float(a) for a in context.get_discrete_state(self._hold_angle).get_value()]

    def SetHoldAngles(self, context, angles) -> None:
        """Sets the hold angles (rad, per wheel): an initial condition (a saved scene; the
        wheels' own angles when none is given), after the axle speeds (`SetAxleSpeeds`): with
        both sides turning they are not tracked, as in the run the scene was saved from.
        `context` is this system's."""
        context.SetDiscreteState(self._hold_angle, np.asarray(angles, dtype=float))
        left, right = context.get_discrete_state(self._axle).get_value()
        self._set_tracking(context, Tracking.UNTRACKED if self._holds_none(left, right)
                           else Tracking.TRACKING)

    def _set_tracking(self, context, tracking: float) -> None:
        seq = context.get_discrete_state(self._mode).GetAtIndex(0)
        context.SetDiscreteState(self._mode, np.array([seq, tracking]))

    def Halt(self, context) -> None:
        """Stops the wheels at once (powers, targets and slewed axle speeds to 0): what a
        teleport does, so the robot lands at rest. `context` is this system's."""
        self.SetAxleSpeeds(context, 0.0, 0.0)

    def SetAxleSpeeds(self, context, left: float, right: float) -> None:
        """Sets the commanded (slewed) axle speeds and their targets, rad/s, and the powers
        they amount to: an initial condition (a saved scene). `context` is this system's."""
        status = DriveStatus(context.get_discrete_state(self._status).get_value().copy())
        status.target_left, status.target_right = left, right
        scaling = self._drive.motor_torque_scaling
        status.power_left, status.power_right = left / scaling, right / scaling
        context.SetDiscreteState(self._status, status[:])
        self._set_axle(context.get_mutable_discrete_state(), left, right)
        if context.get_discrete_state(self._mode).GetAtIndex(1) == Tracking.IDLE:
            self._set_tracking(context, Tracking.UNTRACKED)  # the next update writes
