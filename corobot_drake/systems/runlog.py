"""The run log: what a real Corobot's logger records, sampled from the simulation.

Each robot of a station carries a `RunLogSample` system (named `<robot>.run_log_sample`)
feeding a Drake `VectorLogSink` (`<robot>.run_log`) that samples it every `LOG_PERIOD` s. The
log lives in the Context, like the rest of the run. `write_csv` writes it in the CSV format that
`corobot_drake.analysis.sysid` reads (columns documented in docs/tuning.md):

    time,left_power,right_power,left_ticks,right_ticks,x,y,yaw

- time: s. left_power, right_power: the drive's commanded power per side in [-1, 1].
- left_ticks, right_ticks: front-left / front-right encoder counts, `ENCODER_TICKS_PER_REVOLUTION`
  (600) per wheel revolution, floor(600 q / 2 pi) of the integrated wheel angle q (forward
  rolling counts up).
- x, y: chassis position in the world, m. yaw: chassis heading about world z, rad, in (-pi, pi].
"""

import math
from pathlib import Path

import numpy as np
from pydrake.systems.framework import BasicVector, LeafSystem
from pydrake.systems.primitives import LogVectorOutput

from corobot_drake.model import dimensions as dim
from corobot_drake.systems.odometry import yaw_from_quaternion

LOG_PERIOD = 0.01
"""s: the run log's sample period (100 Hz)."""
COLUMNS = ("time", "left_power", "right_power", "left_ticks", "right_ticks", "x", "y", "yaw")


def ticks(angle: float) -> int:
    """Encoder count of a wheel turned by `angle` rad (600 per revolution, floor)."""
    return math.floor(dim.ENCODER_TICKS_PER_REVOLUTION * angle / (2 * math.pi))


class RunLogSample(LeafSystem):
    """One row of the run log (without time) from the plant state and the drive status.

    Input `plant_state` (the plant's full state); input `drive_status` (the drive controller's
    [enabled, power_left, power_right, ...]). Output `sample`
    [left_power, right_power, left_ticks, right_ticks, x, y, yaw].
    """

    def __init__(self, num_states: int, quaternion_start: int, left_wheel_q: int,
                 right_wheel_q: int):
        super().__init__()
        self._q0 = quaternion_start
        self._wheels = (left_wheel_q, right_wheel_q)
        self._state_port = self.DeclareVectorInputPort("plant_state", num_states)
        self._status_port = self.DeclareVectorInputPort("drive_status", 5)
        self.DeclareVectorOutputPort("sample", 7, self._calc)

    def _calc(self, context, output: BasicVector):
        state = self._state_port.Eval(context)
        status = self._status_port.Eval(context)
        w, qx, qy, qz, x, y = state[self._q0:self._q0 + 6]
        yaw = yaw_from_quaternion(w, qx, qy, qz)
        left, right = (ticks(state[i]) for i in self._wheels)
        output.SetFromVector([status[1], status[2], left, right, x, y, yaw])


def add_run_log(builder, plant, name: str, chassis, wheel_joints, drive_status_port):
    """Adds `<name>.run_log_sample` and its sink `<name>.run_log`; returns the sink."""
    front_left, front_right = (j.position_start() for j in wheel_joints[:2])
    sample = builder.AddNamedSystem(f"{name}.run_log_sample", RunLogSample(
        plant.num_multibody_states(), chassis.floating_positions_start(), front_left,
        front_right))
    builder.Connect(plant.get_state_output_port(), sample.GetInputPort("plant_state"))
    builder.Connect(drive_status_port, sample.GetInputPort("drive_status"))
    sink = LogVectorOutput(sample.get_output_port(), builder, LOG_PERIOD)
    sink.set_name(f"{name}.run_log")
    return sink


def log_rows(sink, root_context) -> np.ndarray:
    """The log so far as an array with the `COLUMNS` (one row per sample)."""
    log = sink.FindLog(root_context)
    return np.column_stack([log.sample_times(), log.data().T]) if log.num_samples() else \
        np.zeros((0, len(COLUMNS)))


def write_csv(rows: np.ndarray, path: str | Path) -> None:
    """Writes run-log rows (from `log_rows`) as CSV with a header line."""
    with open(path, "w") as f:
        f.write(",".join(COLUMNS) + "\n")
        for t, pl, pr, tl, tr, x, y, yaw in rows:
            f.write(f"{t:.6f},{pl:.6g},{pr:.6g},{int(tl)},{int(tr)},{x:.6f},{y:.6f},{yaw:.6f}\n")
