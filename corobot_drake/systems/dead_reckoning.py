"""Dead-reckoning odometry: the robot's pose integrated from its wheel encoders alone.

What a real Corobot's driver computes: each control period, the front wheels' encoder
increments become rim distances (ticks x 2 pi / ticks-per-revolution x the effective wheel
radius); their mean is the distance travelled and their difference over the effective track
width the turn (differential-drive kinematics, integrated along the arc's mid heading). The
effective radius and track (`Drive.effective_wheel_radius`, `effective_track_width`) come from
a calibration (`tools/calibrate_odometry.py`, docs/tuning.md): compliant tyres roll on less
than their nominal radius, and a skid-steer robot turns less than its geometric track predicts.

The samples are taken every control period by Drake (`encoder_history`, a shift register in
the Context) and folded into the pose in Python only every `HISTORY` periods and when the pose
is read: the same sums in the same order as an update every period, without a Python callback
on every physics step.
"""

import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform
from pydrake.systems.framework import BasicVector, Diagram, DiagramBuilder, LeafSystem
from pydrake.systems.primitives import AffineSystem

from corobot_drake.config.scenario import Drive
from corobot_drake.robots import corobot
from corobot_drake.systems.odometry import heading_of

HISTORY = 8
"""Encoder samples the history holds; the pose is folded every `HISTORY` control periods. A
power of two: k x (8 period) and 8k x period are then the same double, so the fold happens at
the very instants of the history's samples (and adds no step of its own to the Simulator)."""
_X, _Y, _YAW, _LEFT, _RIGHT, _TAKEN, _ROLLED, _TURNED = range(8)
"""The integrator's state: pose (m, m, rad unwrapped), the encoder counts it last used, the
history's sample count it has folded up to, and the travel since the last reset: the distance
rolled (m, forward and back alike) and the turning (rad, either way) the odometry's error grows
with (`systems.odometry_error`)."""
_GIVEN = 5
"""The `start` parameter: the state's first five values, then how many of them are given (0:
none, 3: the pose, 5: the pose and the counts)."""


def advance_pose(x: float, y: float, yaw: float, left: float, right: float,
                 track_width: float) -> tuple[float, float, float]:
    """The pose after the left and right wheels rolled `left`, `right` m: distance (l + r) / 2
    along the mid heading, yaw (r - l) / track (rad)."""
    distance, turn = 0.5 * (left + right), (right - left) / track_width
    mid = yaw + 0.5 * turn
    return x + distance * math.cos(mid), y + distance * math.sin(mid), yaw + turn


def encoder_history(period: float, length: int = HISTORY) -> AffineSystem:
    """A shift register of encoder samples, updated every `period` s (C++: no Python per step).

    Input (2): the encoder counts [left, right]. State and output (1 + 2 `length`): how many
    samples were ever taken, then the last `length` samples' [left, right], newest first.
    The copies are exact (each entry is a sum of one sample times 1 and zeros)."""
    n = 1 + 2 * length
    shift = np.zeros((n, n))
    shift[0, 0] = 1.0
    shift[3:, 1:n - 2] = np.eye(n - 3)
    take = np.zeros((n, 2))
    take[1, 0] = take[2, 1] = 1.0
    count = np.zeros(n)
    count[0] = 1.0
    return AffineSystem(A=shift, B=take, f0=count, C=np.eye(n), y0=np.zeros(n),
                        time_period=period)


