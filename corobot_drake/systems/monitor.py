"""Run statistics measured from the simulation (for the summary and the tests)."""

import math

from pydrake.systems.framework import LeafSystem


def quaternion_tilt_deg(qw: float, qx: float, qy: float, qz: float) -> float:
    """Angle (deg) between a body's +z and the world's +z (0 upright, 180 upside down) for
    the quaternion (w, x, y, z; any norm) of its R_WB: R[2, 2] is 1 - 2 (x^2 + y^2) of the
    normalized quaternion."""
    cos_tilt = 1.0 - 2.0 * (qx * qx + qy * qy) / (qw * qw + qx * qx + qy * qy + qz * qz)
    return math.degrees(math.acos(min(1.0, max(-1.0, cos_tilt))))


class TiltMonitor(LeafSystem):
    """Largest tilt from upright of one body over the run, sampled every `period` s.

    .. pydrake_system::

        name: TiltMonitor
        input_ports:
        - chassis_state
        output_ports:
        - max_tilt_deg

    Input `chassis_state` (7: the body's floating-base positions, `odometry.CHASSIS_STATE`:
    quaternion w, x, y, z, then position; a vector straight from the plant's state, so a
    sample costs no pose conversion). Output `max_tilt_deg` (1-vector, degrees): the largest
    tilt sampled so far, held in discrete state (0 before the first sample, at time 0).
    """

    def __init__(self, period: float):
        super().__init__()
        self._state_port = self.DeclareVectorInputPort("chassis_state", 7)
        self._state = self.DeclareDiscreteState(1)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update)
        self.DeclareStateOutputPort("max_tilt_deg", self._state)

    def _update(self, context, discrete_state):
        # A BasicVector's elements, not a copy of the input as numpy: this runs every period.
        q = self._state_port.EvalBasicVector(context)
        tilt = quaternion_tilt_deg(q[0], q[1], q[2], q[3])
        if tilt > context.get_discrete_state(self._state)[0]:
            discrete_state.get_mutable_vector(self._state).SetAtIndex(0, tilt)
