"""System identification of the drive from a run log (CSV), by least squares.

The drive model: each side's axle speed command moves toward
power x MotorTorqueScaling at no more than the slew limit (rad/s^2), and the wheels follow it.
`fit_drive` finds MotorTorqueScaling S, the slew limit L and a small time offset tau (the
controller's frame and the servo's lag) that make the modelled front-wheel speeds match the ones
measured by the encoders, by least squares on the speed residuals (scipy's `least_squares`,
the [study] extra's), started from a coarse grid.

The CSV is what `Robot.write_log` / `python -m corobot_drake --log` write, or what a real
robot's logger writes with the same header (docs/tuning.md):
time, left_power, right_power, left_ticks, right_ticks[, x, y, yaw, anything else].
"""

import contextlib
import csv
import dataclasses as dc
import math
import os
import tempfile
from pathlib import Path

import numpy as np

from corobot_drake.config.scenario import ScenarioError, load_scenario, one_line, read_text
from corobot_drake.names import unknown_robot
from corobot_drake.robots import corobot

MAX_LOG_BYTES = 64 << 20
"""The largest log read (64 MiB: an hour of the simulator's 100 Hz run log is 360k lines);
larger is refused unread."""
REQUIRED = ("time", "left_power", "right_power", "left_ticks", "right_ticks")


class LogError(ValueError):
    """A log that cannot be used; the message names the file and line."""


@dc.dataclass
class DriveLog:
    """A run log: time (s), power [n, 2] (left, right), wheel angle [n, 2] (rad, from ticks)."""

    time: np.ndarray
    power: np.ndarray
    angle: np.ndarray
    source: str = ""
    position: np.ndarray | None = None
    """[n, 2] chassis x, y (m) when the log has ground truth, else None."""


def read_columns(path: str | Path, required: tuple[str, ...]) -> np.ndarray:
    """The `required` columns of a CSV log with a header line, as an array [n, len(required)]
    (time first, increasing); raises LogError naming the line of the first problem."""
    path = Path(path)
    try:
        text = read_text(path, kind="a log is a CSV file", max_bytes=MAX_LOG_BYTES)
    except ScenarioError as e:  # not a regular file, unreadable, too large, not UTF-8
        where = f"{e.source}:{e.line}" if e.line else e.source
        raise LogError(f"{where}: {e.message}") from None
    rows = list(csv.reader(text.splitlines()))
    if not rows:
        raise LogError(f"{path}:1: empty file; expected a header line "
                       f"({', '.join(required)}, ...)")
    header = [h.strip() for h in rows[0]]
    missing = [c for c in required if c not in header]
    if missing:
        raise LogError(f"{path}:1: header lacks column(s) {', '.join(missing)}; "
                       f"expected {', '.join(required)} (got {', '.join(header)})")
    index = [header.index(c) for c in required]
    data = []
    previous_time = -math.inf
    for line, row in enumerate(rows[1:], start=2):
        if not row or all(not f.strip() for f in row):
            continue  # blank line
        if len(row) != len(header):
            raise LogError(f"{path}:{line}: expected {len(header)} fields like the header, "
                           f"got {len(row)}")
        values = []
        for column, i in zip(required, index, strict=True):
            try:
                value = float(row[i])
            except ValueError:
                raise LogError(f"{path}:{line}: {column} is not a number: {row[i]!r}") from None
            if not math.isfinite(value):
                raise LogError(f"{path}:{line}: {column} is not finite: {row[i]!r}")
            values.append(value)
        if values[0] <= previous_time:
            raise LogError(f"{path}:{line}: time {values[0]:g} does not increase "
                           f"(previous {previous_time:g})")
        for column, value in zip(required, values, strict=True):
            if column.endswith("_power") and abs(value) > 1 + 1e-9:
                raise LogError(f"{path}:{line}: power must be in [-1, 1], got "
                               f"{column} {value:g}")
        previous_time = values[0]
        data.append(values)
    if len(data) < 10:
        raise LogError(f"{path}:{len(rows)}: only {len(data)} samples; a fit needs at least 10")
    return np.array(data)


