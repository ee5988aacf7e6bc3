"""The run log: what a real Corobot's logger records, sampled from the simulation.

Each robot of a station carries a `RunLogSample` system (named `<robot>.run_log_sample`)
feeding a Drake `VectorLogSink` (`<robot>.run_log`) that samples it every `LOG_PERIOD` s. The
log lives in the Context, like the rest of the run. `write_csv` writes it in the CSV format that
`corobot_drake.tuning.sysid` reads (columns documented in docs/tuning.md), then the
simulation's contact telemetry, which no real logger has:

    time,left_power,right_power,left_ticks,right_ticks,x,y,yaw,
    load_fl,load_fr,load_rl,load_rr,slip_ratio_fl,...,slip_angle_fl,...,tip_margin

- time: s. left_power, right_power: the drive's commanded power per side in [-1, 1].
- left_ticks, right_ticks: front-left / front-right encoder counts, `ENCODER_TICKS_PER_REVOLUTION`
  (600) per wheel revolution, floor(600 q / 2 pi) of the integrated wheel angle q (forward
  rolling counts up): the odometry's encoders (`odometry.add_wheel_encoders`).
- x, y: chassis position in the world, m. yaw: chassis heading about world z, rad, in (-pi, pi].
- load_*, slip_ratio_*, slip_angle_*: per wheel (fl front left, fr, rl, rr), N,
  dimensionless (+ traction), deg (+ to the left): `contact.WheelContacts`, sampled every
  `HELD_PERIOD` (0.1 s) and held. tip_margin: deg, `stability.TipMargin`, every row. They go
  into the sink straight from those systems' ports (a Multiplexer).
"""

from pathlib import Path

import numpy as np
from pydrake.common.containers import namedview
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform
from pydrake.systems.framework import BasicVector, LeafSystem
from pydrake.systems.primitives import LogVectorOutput, Multiplexer, ZeroOrderHold

from corobot_drake import signals
from corobot_drake.systems.drive import DriveStatus
from corobot_drake.systems.odometry import heading_of

LOG_PERIOD = 0.01
"""s: the run log's sample period (100 Hz)."""
RUN_LOG_CHUNK = 1000
"""Samples (10 s at 100 Hz) moved out of the sink at a time when the run log is bounded
(`Simulation.run_log_window`)."""
SAMPLE_COLUMNS = ("time", "left_power", "right_power", "left_ticks", "right_ticks", "x", "y",
                  "yaw")
"""What a real Corobot's logger records (the `RunLogSample`, after the sink's time)."""
TELEMETRY = tuple((signal.port, signal.log) for signal in signals.TELEMETRY)
"""(robot port, its columns) of the contact telemetry, in the log's order (`signals.TELEMETRY`)."""
HELD_PERIOD = 0.1
"""s: the loads and the slip are sampled every 0.1 s (10 Hz) and held between (ZeroOrderHolds):
evaluated every 10 ms step, the loads (the plant's contact results) and the slip (the bodies'
velocities) cost well over the ~3% of a step the run log may add (the
measurement is in the commit that added this). A row's loads and slip are those of the latest
0.1 s sample; its tip margin is the step's (a few sums from the chassis pose, and the run's
least margin, `Robot.min_tip_margin_deg`, is read from it)."""
HELD = tuple(signal.port for signal in signals.TELEMETRY if signal.costly)
COLUMNS = SAMPLE_COLUMNS + tuple(c for _, columns in TELEMETRY for c in columns)

LogSample = namedview("LogSample", SAMPLE_COLUMNS[1:])
"""`RunLogSample`'s output, read by name: the `SAMPLE_COLUMNS` after time (the sink adds
time)."""


class RunLogSample(LeafSystem):
    """One row of the run log (without time) from the robot's signals.

    .. pydrake_system::

        name: RunLogSample
        input_ports:
        - chassis_pose
        - drive_status
        - encoder_ticks
        output_ports:
        - sample

    Input `chassis_pose` (abstract RigidTransform X_WB, from `odometry.ChassisPoses`); input
    `drive_status` (5, `drive.DriveStatus`); input `encoder_ticks` (2, front left and front
    right, from the odometry's encoders). Output `sample` (7, `LogSample`): left_power,
    right_power in [-1, 1]; left_ticks, right_ticks rounded to whole ticks; x, y, m, of the
    chassis origin in the world frame; yaw, rad in (-pi, pi] (`odometry.heading_of`).
    """

    def __init__(self):
        super().__init__()
        self._pose_port = self.DeclareAbstractInputPort("chassis_pose",
                                                        AbstractValue.Make(RigidTransform()))
        self._status_port = self.DeclareVectorInputPort("drive_status",
                                                        len(DriveStatus.get_fields()))
        self._ticks_port = self.DeclareVectorInputPort("encoder_ticks", 2)
        self.DeclareVectorOutputPort("sample", len(LogSample.get_fields()), self._calc)

    def _calc(self, context, output: BasicVector):
        X_WB = self._pose_port.Eval(context)
        status = DriveStatus(self._status_port.Eval(context))
        left_ticks, right_ticks = np.rint(self._ticks_port.Eval(context))  # whole ticks
        x, y, _ = X_WB.translation()
        sample = dict(left_power=status.power_left, right_power=status.power_right,
                      left_ticks=left_ticks, right_ticks=right_ticks, x=x, y=y,
                      yaw=heading_of(X_WB))
        output.SetFromVector([sample[field] for field in LogSample.get_fields()])


def add_run_log(builder, name: str, chassis_pose_port, drive_status_port, encoder_ticks_port,
                telemetry_ports: dict):
    """Adds `<name>.run_log_sample`, `<name>.run_log_row` (a Multiplexer of the sample and the
    `telemetry_ports`, {`TELEMETRY` port name: output port}; the `HELD` ones through holds
    `<name>.run_log_<port>`) and its sink `<name>.run_log`; returns the sink."""
    sample = builder.AddNamedSystem(f"{name}.run_log_sample", RunLogSample())
    for port_name, port in (("chassis_pose", chassis_pose_port),
                            ("drive_status", drive_status_port),
                            ("encoder_ticks", encoder_ticks_port)):
        builder.Connect(port, sample.GetInputPort(port_name))
    sizes = [len(SAMPLE_COLUMNS) - 1, *(len(columns) for _, columns in TELEMETRY)]
    row = builder.AddNamedSystem(f"{name}.run_log_row", Multiplexer(sizes))
    builder.Connect(sample.get_output_port(), row.get_input_port(0))
    for k, (port_name, columns) in enumerate(TELEMETRY, start=1):
        port = telemetry_ports[port_name]
        if port_name in HELD:
            hold = builder.AddNamedSystem(f"{name}.run_log_{port_name}",
                                          ZeroOrderHold(HELD_PERIOD, len(columns)))
            builder.Connect(port, hold.get_input_port())
            port = hold.get_output_port()
        builder.Connect(port, row.get_input_port(k))
    sink = LogVectorOutput(row.get_output_port(), builder, LOG_PERIOD)
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
        for t, pl, pr, tl, tr, x, y, yaw, *telemetry in rows:
            f.write(f"{t:.6f},{pl:.6g},{pr:.6g},{int(tl)},{int(tr)},{x:.6f},{y:.6f},{yaw:.6f}")
            f.write("".join(f",{v:.6g}" for v in telemetry) + "\n")
