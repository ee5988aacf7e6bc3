"""Run statistics measured from the simulation (for the summary and the tests)."""

import math

from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform
from pydrake.systems.framework import LeafSystem


def tilt_deg(X_WB: RigidTransform) -> float:
    """Angle (deg) between the body's +z and the world's +z: 0 upright, 180 upside down."""
    cos_tilt = float(X_WB.GetAsMatrix34()[2, 2])  # R[2, 2]
    return math.degrees(math.acos(min(1.0, max(-1.0, cos_tilt))))


class TiltMonitor(LeafSystem):
    """Largest tilt from upright of one body over the run, sampled every `period` s.

    .. pydrake_system::

        name: TiltMonitor
        input_ports:
        - chassis_pose
        output_ports:
        - max_tilt_deg

    Input `chassis_pose` (abstract RigidTransform X_WB, e.g. from `odometry.ChassisPoses`).
    Output `max_tilt_deg` (1-vector, degrees): the largest `tilt_deg` sampled so far, held in
    discrete state (0 before the first sample, at time 0).
    """

    def __init__(self, period: float):
        super().__init__()
        self._pose_port = self.DeclareAbstractInputPort("chassis_pose",
                                                        AbstractValue.Make(RigidTransform()))
        self._state = self.DeclareDiscreteState(1)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update)
        self.DeclareStateOutputPort("max_tilt_deg", self._state)

    def _update(self, context, discrete_state):
        previous = context.get_discrete_state(self._state).get_value()[0]
        tilt = tilt_deg(self._pose_port.Eval(context))
        discrete_state.set_value(self._state, [max(previous, tilt)])