def scenario_robot(scenario_path, robot: str | None = None):
    """(name, `robots.RobotSpec`) of the robot `robot` of a scenario file, or of its only
    robot; ScenarioError (one line) when there is no such robot or it is not named among
    several."""
    from corobot_drake.robots import robot_spec

    robots = load_scenario(scenario_path).robots
    if robot is None and len(robots) == 1:
        robot = next(iter(robots))
    if robot not in robots:
        raise ScenarioError(str(scenario_path), "robots", f"name a robot with --robot "
                            f"(robots: {', '.join(robots)})")
    return robot, robot_spec(robots[robot].robot)


def read_log(path: str | Path, ticks_per_revolution: int = corobot.drive(
             "encoder_ticks_per_revolution")) -> DriveLog:
    """Reads and checks a run-log CSV; raises LogError naming the line of the first problem.
    The chassis pose (x, y: m) is kept when the log has it (`DriveLog.position`)."""
    a = read_columns(path, REQUIRED)
    log = DriveLog(time=a[:, 0], power=a[:, 1:3],
                   angle=a[:, 3:5] * (2 * math.pi / ticks_per_revolution), source=str(path))
    with contextlib.suppress(LogError):  # encoders only: a robot without ground truth
        log.position = read_columns(path, ("time", "x", "y"))[:, 1:]
    return log


