"""The metrics registry: named measurements of one robot at the end of a run.

A metric is one small function `(RobotRun) -> value`, registered with `@metric("name",
"unit")`. A value is a number or text (one column `<robot>.<name>`), or a dict of them (one
column per key, `<robot>.<name>.<key>`). Adding a metric is writing one such function here
(`reads_ir=True` if it reads the IR sensors, which a study's runs otherwise switch off;
`needs_seconds` if a shorter run cannot give it), or in a module of your own, named in a study
as `module:function` (`load_user_metrics`; its `unit` attribute labels its plots).
"""

from __future__ import annotations

import dataclasses as dc
import importlib
import math
import sys
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np

from corobot_drake.config.scenario import DriveDistance, RotateDegrees
from corobot_drake.readings import BodyPose
from corobot_drake.simulation import Robot, Simulation
from corobot_drake.study.programs import COMMANDS_PER_LOOP

Value = float | int | str
METRICS: dict[str, Callable[[RobotRun], Value | dict[str, Value]]] = {}


@dc.dataclass
class RobotRun:
    """One robot after a run, the argument of every metric: the simulation (at the run's
    end), the robot and where it started."""

    sim: Simulation
    """The simulation, at the run's end (`sim.time`, s)."""
    robot: Robot
    """The robot measured (one of `sim.robots`)."""
    start: BodyPose
    """The chassis pose at the start (`Robot.pose()`: world frame, m and rad)."""
    start_heading: float
    """Compass heading at the start (`Robot.heading()`), rad."""


READS_IR: set[str] = set()
"""The metrics that read the sensors (`reads_ir`, named after the first): a study's runs
scan (IR, and every other kind but the cameras) only when one is asked for."""
UNITS: dict[str, str] = {}
"""Each registered metric's unit (its values', per key for a mapping): the plots' axes."""
NEEDS_SECONDS: dict[str, float] = {}
"""The simulated s a run must last for the metric to mean anything (a study whose runs are
shorter is refused as it loads)."""


def metric(name: str, unit: str = "", reads_ir: bool = False, needs_seconds: float = 0.0):
    """Registers a metric `name` whose values are in `unit` ("" for text)."""
    def register(fn):
        METRICS[name] = fn
        UNITS[name] = unit
        if reads_ir:
            READS_IR.add(name)
        if needs_seconds:
            NEEDS_SECONDS[name] = needs_seconds
        return fn
    return register


def unit_of(column: str, names: Iterable[str], user: dict[str, Callable] | None = None) -> str:
    """The unit of a row's metric column `<robot>.<metric>[.<key>]` of one of `names` (the
    study's metrics): the registry's, or a user metric's `unit` attribute, else ""."""
    rest = column.partition(".")[2]
    for name in sorted(names, key=len, reverse=True):  # `ir` must not take `ir_x`'s column
        if rest == name or rest.startswith(name + "."):
            return UNITS.get(name) or str(getattr((user or {}).get(name), "unit", ""))
    return ""


def load_user_metrics(names: Iterable[str], directory: str | Path) -> dict[str, Callable]:
    """Each `module:function` of `names` (a study's metrics), imported: the module is looked
    for in `directory` (the study file's) first, then on Python's path. ValueError naming the
    first that does not load. A user metric is called as a registered one; it sees the IR
    sensors when the function has `reads_ir = True`."""
    functions = {}
    for name in names:
        if ":" not in name:
            continue
        module_name, _, function = name.partition(":")
        if not all(part.isidentifier() for part in module_name.split(".")) or \
                not function.isidentifier():
            raise ValueError(f"{name!r}: a user metric is module:function (e.g. "
                             "my_metrics:lateral_speed)")
        sys.path.insert(0, str(directory))
        try:
            module = importlib.import_module(module_name)
        except Exception as e:  # the user's module: any error in it is its one line
            message = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
            raise ValueError(f"{name}: cannot import {module_name!r} ({message})") from None
        finally:
            sys.path.remove(str(directory))
        fn = getattr(module, function, None)
        if not callable(fn):
            raise ValueError(f"{name}: {module_name} ({module.__file__}) has no function "
                             f"{function!r}")
        functions[name] = fn
    return functions


def reads_ir(names: Iterable[str], functions: dict[str, Callable] | None = None) -> bool:
    """Whether any of the named metrics reads the IR sensors."""
    return any(name in READS_IR or getattr((functions or {}).get(name), "reads_ir", False)
               for name in names)


@metric("x", "m")
def _x(run: RobotRun) -> float:
    """Final chassis x in the world, m."""
    return run.robot.pose().x


