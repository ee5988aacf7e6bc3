"""Run statistics measured from the simulation (for the summary and the tests)."""

import math

import numpy as np
from pydrake.math import RigidTransform
from pydrake.systems.framework import LeafSystem


def tilt_deg(X_WB: RigidTransform) -> float:
    """Angle (deg) between the body's +z and the world's +z: 0 upright, 180 upside down."""
    return math.degrees(math.acos(float(np.clip(X_WB.rotation().matrix()[2, 2], -1.0, 1.0))))


def quaternion_tilt_deg(w: float, x: float, y: float, z: float) -> float:
    """tilt_deg of the rotation given by a unit quaternion: R[2, 2] = 1 - 2 (x^2 + y^2)."""
    norm2 = w * w + x * x + y * y + z * z
    cos_tilt = 1.0 - 2.0 * (x * x + y * y) / norm2
    return math.degrees(math.acos(min(1.0, max(-1.0, cos_tilt))))


class TiltMonitor(LeafSystem):
    """Largest tilt from upright of one floating body over the run, sampled every `period` s.

    Input `plant_state` (the plant's full state vector); the body's quaternion (w, x, y, z)
    starts at `quaternion_start`. Output `max_tilt_deg` (1-vector, degrees).
    """

    def __init__(self, num_states: int, quaternion_start: int, period: float):
        super().__init__()
        self._start = quaternion_start
        self._state_port = self.DeclareVectorInputPort("plant_state", num_states)
        self._state = self.DeclareDiscreteState(1)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update)
        self.DeclareStateOutputPort("max_tilt_deg", self._state)

    def _update(self, context, discrete_state):
        q = self._state_port.Eval(context)[self._start:self._start + 4]
        previous = context.get_discrete_state(self._state).get_value()[0]
        discrete_state.set_value(self._state, [max(previous, quaternion_tilt_deg(*q))])
