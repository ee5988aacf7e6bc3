"""The skid-steer drive: the command source (script + API inbox) and the drive controller.

Commands are the scenario's command dataclasses (`SetPower`, `SetSpeed`, ...). A `DriveRequest`
pairs one with a sequence number; a system acts on a request when it sees a new number, so a
request is a message, not a level, and every system's memory of it lives in the Context.
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.common.value import Value
from pydrake.systems.framework import BasicVector, LeafSystem

from corobot_drake import dimensions as dim
from corobot_drake.scenario import AllStop, Drive, Enable, SetPower, SetSpeed, Wait


class _Immutable:
    """Frozen values are shared, not copied, when Drake clones the Context's abstract state
    (it does so every step; a deep copy of a growing log would make long runs slow)."""

    def __deepcopy__(self, memo):
        return self

    def __copy__(self):
        return self


@dc.dataclass(frozen=True)
class DriveRequest(_Immutable):
    """A command (a scenario command dataclass) stamped with its sequence number and time.

    The command is never mutated after it is issued."""

    seq: int = 0
    """Increases by one with every request; 0 means "nothing requested yet"."""
    command: object = None
    time: float = 0.0
    """Simulation time (s) at which it was issued."""


@dc.dataclass(frozen=True)
class CommandRecord(_Immutable):
    """One command's life, for the run summary. Times in s; end_time None while running."""

    seq: int
    command: str
    start_time: float
    end_time: float | None = None
    status: str = "running"
    """running, succeeded or failed."""
    reason: str = ""