@metric("y", "m")
def _y(run: RobotRun) -> float:
    """Final chassis y in the world, m."""
    return run.robot.pose().y


@metric("yaw_deg", "deg")
def _yaw_deg(run: RobotRun) -> float:
    """Final heading, degrees in (-180, 180]."""
    return math.degrees(run.robot.pose().yaw)


@metric("distance_from_start", "m")
def _distance_from_start(run: RobotRun) -> float:
    """Straight-line distance from the start position, m."""
    p = run.robot.pose()
    return math.hypot(p.x - run.start.x, p.y - run.start.y)


@metric("speed", "m/s")
def _speed(run: RobotRun) -> float:
    """Final forward speed, m/s."""
    return run.robot.velocity().forward


@metric("yaw_rate", "rad/s")
def _yaw_rate(run: RobotRun) -> float:
    """Final yaw rate, rad/s."""
    return run.robot.velocity().yaw_rate


WINDOW = 1.0
"""s: the window of the `steady_*` metrics, the run's last second."""


@metric("steady_speed", "m/s", needs_seconds=WINDOW)
def _steady_speed(run: RobotRun) -> float:
    """Mean forward speed over the run's last `WINDOW` s (the displacement along the mean
    heading over the window's length), m/s: a steady speed without a sample's noise."""
    rows = _window(run)
    yaw = np.unwrap(rows[:, 7])
    heading = 0.5 * (yaw[0] + yaw[-1])
    dx, dy = rows[-1, 5:7] - rows[0, 5:7]
    return float(dx * math.cos(heading) + dy * math.sin(heading)) / _span(rows)


@metric("steady_yaw_rate", "rad/s", needs_seconds=WINDOW)
def _steady_yaw_rate(run: RobotRun) -> float:
    """Mean yaw rate over the run's last `WINDOW` s, rad/s (the heading unwrapped sample to
    sample: any number of turns)."""
    rows = _window(run)
    yaw = np.unwrap(rows[:, 7])
    return float(yaw[-1] - yaw[0]) / _span(rows)


def _window(run: RobotRun):
    """The run-log rows of the run's last `WINDOW` s."""
    log = run.robot.run_log()
    rows = log[log[:, 0] >= log[-1, 0] - WINDOW - 1e-9]
    if _span(rows) < 0.5 * WINDOW:
        raise ValueError(f"the run is shorter than the {WINDOW:g} s the steady metrics average")
    return rows


def _span(rows) -> float:
    return float(rows[-1, 0] - rows[0, 0])


@metric("max_tilt_deg", "deg")
def _max_tilt_deg(run: RobotRun) -> float:
    """Largest tilt from upright during the run, degrees."""
    return run.robot.max_tilt_deg()


@metric("ir", "m", reads_ir=True)
def _ir(run: RobotRun) -> dict[str, float]:
    """Final raw reading of each IR sensor, m."""
    return run.robot.ir_distances()


@metric("sensors", reads_ir=True)
def _sensors(run: RobotRun) -> dict[str, Value]:
    """Final reading of every sensor of every kind, by kind and name: one column per number
    or text of its summary JSON (`Robot.sensor_readings`), `<kind>.<sensor>.<field>` (e.g.
    `ir_sensors.rear.raw`, m; a yes or no as 1 or 0); lists and empty values left out. A
    metric of your own reads one sensor by name: `run.robot.reading("rear")`."""
    return {f"{kind}.{name}.{field}": int(value) if isinstance(value, bool) else value
            for kind, named in run.robot.sensor_readings(summary=True).items()
            for name, reading in named.items()
            for field, value in reading.items()
            if isinstance(value, int | float | str)}


@metric("wheel_loads", "N")
def _wheel_loads(run: RobotRun) -> dict[str, float]:
    """Final load on each wheel (N, vertical contact force), by wheel name."""
    return run.robot.wheel_loads()


@metric("wheel_slip", "ratio")
def _wheel_slip(run: RobotRun) -> dict[str, float]:
    """Final longitudinal slip ratio of each wheel ((rim - ground speed) / the faster, +
    traction, `systems.contact`), by wheel name."""
    return run.robot.wheel_slip_ratio()


@metric("wheel_slip_angle", "deg")
def _wheel_slip_angle(run: RobotRun) -> dict[str, float]:
    """Final slip angle of each wheel, deg (+ moving to the left of the heading), by wheel
    name."""
    return run.robot.wheel_slip_angle()


@metric("min_tip_margin_deg", "deg")
def _min_tip_margin_deg(run: RobotRun) -> float:
    """Least tip-over margin during the run, deg (`systems.stability`; from the run log)."""
    return run.robot.min_tip_margin_deg()


