"""Dead-reckoning odometry: the robot's pose integrated from its wheel encoders alone.

What a real Corobot's driver computes: each update, the front wheels' encoder increments
become rim distances (ticks x 2 pi / ticks-per-revolution x the effective wheel radius); their
mean is the distance travelled and their difference over the effective track width the turn
(differential-drive kinematics, integrated along the arc's mid heading). The effective radius
and track (`Drive.effective_wheel_radius`, `effective_track_width`) come from a calibration
(`tools/calibrate_odometry.py`, docs/tuning.md): compliant tyres roll on less than their
nominal radius, and a skid-steer robot turns less than its geometric track predicts.
"""

import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform
from pydrake.systems.framework import BasicVector, LeafSystem

from corobot_drake.config.scenario import Drive
from corobot_drake.model import dimensions as dim
from corobot_drake.systems.odometry import heading_of

_X, _Y, _YAW, _LEFT, _RIGHT = range(5)
"""The state: pose (m, m, rad unwrapped) and the encoder counts it last used."""
_GIVEN = 5
"""The `start` parameter: the state's five values, then how many of them are given (0: none,
3: the pose, 5: the pose and the counts)."""


def advance_pose(x: float, y: float, yaw: float, left: float, right: float,
                 track_width: float) -> tuple[float, float, float]:
    """The pose after the left and right wheels rolled `left`, `right` m: distance (l + r) / 2
    along the mid heading, yaw (r - l) / track (rad)."""
    distance, turn = 0.5 * (left + right), (right - left) / track_width
    mid = yaw + 0.5 * turn
    return x + distance * math.cos(mid), y + distance * math.sin(mid), yaw + turn


class DeadReckoning(LeafSystem):
    """Integrates the front wheels' encoder counts into a pose in the world frame.

    .. pydrake_system::

        name: DeadReckoning
        input_ports:
        - encoder_ticks
        - chassis_pose
        output_ports:
        - pose

    Input `encoder_ticks` (2: front left, front right counts, 600 per revolution, forward
    rolling counts up). Input `chassis_pose` (abstract RigidTransform X_WB) is read once, at
    initialization: the start pose (x, y, yaw) the odometry integrates from, unless
    `SetStart` gave one (a saved scene's). Output `pose` (3): x, y (m, the chassis origin in
    the world frame) and yaw (rad in (-pi, pi]) as dead reckoned. Discrete state [x, y, yaw
    (unwrapped), left ticks, right ticks], updated every `period` s and at initialization.
    Numeric parameter `start` (6): what `SetStart` gave.
    """

    def __init__(self, drive: Drive, period: float,
                 ticks_per_revolution: int = dim.ENCODER_TICKS_PER_REVOLUTION):
        super().__init__()
        self._metres_per_tick = 2 * math.pi * drive.effective_wheel_radius / ticks_per_revolution
        self._track = drive.effective_track_width
        self._ticks = self.DeclareVectorInputPort("encoder_ticks", 2)
        self._pose = self.DeclareAbstractInputPort("chassis_pose",
                                                   AbstractValue.Make(RigidTransform()))
        self._state = self.DeclareDiscreteState(5)
        self._start = self.DeclareNumericParameter(BasicVector(np.zeros(6)))
        self.DeclareInitializationDiscreteUpdateEvent(self._initialize)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update)
        self.DeclareVectorOutputPort("pose", 3, self._calc,
                                     {self.discrete_state_ticket(self._state)})

    def SetStart(self, context, values) -> None:
        """The state initialization gives: `values` [x, y, yaw] (m, m, rad unwrapped), then
        optionally the encoder counts [left, right] last integrated (default: the counts at
        initialization); empty: from the chassis pose. `context` is this system's."""
        if len(values) not in (0, 3, 5):
            raise ValueError(f"odometry start: needs 0, 3 or 5 values, got {len(values)}")
        start = np.zeros(6)
        start[:len(values)], start[_GIVEN] = values, len(values)
        context.get_mutable_numeric_parameter(self._start).SetFromVector(start)

    def State(self, context) -> list[float]:
        """[x, y, yaw (rad, unwrapped), left ticks, right ticks]: what `SetStart` takes to
        carry on from here. `context` is this system's."""
        return context.get_discrete_state(self._state).get_value().tolist()

    def _initialize(self, context, discrete_state):
        start = context.get_numeric_parameter(self._start).get_value()
        given = round(start[_GIVEN])
        X_WB = self._pose.Eval(context)
        x, y, _ = X_WB.translation()
        state = [x, y, heading_of(X_WB), *np.rint(self._ticks.Eval(context))]
        state[:given] = start[:given]
        discrete_state.set_value(self._state, state)

    def _update(self, context, discrete_state):
        # Plain floats (round: half to even, as np.rint) read as a BasicVector's elements and
        # written as one numpy array: numpy's per-call overhead and pydrake's input-port copies
        # cost more than the sums on two numbers, every control period.
        ticks = self._ticks.EvalBasicVector(context)
        left, right = round(ticks[0]), round(ticks[1])
        x, y, yaw, last_left, last_right = context.get_discrete_state(
            self._state).get_value().tolist()
        if left == last_left and right == last_right:
            return  # at rest: the state stays (no copy)
        k = self._metres_per_tick
        pose = advance_pose(x, y, yaw, k * (left - last_left), k * (right - last_right),
                            self._track)
        discrete_state.set_value(self._state, np.array([*pose, left, right], dtype=float))

    def _calc(self, context, output):
        x, y, yaw = context.get_discrete_state(self._state).get_value()[:3]
        output.SetFromVector([x, y, math.remainder(yaw, 2 * math.pi)])