class PoseIntegrator(LeafSystem):
    """Folds the encoder history's samples into a pose in the world frame.

    .. pydrake_system::

        name: PoseIntegrator
        input_ports:
        - encoder_history
        - encoder_ticks
        - chassis_pose
        output_ports:
        - pose
        - travel

    Input `encoder_history` (1 + 2 `length`, `encoder_history`'s output). Inputs
    `encoder_ticks` (2: front left, front right counts, 600 per revolution, forward rolling
    counts up) and `chassis_pose` (abstract RigidTransform X_WB) are read once, at
    initialization: the counts and the start pose (x, y, yaw) the odometry integrates from,
    unless `SetStart` gave them (a saved scene's). Output `pose` (3): x, y (m, the chassis
    origin in the world frame) and yaw (rad in (-pi, pi]), with every sample taken so far.
    Output `travel` (2): the distance rolled (m, the sum of each sample's |mean wheel
    distance|) and the turning (rad, the sum of each sample's |turn|) since initialization or
    the last `Teleport`. Discrete state [x, y, yaw (unwrapped), left ticks, right ticks,
    samples folded, distance rolled, turning], folded every `fold_period` s and at
    initialization. Numeric parameter `start` (6): what
    `SetStart` gave.
    """

    def __init__(self, drive: Drive, fold_period: float, length: int = HISTORY,
                 ticks_per_revolution: int = corobot.drive("encoder_ticks_per_revolution")):
        super().__init__()
        self._metres_per_tick = 2 * math.pi * drive.effective_wheel_radius / ticks_per_revolution
        self._track, self._length = drive.effective_track_width, length
        self._history = self.DeclareVectorInputPort("encoder_history", 1 + 2 * length)
        self._ticks = self.DeclareVectorInputPort("encoder_ticks", 2)
        self._pose = self.DeclareAbstractInputPort("chassis_pose",
                                                   AbstractValue.Make(RigidTransform()))
        self._state = self.DeclareDiscreteState(8)
        self._start = self.DeclareNumericParameter(BasicVector(np.zeros(6)))
        self.DeclareInitializationDiscreteUpdateEvent(self._initialize)
        self.DeclarePeriodicDiscreteUpdateEvent(fold_period, 0.0, self._fold)
        folded = {self.discrete_state_ticket(self._state), self._history.ticket()}
        self.DeclareVectorOutputPort("pose", 3, self._calc, folded)
        self.DeclareVectorOutputPort(
            "travel", 2, lambda c, o: o.SetFromVector(self._folded(c)[_ROLLED:]), folded)

    def SetStart(self, context, values) -> None:
        """See `DeadReckoning.SetStart`; `context` is this system's."""
        if len(values) not in (0, 3, 5):
            raise ValueError(f"odometry start: needs 0, 3 or 5 values, got {len(values)}")
        start = np.zeros(6)
        start[:len(values)], start[_GIVEN] = values, len(values)
        context.get_mutable_numeric_parameter(self._start).SetFromVector(start)

    def State(self, context) -> list[float]:
        """See `DeadReckoning.State`; `context` is this system's."""
        return list(self._folded(context)[:_TAKEN])

    def Teleport(self, context, x: float, y: float, yaw: float) -> None:
        """See `DeadReckoning.Teleport`; `context` is this system's."""
        folded = list(self._folded(context))
        folded[:_LEFT] = x, y, yaw
        folded[_ROLLED:] = 0.0, 0.0  # a reset pose is known: its error starts afresh
        context.SetDiscreteState(np.array(folded, dtype=float))

    def _initialize(self, context, discrete_state):
        start = context.get_numeric_parameter(self._start).get_value()
        given = round(start[_GIVEN])
        X_WB = self._pose.Eval(context)
        x, y, _ = X_WB.translation()
        state = [x, y, heading_of(X_WB), *np.rint(self._ticks.Eval(context)),
                 self._history.EvalBasicVector(context)[0], 0.0, 0.0]
        state[:given] = start[:given]
        discrete_state.set_value(self._state, state)

    def _folded(self, context) -> tuple[float, ...]:
        """The state with the samples the history took since the last fold folded in: each
        sample's increments since the one before, oldest first (plain floats; round: half to
        even, as np.rint)."""
        history = self._history.EvalBasicVector(context)
        x, y, yaw, left, right, taken, rolled, turned = context.get_discrete_state(
            self._state).get_value().tolist()
        count = history[0]
        pending = round(count - taken)
        if pending > self._length:
            raise RuntimeError(f"dead reckoning: {pending} encoder samples to fold, the history "
                               f"holds {self._length}")
        k = self._metres_per_tick
        for i in range(pending, 0, -1):
            sample_left, sample_right = round(history[2 * i - 1]), round(history[2 * i])
            if sample_left == left and sample_right == right:
                continue  # at rest: no motion
            rolled_left, rolled_right = k * (sample_left - left), k * (sample_right - right)
            x, y, yaw = advance_pose(x, y, yaw, rolled_left, rolled_right, self._track)
            rolled += abs(0.5 * (rolled_left + rolled_right))
            turned += abs(rolled_right - rolled_left) / self._track
            left, right = sample_left, sample_right
        return x, y, yaw, float(left), float(right), count, rolled, turned

    def _fold(self, context, discrete_state):
        discrete_state.set_value(self._state, np.array(self._folded(context), dtype=float))

    def _calc(self, context, output):
        x, y, yaw = self._folded(context)[:3]
        output.SetFromVector([x, y, math.remainder(yaw, 2 * math.pi)])


