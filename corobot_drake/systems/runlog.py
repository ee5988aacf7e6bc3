"""The run log: what a real Corobot's logger records, sampled from the simulation.

Each robot of a station carries a Drake `VectorLogSink` (`<robot>.run_log`) that samples its
signals every `LOG_PERIOD` s (`RAW_COLUMNS`, straight from C++ systems' ports: no Python call
per sample); `log_rows` turns them into the columns below when the log is read. The log lives
in the Context, like the rest of the run. `write_csv` writes it in the CSV format that
`corobot_drake.tuning.sysid` reads (columns documented in docs/tuning.md), then the
simulation's contact telemetry, which no real logger has:

    time,left_power,right_power,left_ticks,right_ticks,x,y,yaw,
    load_fl,load_fr,load_rl,load_rr,slip_ratio_fl,...,slip_angle_fl,...,tip_margin,
    ir_front,ir_rear,... (its sensors')

- time: s. left_power, right_power: the drive's commanded power per side in [-1, 1].
- left_ticks, right_ticks: front-left / front-right encoder counts, the robot's
  `encoder_ticks_per_revolution` (the Corobot's 600) per wheel revolution, floor(600 q / 2 pi)
  of the integrated wheel angle q (forward rolling counts up): the odometry's encoders
  (`odometry.add_wheel_encoders`).
- x, y: chassis position in the world, m. yaw: chassis heading about world z, rad, in (-pi, pi].
- load_*, slip_ratio_*, slip_angle_*: per wheel (the Corobot's fl front left, fr, rl, rr;
  any robot's `signals.wheel_short`, in its wheel order: its `Layout`), N,
  dimensionless (+ traction), deg (+ to the left): `contact.WheelContacts`, sampled every
  `HELD_PERIOD` (0.1 s) and held (a row shows the latest sample before it). On a continuous
  plant they are made when the log is read (`ContactSamples`), from the plant's state sampled
  at those times: nothing evaluates them while the simulation runs. tip_margin: deg,
  `stability.TipMargin` of the row's chassis pose (computed when the log is read, as the yaw
  is).

Then the columns of each of the robot's sensors, kind by kind (`SensorKind.log_columns`;
`Layout.sensor_columns`), sampled every row from the rows of its `SensorKind.log_port` (a
state output port) that a C++ `MatrixGain` picks: no Python call per sample. The Corobot's
IR sensors give `ir_front`, `ir_rear` (m, the latest scan's distance); a bumper
`bumper_<name>_pressed` (1 or 0) and `bumper_<name>_force` (N); an IMU `imu_<name>_wx`, `_wy`,
`_wz` (rad/s) and `_ax`, `_ay`, `_az` (m/s^2), in its frame.

The run's largest tilt from upright (`max_tilt_deg`) is read from the same samples' chassis
state, so nothing samples the chassis a second time while the simulation runs.
"""

import dataclasses as dc
import functools
import math
from pathlib import Path

import numpy as np
from pydrake.systems.primitives import LogVectorOutput, MatrixGain, Multiplexer, ZeroOrderHold

from corobot_drake import signals
from corobot_drake.systems.contact import held_velocity_name
from corobot_drake.systems.drive import DriveStatus
from corobot_drake.systems.odometry import CHASSIS_STATE, rotation_rows