def _central_speed(t: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Speed at the interior samples by central differences (rad/s), [n - 2, 2]."""
    return (angle[2:] - angle[:-2]) / (t[2:] - t[:-2])[:, None]


def model_angle(log: DriveLog, scaling: float, slew: float, delay: float,
                substeps: int = 4) -> np.ndarray:
    """Modelled wheel angle [n, 2] at the log's times: rate-limited power x scaling, delayed.

    The power is held from each sample to the next (zero-order hold); the limiter is integrated
    on a grid `substeps` times finer than the log."""
    t = log.time
    n = len(t)
    frac = np.arange(substeps) / substeps
    dts = np.repeat(np.diff(t) / substeps, substeps)
    grid = np.append((t[:-1, None] + np.diff(t)[:, None] * frac[None, :]).ravel(), t[-1])
    held = np.clip(np.searchsorted(t, grid[:-1], side="right") - 1, 0, n - 1)
    out = np.empty_like(log.angle)
    for side in (0, 1):
        targets = (log.power[held, side] * scaling).tolist()
        steps = (dts * slew).tolist()
        w = 0.0
        speeds = []
        for target, step in zip(targets, steps, strict=True):
            w += min(step, max(-step, target - w))
            speeds.append(w)
        theta = np.concatenate([[0.0], np.cumsum(np.array(speeds) * dts)])
        # The wheels follow the command `delay` s late: smooth in the delay (linear interp.).
        out[:, side] = log.angle[0, side] + np.interp(t - delay, grid, theta, left=0.0)
    return out


@dc.dataclass
class DriveFit:
    """The fitted drive parameters and how well they explain the log."""

    motor_torque_scaling: float
    slew_rate: float
    delay: float
    residual_rms: float
    """rad/s: RMS of measured minus modelled front-wheel speed."""
    stderr: tuple[float, float, float]
    """Approximate standard errors of (scaling, slew, delay): the Gauss-Newton covariance at the
    solution (the Jacobian's J^T J), scaled by the residuals' variance."""
    samples: int
    iterations: int
    """Iterations of the least-squares solver."""

    def describe(self) -> str:
        s_err, l_err, d_err = self.stderr
        return (f"motor_torque_scaling: {self.motor_torque_scaling:.4f} (+- {s_err:.4f})\n"
                f"slew_rate: {self.slew_rate:.3f} rad/s^2 (+- {l_err:.3f})\n"
                f"delay: {self.delay * 1000:.2f} ms (+- {d_err * 1000:.2f})\n"
                f"residual: {self.residual_rms:.4f} rad/s RMS over {self.samples} speed samples "
                f"({self.iterations} least-squares iterations)")


def fit_speeds(log: DriveLog, fit: DriveFit) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(time, measured, modelled) front-wheel speeds of a fit at the log's interior samples:
    rad/s, [n - 2, 2] (left, right), by central differences of the logged (encoder) and the
    modelled angles."""
    model = model_angle(log, fit.motor_torque_scaling, fit.slew_rate, fit.delay)
    return (log.time[1:-1], _central_speed(log.time, log.angle),
            _central_speed(log.time, model))


def _residuals(log: DriveLog, measured: np.ndarray, p, keep=None) -> np.ndarray:
    """Modelled minus measured speeds at the interior samples `keep` (all by default),
    both sides, flattened."""
    angle = model_angle(log, *p)
    r = _central_speed(log.time, angle) - measured
    return (r if keep is None else r[keep]).ravel()


def fit_drive(log: DriveLog, max_iterations: int = 30, progress=None,
              keep: np.ndarray | None = None) -> DriveFit:
    """Least-squares MotorTorqueScaling, slew limit and delay from the log's encoder speeds,
    over the interior samples `keep` (a bool mask [n - 2]; default all: `robust_fit` drops
    stalls and outliers): scipy's `least_squares` (trust region, scaling and slew bounded
    below by 1e-3) from a coarse start, at most `max_iterations` evaluations of the model;
    `progress(iteration, (scaling, slew, delay), rms rad/s)` after each iteration."""
    from scipy.optimize import least_squares

    measured_all = _central_speed(log.time, log.angle)
    keep = np.ones(len(measured_all), bool) if keep is None else keep
    measured = measured_all[keep]
    p_mid = log.power[1:-1][keep]
    driven = np.abs(p_mid) > 0.1
    if not driven.any():
        raise LogError(f"{log.source}: the log never commands more than 10% power: nothing to fit")
    # Start: scaling from the median ratio of speed to power, slew from a coarse grid.
    scaling0 = float(np.median(measured[driven] / p_mid[driven]))
    best = None
    for slew in np.geomspace(2.0, 300.0, 13):
        r = _residuals(log, measured_all, (scaling0, slew, 0.0), keep)
        sse = float(r @ r)
        if best is None or sse < best[0]:
            best = (sse, slew)
    size = r.size
    iterations = 0

    def iterated(intermediate_result) -> None:
        nonlocal iterations
        iterations += 1
        if progress is not None:
            progress(iterations, intermediate_result.x,
                     math.sqrt(2.0 * intermediate_result.cost / size))

    result = least_squares(
        lambda p: _residuals(log, measured_all, p, keep),
        [max(scaling0, 2e-3), best[1], 0.0],
        # Forward differences of 0.1% of scaling and slew, 0.1 ms of delay: the limiter's
        # corners make the residuals only piecewise smooth, so a finer step sees noise.
        jac="2-point", diff_step=[1e-3, 1e-3, 1e-4],
        bounds=([1e-3, 1e-3, -np.inf], np.inf), method="trf", x_scale="jac",
        max_nfev=max_iterations, callback=iterated)
    p, r = result.x, result.fun
    sse = float(r @ r)
    sigma2 = sse / max(r.size - 3, 1)
    try:  # the Gauss-Newton approximation of the covariance at the solution
        cov = np.linalg.inv(result.jac.T @ result.jac) * sigma2
        stderr = tuple(float(math.sqrt(max(v, 0.0))) for v in np.diag(cov))
    except np.linalg.LinAlgError:
        stderr = (math.nan, math.nan, math.nan)
    return DriveFit(float(p[0]), float(p[1]), float(p[2]), math.sqrt(sse / r.size), stderr,
                    int(r.size), iterations)


# --- stalls and outliers ------------------------------------------------------------------

STALL_FRACTION = 0.1
"""A side stalls when its wheel turns at less than this fraction of the speed its power asks."""
STALL_MIN_TIME = 0.2
"""s: how long a stall lasts at least (the slew ramp after a power step is shorter)."""
OUTLIER_SIGMAS = 6.0
"""Residuals beyond this many robust standard deviations are outliers..."""
OUTLIER_FLOOR = 2.5
"""...and beyond this, rad/s: a fifth of the top axle speed, above the 1.9 rad/s a good log's
power steps reach (the servo's lag the model leaves out, plus one encoder tick per 20 ms)."""
MAX_DROPPED = 0.5
"""A log whose dropped samples exceed this share of its driven ones is refused."""


@dc.dataclass
class Dropped:
    """A stretch of the log left out of the fit: times (s) and why."""

    start: float
    end: float
    reason: str

    def describe(self) -> str:
        return f"{self.start:.2f}-{self.end:.2f} s: {self.reason}"


def _runs(mask: np.ndarray):
    """(first, last) indices of each run of True in `mask`."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(int), [0]])))
    return list(zip(edges[::2], edges[1::2] - 1, strict=True))


def find_stalls(log: DriveLog, scaling: float) -> tuple[np.ndarray, list[Dropped]]:
    """Interior samples [n - 2] where power is commanded but a side's wheel barely turns (under
    `STALL_FRACTION` of power x `scaling`) for at least `STALL_MIN_TIME`: the wheels are held (an
    obstacle, the motor's torque limit), so the drive model does not hold there."""
    t, measured, power = log.time[1:-1], _central_speed(log.time, log.angle), log.power[1:-1]
    asked = np.abs(power) * scaling
    still = ((np.abs(power) > 0.1) & (np.abs(measured) < STALL_FRACTION * asked)).any(axis=1)
    mask = np.zeros(len(t), bool)
    dropped = []
    for a, b in _runs(still):
        if t[b] - t[a] < STALL_MIN_TIME:
            continue
        mask[a:b + 1] = True
        reason = "stall: power commanded, the wheels still"
        if log.position is not None:
            moved = np.hypot(*(log.position[b + 1] - log.position[a + 1]))
            reason += f", the robot moved {moved * 1000:.1f} mm (pushing an obstacle?)"
        dropped.append(Dropped(float(t[a]), float(t[b]), reason))
    return mask, dropped


def find_outliers(log: DriveLog, fit: DriveFit, keep: np.ndarray
                  ) -> tuple[np.ndarray, list[Dropped]]:
    """Interior samples whose speed residual (either side) exceeds `OUTLIER_SIGMAS` robust
    standard deviations (1.4826 MAD over the kept samples) and `OUTLIER_FLOOR`."""
    t, measured, model = fit_speeds(log, fit)
    r = np.abs(model - measured).max(axis=1)
    sigma = 1.4826 * float(np.median(np.abs(r[keep] - np.median(r[keep]))))
    limit = max(OUTLIER_SIGMAS * sigma, OUTLIER_FLOOR)
    mask = (r > limit) & keep
    return mask, [Dropped(float(t[a]), float(t[b]),
                          f"outlier: residual up to {r[a:b + 1].max():.2f} rad/s "
                          f"(limit {limit:.2f})") for a, b in _runs(mask)]


def robust_fit(log: DriveLog, progress=None) -> tuple[DriveFit, list[Dropped]]:
    """`fit_drive` without the log's stalls and outliers: drops them (returned, to warn about)
    and refits; LogError when they are more than `MAX_DROPPED` of the driven samples."""
    measured, power = _central_speed(log.time, log.angle), log.power[1:-1]
    driven = (np.abs(power) > 0.1).any(axis=1)
    moving = driven & (np.abs(measured) > 0).any(axis=1)
    scaling0 = float(np.median(np.abs(measured[moving] / np.where(
        np.abs(power[moving]) > 0.1, power[moving], np.inf)).max(axis=1))) if moving.any() else 1
    stalled, dropped = find_stalls(log, scaling0)
    keep = ~stalled
    fit = None
    for _ in range(3):  # fit, drop outliers, refit (twice at most)
        _check_dropped(log, driven, keep, dropped)
        fit = fit_drive(log, progress=progress, keep=keep)
        outliers, more = find_outliers(log, fit, keep)
        if not more:
            break
        keep &= ~outliers
        dropped += more
    return fit, sorted(dropped, key=lambda d: d.start)


def _check_dropped(log: DriveLog, driven, keep, dropped) -> None:
    lost = int((driven & ~keep).sum())
    if lost > MAX_DROPPED * driven.sum():
        where = "; ".join(d.describe() for d in dropped[:3]) + ("; ..." if len(dropped) > 3
                                                                else "")
        raise LogError(f"{log.source}: the drive model does not hold in {lost} of the "
                       f"{int(driven.sum())} driven samples ({where}): refusing to fit; log "
                       "straight runs in the open")


# --- editing a scenario file in place ----------------------------------------------------


def set_drive_field(text: str, robot: str, field: str, value: float, comment: str | None = None,
                    digits: int = 4) -> str:
    """`text` (a scenario YAML) with robot `robot`'s `drive.<field>` set to `value` (`digits`
    significant digits).

    A round trip through ruamel.yaml: every other value, comment, tag, quote, flow or block
    style and the indentation stay; the field's line keeps its comment (at its column, at least
    two spaces after the value), and a missing field is added at the end of the robot's
    `drive:` mapping. With `comment`, the field's comment becomes it, two spaces after the
    value, unless the field sits in a flow mapping (`drive: {...}`), whose line holds other
    fields too: that line keeps its own. Raises ValueError if the robot is absent (naming the
    closest robots) or has no `drive:` mapping to hold the field.
    """
    yaml, data = _round_trip(text)
    number = f"{value:.{digits}g}"
    spec, drive = _drive_mapping(data, robot, field, number)
    if drive.fa.flow_style():
        drive[field] = float(number)
        # The comment on the line is the `drive:` key's.
        edited = [_comment_token(spec, "drive"), drive.ca.comment and drive.ca.comment[0]]
    else:
        edited = [_set_block_field(drive, field, float(number), comment)]
    return _dump(yaml, data, [c for c in edited if c is not None])


def _round_trip(text: str):
    """ruamel.yaml's round-trip loader set to `text`'s indentation, and `text` loaded by it;
    ValueError (where and why, one line) if it cannot read it."""
    from ruamel.yaml import YAML
    from ruamel.yaml.error import YAMLError
    from ruamel.yaml.util import load_yaml_guess_indent

    yaml = YAML()  # round-trip
    yaml.preserve_quotes = True
    yaml.width = 1 << 16  # never fold a long line
    try:
        _, indent, block_seq_indent = load_yaml_guess_indent(text)
        indent, offset = indent or 2, block_seq_indent or 0  # None: no block mapping, no list
        yaml.indent(mapping=indent, sequence=indent + offset, offset=offset)
        return yaml, yaml.load(text)  # with preserve_quotes
    except YAMLError as e:  # the loader would refuse it too: one line, where and why
        mark = getattr(e, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        problem = getattr(e, "problem", None) or one_line(e)
        raise ValueError(f"not a YAML file ruamel.yaml can edit{where}: "
                         f"{problem.strip().splitlines()[0]}") from None


def _drive_mapping(data, robot: str, field: str, number: str):
    """Robot `robot`'s mapping and its `drive:` mapping in the loaded scenario `data`;
    ValueError naming what is missing."""
    from ruamel.yaml.comments import CommentedMap

    robots = data.get("robots") if isinstance(data, CommentedMap) else None
    if not isinstance(robots, CommentedMap):
        raise ValueError("no `robots:` mapping at the top level")
    if robot not in robots:
        raise ValueError(unknown_robot(robot, robots))
    spec = robots[robot]
    drive = spec.get("drive") if isinstance(spec, CommentedMap) else None
    if not isinstance(drive, CommentedMap):
        raise ValueError(f"robot {robot!r} has no `{field}:` line and no `drive:` mapping to "
                         f"add it to; add `{field}: {number}` under its `drive:`")
    return spec, drive


def _set_block_field(drive, field: str, value: float, comment: str | None):
    """Sets `field` in the block mapping `drive`; returns the comment token of its line (None
    if it has none), `comment` when given."""
    # A key's comment token holds its line's comment and the blank and comment lines below it:
    # a field added after the last key takes those below, so they stay above what follows.
    below = ""
    if field not in drive and drive:
        last = _comment_token(drive, list(drive)[-1])
        if last is not None and "\n" in last.value:
            cut = last.value.index("\n") + 1
            last.value, below = last.value[:cut], last.value[cut:]
    drive[field] = value
    own = _comment_token(drive, field)
    if own is None and (comment is not None or below):
        drive.yaml_add_eol_comment("#", field, column=0)
        own = _comment_token(drive, field)
        own.value = "\n"
    if own is not None and (comment is not None or below):
        rest = own.value[own.value.index("\n"):] if "\n" in own.value else "\n"
        head = own.value[:len(own.value) - len(rest)]
        own.value = (f"# {comment}" if comment is not None else head) + rest + below
        if comment is not None:
            own.start_mark.column = 0  # two spaces after the value (_dump)
    return own


def _dump(yaml, data, edited: list) -> str:
    """`data` written by `yaml`, each comment token in `edited` at least two spaces after its
    line's new value."""
    import io

    from ruamel.yaml.emitter import RoundTripEmitter

    class Emitter(RoundTripEmitter):
        def write_comment(self, token, pre=False):
            if any(token is c for c in edited) and self.column:
                token.start_mark.column = max(token.start_mark.column, self.column + 2)
            super().write_comment(token, pre)

    yaml.Emitter = Emitter
    out = io.StringIO()
    yaml.dump(data, out)
    return out.getvalue()


def _comment_token(mapping, key):
    """The ruamel comment token after `key`'s value in `mapping` (None if it has none)."""
    tokens = mapping.ca.items.get(key) or []
    return tokens[2] if len(tokens) > 2 else None


@dc.dataclass(frozen=True)
class DriveField:
    """One value for a robot's `drive:` block: the field, its value (in the field's unit), the
    comment saying where it came from (None keeps the line's own) and its significant digits."""

    name: str
    value: float
    comment: str | None = None
    digits: int = 4


def write_drive_fields(scenario_path: str | Path, robot: str, fields: list[DriveField],
                       out_path: str | Path | None = None) -> Path:
    """Writes the scenario `scenario_path` with robot `robot`'s `fields` set (`set_drive_field`:
    only their lines change) to `out_path` (default: in place); returns `out_path`.

    The result is loaded back (`load_scenario`) before `out_path` is touched, so a tool never
    leaves a scenario that does not load. ScenarioError (one line: the file, the line, the
    field) when the robot or a field cannot be written, or when the result does not load (a
    value out of its bound, not finite)."""
    scenario_path = Path(scenario_path)
    out_path = Path(out_path or scenario_path)
    text = read_text(scenario_path)
    for field in fields:
        try:
            text = set_drive_field(text, robot, field.name, field.value, field.comment,
                                   field.digits)
        except ValueError as e:
            raise ScenarioError(str(scenario_path), f"robots.{robot}.drive.{field.name}",
                                str(e)) from None
    _check_loads(text, out_path)
    out_path.write_text(text)
    return out_path


def _check_loads(text: str, out_path: Path) -> None:
    """Loads `text` as the scenario `out_path` would be (from a file beside it: its relative
    mesh and model paths resolve the same); ScenarioError naming `out_path` if it does not."""
    try:
        fd, probe = tempfile.mkstemp(suffix=".yaml", dir=out_path.parent)
    except OSError as e:  # named as the file asked for, not the probe's random name
        raise OSError(e.errno, e.strerror, str(out_path)) from None
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
        load_scenario(probe)
    except ScenarioError as e:
        raise ScenarioError(str(out_path), e.field, e.message, e.line) from None
    finally:
        os.unlink(probe)