class DeadReckoning(Diagram):
    """Integrates the front wheels' encoder counts into a pose in the world frame: the
    `encoder_history` sampling them every `period` s, the `PoseIntegrator` folding them.

    .. pydrake_system::

        name: DeadReckoning
        input_ports:
        - encoder_ticks
        - chassis_pose
        output_ports:
        - pose
        - travel

    Input `encoder_ticks` (2: front left, front right counts, 600 per revolution, forward
    rolling counts up), sampled every `period` s from 0. Input `chassis_pose` (abstract
    RigidTransform X_WB) is read once, at initialization: the start pose (x, y, yaw) the
    odometry integrates from, unless `SetStart` gave one (a saved scene's). Output `pose` (3):
    x, y (m, the chassis origin in the world frame) and yaw (rad in (-pi, pi]) as dead
    reckoned through the latest sample. Output `travel` (2): the distance rolled (m) and the
    turning (rad) since the start or the last `Teleport`, which the odometry's error grows
    with (`systems.odometry_error`).
    """

    def __init__(self, drive: Drive, period: float,
                 ticks_per_revolution: int = corobot.drive("encoder_ticks_per_revolution")):
        super().__init__()
        builder = DiagramBuilder()
        history = builder.AddNamedSystem("encoder_history", encoder_history(period))
        self._integrator = builder.AddNamedSystem(
            "integrator", PoseIntegrator(drive, HISTORY * period, HISTORY, ticks_per_revolution))
        builder.Connect(history.get_output_port(),
                        self._integrator.GetInputPort("encoder_history"))
        builder.ExportInput(history.get_input_port(), "encoder_ticks")
        builder.ConnectInput("encoder_ticks", self._integrator.GetInputPort("encoder_ticks"))
        builder.ExportInput(self._integrator.GetInputPort("chassis_pose"), "chassis_pose")
        builder.ExportOutput(self._integrator.GetOutputPort("pose"), "pose")
        builder.ExportOutput(self._integrator.GetOutputPort("travel"), "travel")
        builder.BuildInto(self)

    def SetStart(self, context, values) -> None:
        """The state initialization gives: `values` [x, y, yaw] (m, m, rad unwrapped), then
        optionally the encoder counts [left, right] last integrated (default: the counts at
        initialization); empty: from the chassis pose. `context` is this system's."""
        self._integrator.SetStart(
            self.GetMutableSubsystemContext(self._integrator, context), values)

    def State(self, context) -> list[float]:
        """[x, y, yaw (rad, unwrapped), left ticks, right ticks]: what `SetStart` takes to
        carry on from here. `context` is this system's."""
        return self._integrator.State(self.GetSubsystemContext(self._integrator, context))

    def Teleport(self, context, x: float, y: float, yaw: float) -> None:
        """Puts the dead reckoning at the pose a teleport put the robot (x, y m, yaw rad), the
        encoder samples taken so far folded in first: it integrates on from there, as a
        driver's odometry reset does; its travel (and so its error) starts again from 0.
        `context` is this system's."""
        self._integrator.Teleport(
            self.GetMutableSubsystemContext(self._integrator, context), x, y, yaw)