LOG_PERIOD = 0.01
"""s: the run log's sample period (100 Hz: tilt changes over tenths of a second even in a flip,
so the largest tilt's samples catch its peak)."""
RUN_LOG_CHUNK = 1000
"""Samples (10 s at 100 Hz) moved out of the sink at a time when the run log is bounded
(`Simulation.run_log_window`)."""
HELD_PERIOD = 0.1
"""s: the loads and the slip are sampled every 0.1 s (10 Hz) and held between: evaluated every
10 ms step, the loads (the plant's contact results) and the slip (the bodies' velocities) cost
well over the ~3% of a step the run log may add. On a discrete plant ZeroOrderHolds sample
them; on a continuous one the plant's state is kept at those times and they are made from it
when the log is read (`ContactSamples`). A row's loads and slip are those of the latest 0.1 s
sample; its tip margin is the step's (a few sums from the chassis pose, made when the log is
read; the run's least margin, `Robot.min_tip_margin_deg`, is read from it)."""
MADE_WHEN_READ = ("commanded_power", "encoders", "pose", "tip_margin")
"""The signals whose columns `rows_of` makes from the drive status, the encoders' counts and
the chassis state when the log is read (`_made_when_read`); every other signal with run-log
columns is sampled from its port."""
for _spec in signals.SIGNALS.values():
    if _spec.log and _spec.name not in MADE_WHEN_READ and not _spec.system:
        raise ValueError(f"signal {_spec.name!r} has run-log columns but no system to sample")


@dc.dataclass(frozen=True)
class Layout:
    """One robot's run-log columns, from its signals (`signals.robot_signals`: the per-wheel
    columns are its wheels'). The module's constants are the Corobot's (`LAYOUT`)."""

    signals: dict = dc.field(hash=False, compare=False)
    """{name: `signals.Signal`}, the robot's, in the table's order."""
    sampled: tuple
    """(robot port, its columns) of the signals sampled from their ports, in the table's
    order."""
    held: tuple
    """The sampled ports held (`HELD_PERIOD`): costly to evaluate every sample."""
    held_columns: tuple
    """The run-log columns of the `held` ports."""
    columns: tuple
    """The run log's columns: time, then each signal's (`signals.Signal.log`), in the
    table's order."""
    formats: tuple
    """The CSV format of each column."""
    raw_columns: tuple
    """What the sink records every `LOG_PERIOD` s (`RAW_COLUMNS`)."""
    sensor_columns: tuple = ()
    """The robot's sensors' columns (`sensor_log`), after the signals' in `columns` and
    last in `raw_columns`."""

    def sink_columns(self, held_when_read: bool) -> tuple[str, ...]:
        """The sink's columns: `raw_columns`, less the `held_columns` when they are made
        when the log is read (`ContactSamples`)."""
        return tuple(c for c in self.raw_columns
                     if not (held_when_read and c in self.held_columns))


@functools.cache
def layout(wheel_names: tuple[str, ...] = signals.WHEEL_NAMES,
           encoded: tuple[str, str] = signals.CODED,
           sensor_columns: tuple[str, ...] = ()) -> Layout:
    """The run-log `Layout` of a robot whose wheels are `wheel_names` with encoders on
    `encoded` (`signals.robot_signals`) and whose sensors log `sensor_columns` (`sensor_log`);
    the defaults: the Corobot's without sensors."""
    table = signals.robot_signals(wheel_names, encoded)
    sampled = tuple((s.port, s.log_columns) for s in table.values()
                    if s.log and s.name not in MADE_WHEN_READ)
    held = tuple(s.port for s in table.values()
                 if s.log and s.name not in MADE_WHEN_READ and s.costly)
    return Layout(
        signals=table, sampled=sampled, held=held,
        held_columns=tuple(c for port, columns in sampled if port in held for c in columns),
        columns=("time", *(c for s in table.values() for c in s.log_columns),
                 *sensor_columns),
        formats=(".6f", *(s.log_format for s in table.values() for _ in s.log),
                 *(".6f" for _ in sensor_columns)),
        raw_columns=(*DriveStatus.get_fields(), "left_ticks", "right_ticks", *CHASSIS_STATE,
                     *(c for _, columns in sampled for c in columns), *sensor_columns),
        sensor_columns=tuple(sensor_columns))


def sensor_log(sensors: dict | None) -> list[tuple[tuple[str, ...], object]]:
    """(columns, `BuiltSensor`) of each sensor with run-log columns
    (`SensorKind.log_columns`), from {kind field: {name: BuiltSensor}} (a robot's built
    sensors), kind by kind in their order."""
    return [(columns, s) for by_name in (sensors or {}).values() for s in by_name.values()
            if (columns := s.kind.log_columns(s.name))]


