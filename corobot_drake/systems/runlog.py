"""The run log: what a real Corobot's logger records, sampled from the simulation.

Each robot of a station carries a Drake `VectorLogSink` (`<robot>.run_log`) that samples its
signals every `LOG_PERIOD` s (`RAW_COLUMNS`, straight from C++ systems' ports: no Python call
per sample); `log_rows` turns them into the columns below when the log is read. The log lives
in the Context, like the rest of the run. `write_csv` writes it in the CSV format that
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
  `HELD_PERIOD` (0.1 s) and held. tip_margin: deg, `stability.TipMargin` of the row's
  chassis pose (computed when the log is read, as the yaw is).
"""

from pathlib import Path

import numpy as np
from pydrake.systems.primitives import LogVectorOutput, Multiplexer, ZeroOrderHold

from corobot_drake import signals
from corobot_drake.systems.drive import DriveStatus
from corobot_drake.systems.odometry import CHASSIS_STATE, rotation_rows

LOG_PERIOD = 0.01
"""s: the run log's sample period (100 Hz)."""
RUN_LOG_CHUNK = 1000
"""Samples (10 s at 100 Hz) moved out of the sink at a time when the run log is bounded
(`Simulation.run_log_window`)."""
SAMPLE_COLUMNS = ("time", "left_power", "right_power", "left_ticks", "right_ticks", "x", "y",
                  "yaw")
"""What a real Corobot's logger records."""
TELEMETRY = tuple((signal.port, signal.log) for signal in signals.TELEMETRY)
"""(robot port, its columns) of the contact telemetry, in the log's order (`signals.TELEMETRY`)."""
HELD_PERIOD = 0.1
"""s: the loads and the slip are sampled every 0.1 s (10 Hz) and held between (ZeroOrderHolds):
evaluated every 10 ms step, the loads (the plant's contact results) and the slip (the bodies'
velocities) cost well over the ~3% of a step the run log may add (the
measurement is in the commit that added this). A row's loads and slip are those of the latest
0.1 s sample; its tip margin is the step's (a few sums from the chassis pose, made when the log
is read; the run's least margin, `Robot.min_tip_margin_deg`, is read from it)."""
HELD = tuple(signal.port for signal in signals.TELEMETRY if signal.costly)
COLUMNS = SAMPLE_COLUMNS + tuple(c for _, columns in TELEMETRY for c in columns)

RAW_COLUMNS = (*DriveStatus.get_fields(), "left_ticks", "right_ticks", *CHASSIS_STATE,
               *(c for name, columns in TELEMETRY if name in HELD for c in columns))
"""What the sink records every `LOG_PERIOD` s (after its time): the drive's status, the front
encoders' counts, the chassis' state (`odometry.CHASSIS_STATE`) and the held telemetry, all
straight from C++ systems' ports (no Python call per sample). `rows_of` makes the `COLUMNS`
from them when the log is read: the heading, the tip margin and whole ticks are functions of
one sample each, so they cost nothing while the simulation runs."""


def add_run_log(builder, name: str, chassis_state_port, drive_status_port, encoder_ticks_port,
                held_ports: dict):
    """Adds `<name>.run_log_row` (a Multiplexer of `RAW_COLUMNS`: `drive_status_port`,
    `encoder_ticks_port`, `chassis_state_port` and the `held_ports`, {`HELD` port name: output
    port}, each through a hold `<name>.run_log_<port>`) and its sink `<name>.run_log`; returns
    the sink."""
    sizes = [len(DriveStatus.get_fields()), 2, len(CHASSIS_STATE),
             *(len(columns) for port_name, columns in TELEMETRY if port_name in HELD)]
    row = builder.AddNamedSystem(f"{name}.run_log_row", Multiplexer(sizes))
    for k, port in enumerate((drive_status_port, encoder_ticks_port, chassis_state_port)):
        builder.Connect(port, row.get_input_port(k))
    for k, port_name in enumerate(HELD, start=3):
        hold = builder.AddNamedSystem(f"{name}.run_log_{port_name}",
                                      ZeroOrderHold(HELD_PERIOD, len(dict(TELEMETRY)[port_name])))
        builder.Connect(held_ports[port_name], hold.get_input_port())
        builder.Connect(hold.get_output_port(), row.get_input_port(k))
    sink = LogVectorOutput(row.get_output_port(), builder, LOG_PERIOD)
    sink.set_name(f"{name}.run_log")
    return sink


def rows_of(times: np.ndarray, raw: np.ndarray, tip_margin) -> np.ndarray:
    """Run-log rows (`COLUMNS`) from the sink's sample `times` [n] and `raw` samples [n,
    `RAW_COLUMNS`]; `tip_margin`: the robot's `stability.TipMargin` (its `margin_of_up`)."""
    column = {c: raw[:, i] for i, c in enumerate(RAW_COLUMNS)}
    R = rotation_rows(raw[:, [RAW_COLUMNS.index(c) for c in CHASSIS_STATE[:4]]])
    yaw = np.arctan2(R[:, 1, 0], R[:, 0, 0])  # as `odometry.heading_of`
    margin = tip_margin.margin_of_up(R[:, 2, 0], R[:, 2, 1], R[:, 2, 2])
    held = [column[c] for port_name, columns in TELEMETRY if port_name in HELD
            for c in columns]
    return np.column_stack([times, column["power_left"], column["power_right"],
                            np.rint(column["left_ticks"]), np.rint(column["right_ticks"]),
                            column["x"], column["y"], yaw, *held, margin])


def log_rows(sink, root_context, tip_margin) -> np.ndarray:
    """The log so far as an array with the `COLUMNS` (one row per sample; `rows_of`)."""
    log = sink.FindLog(root_context)
    if not log.num_samples():
        return np.zeros((0, len(COLUMNS)))
    return rows_of(log.sample_times(), log.data().T, tip_margin)


def write_csv(rows: np.ndarray, path: str | Path) -> None:
    """Writes run-log rows (from `log_rows`) as CSV with a header line."""
    with open(path, "w") as f:
        f.write(",".join(COLUMNS) + "\n")
        for t, pl, pr, tl, tr, x, y, yaw, *telemetry in rows:
            f.write(f"{t:.6f},{pl:.6g},{pr:.6g},{int(tl)},{int(tr)},{x:.6f},{y:.6f},{yaw:.6f}")
            f.write("".join(f",{v:.6g}" for v in telemetry) + "\n")