@dc.dataclass(frozen=True)
class CommandSourceState(_Immutable):
    """The command source's whole memory (held as abstract state in the Context)."""

    request: DriveRequest = DriveRequest()
    next_script_index: int = 0
    script_blocked_until: float = 0.0
    """Simulation time before which the script issues nothing (a running Wait)."""
    log: tuple[CommandRecord, ...] = ()


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

    Output `request` (DriveRequest). The script advances at `period`; a `Wait` holds it for
    its duration. `Issue()` writes a command into the Context directly (what the Python API,
    teleop and the server call between simulation steps).
    """

    def __init__(self, script: list, period: float):
        super().__init__()
        for command in script:
            check_finite(command)
        self._script = tuple(script)
        self._state_index = self.DeclareAbstractState(Value(CommandSourceState()))
        self.DeclareAbstractOutputPort(
            "request", lambda: Value(DriveRequest()), self._calc_request,
            {self.abstract_state_ticket(self._state_index)})
        if self._script:
            self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._run_script)

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
        if log and log[-1].end_time is None:
            last = log[-1]
            log[-1] = dc.replace(last, end_time=time, status="succeeded")
        seq = state.request.seq + 1
        log.append(CommandRecord(seq=seq, command=command_name(command), start_time=time))
        return dc.replace(state, request=DriveRequest(seq, command, time), log=tuple(log))

    def Issue(self, context, command) -> int:
        """Issues `command` now (context time); returns its sequence number."""
        state = self._with_command(self.get_state(context), command, context.get_time())
        self._set_state(context, state)
        return state.request.seq

    def _run_script(self, context, state):
        now = context.get_time()
        current = self.get_state(context)
        if current.next_script_index >= len(self._script) or now < current.script_blocked_until:
            return
        command = self._script[current.next_script_index]
        updated = dc.replace(current, next_script_index=current.next_script_index + 1)
        if isinstance(command, Wait):
            log = list(updated.log)
            log.append(CommandRecord(seq=0, command="Wait", start_time=now,
                                     end_time=now + command.seconds, status="succeeded"))
            updated = dc.replace(updated, script_blocked_until=now + command.seconds,
                                 log=tuple(log))
        else:
            updated = self._with_command(updated, command, now)
        self._set_state(state, updated)


# Indices of the drive controller's discrete state.
_SEQ, _ENABLED, _POWER_L, _POWER_R, _TARGET_L, _TARGET_R, _AXLE_L, _AXLE_R = range(8)


class DriveController(LeafSystem):
    """Turns drive requests into the plant's desired wheel state (velocity servo).

    Input `request` (DriveRequest); input `wheel_state` [q, v] of the four axles in
    `dimensions.WHEEL_NAMES` order (rad, rad/s).
    Output `desired_state` [q_d, v_d] for the plant's desired-state input (actuator order;
    q_d = 0: the servo has kp = 0 and only v_d matters).
    Output `axle_speed_command` [left, right] rad/s after the slew limit; rear follows front.
    Output `drive_status` [enabled, power_left, power_right, target_left, target_right].
    Output `axle_speed` [front_left, front_right, rear_left, rear_right] measured, rad/s.
    Discrete state, updated every `drive.control_period` s.
    """

    def __init__(self, drive: Drive):
        super().__init__()
        self._drive = drive
        self._request_port = self.DeclareAbstractInputPort("request", Value(DriveRequest()))
        self._wheel_state_port = self.DeclareVectorInputPort("wheel_state", 8)
        initial = np.zeros(8)
        initial[_ENABLED] = 1.0
        self._state = self.DeclareDiscreteState(initial)
        self.DeclarePeriodicDiscreteUpdateEvent(drive.control_period, 0.0, self._update)
        ticket = {self.discrete_state_ticket(self._state)}
        # Depends on the state only, so the plant's per-step evaluation hits the cache.
        self.DeclareVectorOutputPort("desired_state", 8, self._calc_desired_state, ticket)
        self.DeclareVectorOutputPort("axle_speed_command", 2, self._calc_axle, ticket)
        self.DeclareVectorOutputPort("drive_status", 5, self._calc_status, ticket)
        self.DeclareVectorOutputPort(
            "axle_speed", 4, lambda c, o: o.SetFromVector(self._wheel_state_port.Eval(c)[4:]),
            {self.input_port_ticket(self._wheel_state_port.get_index())})

    def target_for(self, command, enabled: bool) -> tuple[float, float, float, float] | None:
        """(power_l, power_r, axle_l, axle_r) a motion command asks for; None if not motion."""
        d = self._drive
        if isinstance(command, SetPower):
            pl, pr = (float(np.clip(p, -1.0, 1.0)) for p in (command.left, command.right))
            return pl, pr, pl * d.motor_torque_scaling, pr * d.motor_torque_scaling
        if isinstance(command, SetSpeed):
            al, ar = (float(np.clip(v / dim.WHEEL_RADIUS, -d.max_axle_speed, d.max_axle_speed))
                      for v in (command.left, command.right))
            return al / d.motor_torque_scaling, ar / d.motor_torque_scaling, al, ar
        if isinstance(command, AllStop):
            return 0.0, 0.0, 0.0, 0.0
        return None

    def _update(self, context, discrete_state):
        x = context.get_discrete_state(self._state).get_value().copy()
        request = self._request_port.Eval(context)
        if request.seq != int(x[_SEQ]):
            x[_SEQ] = request.seq
            command = request.command
            if isinstance(command, Enable):
                x[_ENABLED] = 1.0 if command.enabled else 0.0
            elif x[_ENABLED]:
                target = self.target_for(command, True)
                if target is not None:
                    x[_POWER_L:_TARGET_R + 1] = target
        if not x[_ENABLED]:
            x[_POWER_L:_AXLE_R + 1] = 0.0  # disabled: wheels held at zero at once
        step = self._drive.slew_rate * self._drive.control_period
        x[_AXLE_L:_AXLE_R + 1] += np.clip(
            x[_TARGET_L:_TARGET_R + 1] - x[_AXLE_L:_AXLE_R + 1], -step, step)
        discrete_state.set_value(self._state, x)

    def _calc_desired_state(self, context, output: BasicVector):
        x = context.get_discrete_state(self._state).get_value()
        left, right = x[_AXLE_L], x[_AXLE_R]
        output.SetFromVector([0.0, 0.0, 0.0, 0.0, left, right, left, right])

    def _calc_axle(self, context, output: BasicVector):
        output.SetFromVector(context.get_discrete_state(self._state).get_value()[_AXLE_L:])

    def _calc_status(self, context, output: BasicVector):
        output.SetFromVector(
            context.get_discrete_state(self._state).get_value()[_ENABLED:_TARGET_R + 1])