def spec_layout(spec, sensors: dict | None = None) -> Layout:
    """The run-log `Layout` of a `robots.RobotSpec` whose built sensors are `sensors`
    ({kind field: {name: BuiltSensor}}; None: none logged)."""
    left, right = spec.encoded
    return layout(spec.wheel_names, (spec.wheel_names[left], spec.wheel_names[right]),
                  tuple(c for columns, _ in sensor_log(sensors) for c in columns))


LAYOUT = layout()
"""The Corobot's run-log layout."""
SAMPLED = LAYOUT.sampled
"""(robot port, its columns) of the signals sampled from their ports, in the table's order."""
HELD = LAYOUT.held
"""The sampled ports held (`HELD_PERIOD`): costly to evaluate every sample."""
HELD_COLUMNS = LAYOUT.held_columns
"""The run-log columns of the `HELD` ports."""
COLUMNS = LAYOUT.columns
"""The run log's columns: time, then each signal's (`signals.Signal.log`), in the table's
order."""
FORMATS = LAYOUT.formats
"""The CSV format of each column."""

RAW_COLUMNS = LAYOUT.raw_columns
"""What the sink records every `LOG_PERIOD` s (after its time): the drive's status, the front
encoders' counts, the chassis' state (`odometry.CHASSIS_STATE`) and the sampled ports (the
held ones through their holds), all straight from C++ systems' ports (no Python call per
sample). `rows_of` makes the `COLUMNS` from them when the log is read: the heading, the tip
margin and whole ticks are functions of one sample each, so they cost nothing while the
simulation runs. With `ContactSamples` (a continuous plant) the sink records the columns up to
the `HELD_COLUMNS` (`raw_columns`). The chassis' columns are at the same places in every
robot's."""


def raw_columns(held_when_read: bool, layout: Layout = LAYOUT) -> tuple[str, ...]:
    """The sink's columns: `RAW_COLUMNS`, less the `HELD_COLUMNS` when they are made when the
    log is read (`ContactSamples`)."""
    return layout.sink_columns(held_when_read)


CONTACT_STATES = "run_log_contact_states"
"""The station's sink of [the plant's state; each robot's held chassis velocity] every
`HELD_PERIOD` s on a continuous plant (`add_contact_states`, `ContactSamples`)."""