@metric("odometry_error", "m")
def _odometry_error(run: RobotRun) -> float:
    """Final distance of the dead-reckoned position (`Robot.odometry()`) from the true one, m."""
    odometry, pose = run.robot.odometry(), run.robot.pose()
    return math.hypot(odometry.x - pose.x, odometry.y - pose.y)


@metric("command_status")
def _command_status(run: RobotRun) -> dict[str, str]:
    """Each command's final status (`succeeded`, `running`, `failed:<reason>`), by index."""
    return {str(i): r.status + (f":{r.reason}" if r.reason else "")
            for i, r in enumerate(run.robot.command_log())}


@metric("command_duration", "s")
def _command_duration(run: RobotRun) -> dict[str, float]:
    """Each ended command's duration, simulated s (NaN while running), by index."""
    return {str(i): (r.end_time - r.start_time) if r.end_time is not None else math.nan
            for i, r in enumerate(run.robot.command_log())}


@metric("landing_error", "mm (drive) or deg (rotate)")
def _landing_error(run: RobotRun) -> dict[str, float]:
    """Each DriveDistance's (mm) and RotateDegrees' (deg) landing error, by command index:
    measured from the run log at the command's start and at the run's end, so a study with
    `until: commands` and `settle` measures the robot at rest. A run with one such command
    measures exactly the book's landing; with several, each is measured to the next's start."""
    log = run.robot.run_log()
    records = run.robot.command_log()
    script = run.sim.scenario.robots[run.robot.name].commands
    starts = [r.start_time for r in records] + [math.inf]
    out = {}
    for i, (r, command) in enumerate(zip(records, script, strict=False)):
        if not isinstance(command, DriveDistance | RotateDegrees):
            continue
        a, b = _row_at(log, r.start_time), _row_at(log, starts[i + 1])
        if isinstance(command, DriveDistance):
            travelled = math.hypot(b[5] - a[5], b[6] - a[6])
            out[str(i)] = (travelled - abs(command.distance)) * 1000.0
        else:
            turned = b[7] - a[7] - math.radians(command.degrees)
            out[str(i)] = math.degrees(math.remainder(turned, 2 * math.pi))
    return out


@metric("drive_test_drift", "mm")
def _drive_test_drift(run: RobotRun) -> dict[str, float]:
    """The drive test's drift (a study with `drive_test`): mm from the start position when each
    loop's last command ended, by loop (1, 2, ...); NaN for a loop that did not end."""
    return {str(k): 1000.0 * math.hypot(row[5] - run.start.x, row[6] - run.start.y)
            if row is not None else math.nan for k, row in _loop_ends(run)}


@metric("drive_test_heading_error", "deg")
def _drive_test_heading_error(run: RobotRun) -> dict[str, float]:
    """The drive test's heading error (deg, wrapped) when each loop's last command ended."""
    return {str(k): math.degrees(math.remainder(row[7] - run.start_heading, 2 * math.pi))
            if row is not None else math.nan for k, row in _loop_ends(run)}


def _loop_ends(run: RobotRun):
    """(loop number, run-log row when the loop's last command ended, or None)."""
    log, records = run.robot.run_log(), run.robot.command_log()
    loops = len(run.sim.scenario.robots[run.robot.name].commands) // COMMANDS_PER_LOOP
    for k in range(1, loops + 1):
        i = k * COMMANDS_PER_LOOP - 1
        ended = i < len(records) and records[i].end_time is not None
        yield k, _row_at(log, records[i].end_time) if ended else None


def _row_at(log, t: float):
    """The last run-log row at or before time t (the last row for t = inf)."""
    times = log[:, 0]
    index = max(0, int((times <= t + 1e-9).sum()) - 1)
    return log[index]


def measure(sim: Simulation, starts: dict[str, tuple[BodyPose, float]],
            names: list[str], user: dict[str, Callable] | None = None) -> dict[str, Value]:
    """The named metrics of every robot (`user`: the study's own, `load_user_metrics`), as
    flat columns `<robot>.<metric>[.<key>]`."""
    row: dict[str, Value] = {}
    functions = {**METRICS, **(user or {})}
    for robot_name, robot in sim.robots.items():
        start, heading = starts[robot_name]
        run = RobotRun(sim, robot, start, heading)
        for name in names:
            value = functions[name](run)
            if isinstance(value, dict):
                row.update({f"{robot_name}.{name}.{k}": v for k, v in value.items()})
            else:
                row[f"{robot_name}.{name}"] = value
    return row