def add_run_log(builder, name: str, chassis_state_port, drive_status_port, encoder_ticks_port,
                sampled_ports: dict, held_when_read: bool = False, layout: Layout = LAYOUT,
                sensors: dict | None = None):
    """Adds `<name>.run_log_row` (a Multiplexer of `raw_columns`: `drive_status_port`,
    `encoder_ticks_port`, `chassis_state_port` and the `sampled_ports`, {`SAMPLED` port name:
    output port}, the `HELD` ones each through a hold `<name>.run_log_<port>`) and its sink
    `<name>.run_log`; returns the sink. With `held_when_read` (a continuous plant, whose
    station has `add_contact_states`) the `HELD` ports are not sampled: their columns are made
    when the log is read (`ContactSamples`). `layout`: the robot's (the Corobot's);
    `sensors`: its built sensors ({kind field: {name: BuiltSensor}}), whose
    `layout.sensor_columns` are sampled last, each sensor's rows of its `log_port` picked by a
    C++ gain `<name>.run_log_<kind field>_<sensor>` (no Python call per sample)."""
    held = layout.held
    sampled = [(port, columns) for port, columns in layout.sampled
               if not (held_when_read and port in held)]
    logged = sensor_log(sensors)
    if tuple(c for columns, _ in logged for c in columns) != layout.sensor_columns:
        raise ValueError(f"run log {name}: the sensors' columns are not the layout's "
                         f"{layout.sensor_columns}")
    sizes = [len(DriveStatus.get_fields()), 2, len(CHASSIS_STATE),
             *(len(columns) for _, columns in sampled), *(len(c) for c, _ in logged)]
    row = builder.AddNamedSystem(f"{name}.run_log_row", Multiplexer(sizes))
    for k, port in enumerate((drive_status_port, encoder_ticks_port, chassis_state_port)):
        builder.Connect(port, row.get_input_port(k))
    for k, (port_name, columns) in enumerate(sampled, start=3):
        source = sampled_ports[port_name]
        if port_name in held:
            hold = builder.AddNamedSystem(f"{name}.run_log_{port_name}",
                                          ZeroOrderHold(HELD_PERIOD, len(columns)))
            builder.Connect(source, hold.get_input_port())
            source = hold.get_output_port()
        builder.Connect(source, row.get_input_port(k))
    for k, (columns, sensor) in enumerate(logged, start=3 + len(sampled)):
        port, rows = sensor.kind.log_port(sensor)
        pick = np.zeros((len(columns), port.size()))
        pick[range(len(columns)), rows] = 1.0
        gain = builder.AddNamedSystem(f"{name}.run_log_{sensor.kind.field}_{sensor.name}",
                                      MatrixGain(pick))
        builder.Connect(port, gain.get_input_port())
        builder.Connect(gain.get_output_port(), row.get_input_port(k))
    sink = LogVectorOutput(row.get_output_port(), builder, LOG_PERIOD)
    sink.set_name(f"{name}.run_log")
    return sink


def add_contact_states(builder, plant, robots):
    """Adds the `CONTACT_STATES` sink (and its Multiplexer `run_log_contact_state`): the plant's
    state and each robot's held chassis velocity (`contact.held_velocity_name`; `robots`' names
    in order), what their contact telemetry is a function of on a continuous plant, every
    `HELD_PERIOD` s. Its publishes fall where the holds' updates would (k x `HELD_PERIOD`), so
    the simulator stops at the same times either way. Returns the sink."""
    held_velocity_ports = [builder.GetSubsystemByName(held_velocity_name(name))
                           .get_output_port() for name in robots]
    state = builder.AddNamedSystem("run_log_contact_state", Multiplexer(
        [plant.num_multibody_states(), *(port.size() for port in held_velocity_ports)]))
    builder.Connect(plant.get_state_output_port(), state.get_input_port(0))
    for k, port in enumerate(held_velocity_ports, start=1):
        builder.Connect(port, state.get_input_port(k))
    sink = LogVectorOutput(state.get_output_port(), builder, HELD_PERIOD)
    sink.set_name(CONTACT_STATES)
    return sink


class ContactSamples:
    """Makes the robots' `HELD_COLUMNS` when their run logs are read, on a continuous plant:
    each sample of the `CONTACT_STATES` sink is set into a scratch Context (the root's state,
    time and parameters copied in) and each robot's `WheelContacts` ports are evaluated there:
    what holds sampling them live would have held, to the bit, and nothing is evaluated while
    the simulation runs. A sample is taken at the end of the step at its time, so a change
    made between advances at that very time (a teleport) shows from the next sample on.

    Each sample's columns are made once, in a scratch Context made at the first read (about
    10 MB with the default scene) and kept. With the run log's chunks (`Simulation`), the
    columns of the last sample moved out of the sink are kept here (`moved_out`): what rows
    after it show until the next sample."""

    def __init__(self, diagram, plant, robots, layouts: dict | None = None):
        """`robots`: their names; `layouts`: {name: its `Layout`} (default the Corobot's)."""
        layouts = {name: (layouts or {}).get(name, LAYOUT) for name in robots}
        self.sink = diagram.GetSubsystemByName(CONTACT_STATES)
        self._diagram, self._plant = diagram, plant
        self._holds = [diagram.GetSubsystemByName(held_velocity_name(name)) for name in robots]
        self._ports = {name: [diagram.GetSubsystemByName(f"{name}.wheel_contacts")
                              .GetOutputPort(port) for port in HELD] for name in robots}
        self._scratch = None
        self._made: dict[str, list] = {name: [] for name in robots}
        """Each robot's columns of the sink's first samples, made so far."""
        self._sizes = {name: len(layouts[name].held_columns) for name in robots}
        self._before = {name: np.zeros(self._sizes[name]) for name in robots}
        """Each robot's columns of rows before the sink's first sample: the holds' initial
        values, or the last sample moved out."""

    def columns(self, name: str, root_context, times: np.ndarray) -> np.ndarray:
        """[len(times), `HELD_COLUMNS`] of robot `name`: at each row time (s), the latest
        sample before it."""
        log = self.sink.FindLog(root_context)
        sample_times = log.sample_times()
        made = self._made[name]
        if len(made) < len(sample_times):
            self._make(root_context, sample_times, log.data())
        table = np.vstack([self._before[name], *made[:len(sample_times)]])
        return table[np.searchsorted(sample_times, times, side="left")]

    def _make(self, root_context, sample_times, data) -> None:
        """Makes every robot's columns of the samples not made yet."""
        if self._scratch is None:
            self._scratch = self._diagram.CreateDefaultContext()
        scratch = self._scratch
        scratch.SetTimeStateAndParametersFrom(root_context)
        plant_context = self._plant.GetMyMutableContextFromRoot(scratch)
        # Each hold's rows of a sample: after the plant's state, in the robots' order.
        start, holds = self._plant.num_multibody_states(), []
        for hold in self._holds:
            size = hold.get_output_port().size()
            holds.append((hold.GetMyMutableContextFromRoot(scratch), slice(start, start + size)))
            start += size
        states = self._plant.num_multibody_states()
        for j in range(len(next(iter(self._made.values()))), len(sample_times)):
            scratch.SetTime(sample_times[j])
            self._plant.SetPositionsAndVelocities(plant_context, data[:states, j])
            for hold_context, rows in holds:
                hold_context.SetDiscreteState(data[rows, j])
            for name, ports in self._ports.items():
                self._made[name].append(np.concatenate([
                    port.Eval(port.get_system().GetMyContextFromRoot(scratch))
                    for port in ports]))

    def moved_out(self, root_context) -> None:
        """The sink's samples are about to be cleared: later rows start from its last one."""
        log = self.sink.FindLog(root_context)
        if log.num_samples():
            self._make(root_context, log.sample_times(), log.data())
            self._before = {name: made[log.num_samples() - 1]
                            for name, made in self._made.items()}
        self._made = {name: [] for name in self._made}

    def clear(self) -> None:
        """The sink was cleared for a run from the start."""
        self._made = {name: [] for name in self._made}
        self._before = {name: np.zeros(self._sizes[name]) for name in self._made}


def rows_of(times: np.ndarray, raw: np.ndarray, tip_margin, held=None,
            layout: Layout = LAYOUT) -> np.ndarray:
    """Run-log rows (`layout.columns`) from the sink's sample `times` [n] and `raw` samples
    [n, `raw_columns`]; `tip_margin`: the robot's `stability.TipMargin` (its `margin_of_up`);
    `held`: [n, `HELD_COLUMNS`] when the sink has none (`ContactSamples.columns`)."""
    column = {c: raw[:, i] for i, c in enumerate(layout.sink_columns(held is not None))}
    if held is not None:
        column.update((c, held[:, i]) for i, c in enumerate(layout.held_columns))
    made = _made_when_read(column, tip_margin, layout.signals["encoders"].keys)
    out = [times]
    for spec in layout.signals.values():
        values = made.get(spec.name)
        out += [values[key] if values is not None else column[c] for c, key in spec.log]
    out += [column[c] for c in layout.sensor_columns]
    return np.column_stack(out)


def tip_margins(raw: np.ndarray, tip_margin) -> np.ndarray:
    """deg: the tip margin (`stability.TipMargin`) of each raw sample's chassis."""
    return _margins(rotation_rows(raw[:, [RAW_COLUMNS.index(c) for c in CHASSIS_STATE[:4]]]),
                    tip_margin)


def _margins(R: np.ndarray, tip_margin) -> np.ndarray:
    """deg: the tip margin of each chassis rotation R [n, 3, 3] (from its last row: the world's
    up in the chassis frame)."""
    return tip_margin.margin_of_up(R[:, 2, 0], R[:, 2, 1], R[:, 2, 2])


def _made_when_read(column: dict, tip_margin, encoded=signals.CODED) -> dict:
    """{signal name: {key: column}} of the `MADE_WHEN_READ` signals, from the raw columns
    (`encoded`: the wheels with an encoder, left and right, whose keys the per-side columns
    have)."""
    R = rotation_rows(np.column_stack([column[c] for c in CHASSIS_STATE[:4]]))
    left, right = column["power_left"], column["power_right"]
    left_wheel, right_wheel = encoded
    return {
        "commanded_power": {left_wheel: left, right_wheel: right},
        "encoders": {left_wheel: np.rint(column["left_ticks"]),
                     right_wheel: np.rint(column["right_ticks"])},
        "pose": {"x": column["x"], "y": column["y"],
                 "yaw": np.arctan2(R[:, 1, 0], R[:, 0, 0])},  # as `odometry.heading_of`
        "tip_margin": {"": _margins(R, tip_margin)},
    }


def max_tilt_deg(raw: np.ndarray) -> float:
    """deg: the largest tilt from upright of the chassis over raw samples [n, `RAW_COLUMNS`]
    (0 without any): the angle between the chassis' +z and the world's, from each sample's
    quaternion normalized (a continuous plant's drifts off unit norm). R[2, 2] is
    1 - 2 (x^2 + y^2) of the unit quaternion; the largest tilt is the smallest R[2, 2]."""
    if not len(raw):
        return 0.0
    qw, qx, qy, qz = (raw[:, RAW_COLUMNS.index(c)] for c in CHASSIS_STATE[:4])
    cos_tilt = 1.0 - 2.0 * (qx * qx + qy * qy) / (qw * qw + qx * qx + qy * qy + qz * qz)
    return math.degrees(math.acos(min(1.0, max(-1.0, float(cos_tilt.min())))))


def log_rows(sink, root_context, tip_margin, contact_samples=None,
             name: str = "", layout: Layout = LAYOUT) -> np.ndarray:
    """The log so far as an array with the `layout.columns` (one row per sample; `rows_of`),
    its `HELD_COLUMNS` from `contact_samples` (a `ContactSamples`, robot `name`) when the sink
    has none."""
    log = sink.FindLog(root_context)
    if not log.num_samples():
        return np.zeros((0, len(layout.columns)))
    if (contact_samples is None) != (log.data().shape[0] == len(layout.raw_columns)):
        raise ValueError(f"run log {sink.get_name()}: its held columns are "
                         f"{'made when read' if contact_samples is None else 'sampled'}: "
                         f"{'pass' if contact_samples is None else 'pass no'} ContactSamples")
    times = log.sample_times()
    held = (None if contact_samples is None
            else contact_samples.columns(name, root_context, times))
    return rows_of(times, log.data().T, tip_margin, held, layout)


def write_csv(rows: np.ndarray, path: str | Path, layout: Layout = LAYOUT) -> None:
    """Writes run-log rows (from `log_rows`) as CSV with a header line (each column in its
    `FORMATS`; `layout`: the robot's)."""
    formats = [(lambda v: str(int(v))) if f == "d" else (lambda v, f=f: format(v, f))
               for f in layout.formats]
    with open(path, "w") as out:
        out.write(",".join(layout.columns) + "\n")
        for row in rows:
            out.write(",".join(f(v) for f, v in zip(formats, row, strict=True)) + "\n")
