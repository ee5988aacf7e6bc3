"""Calibrates the dead-reckoning odometry: the effective wheel radius and track width.

From a log with encoder ticks and ground truth (a simulated run log or a real robot's CSV:
`time, left_ticks, right_ticks, x, y, yaw`, docs/tuning.md), or, with `--simulate`, from
UMBmark's squares (`--side`, 1 m; counter-clockwise then clockwise, power 0.2) driven in the
scenario.
Prints the fit, plots the dead-reckoned path against the true one before (nominal radius and
track) and after calibration, and with `--write` puts both in the scenario's drive fields
(`effective_wheel_radius`, `effective_track_width`) with a comment saying where they came from.
`--drive-test` then runs the book's drive test (`--loops`, 3) with the calibrated odometry and
prints the dead-reckoned end position error before and after. The squares' log and the plots go in
`--out` (default: a new temporary directory, printed). The fit is
`corobot_drake.tuning.odometry_calibration`.

Usage: python tools/calibrate_odometry.py [LOG.csv | --simulate] [--out DIR] [--write SCENARIO]
       [--drive-test [--loops N]]
"""

import contextlib
import sys
import tempfile
from pathlib import Path

try:  # without the [study] extra: one line naming it, not a traceback
    from tqdm import tqdm
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/calibrate_odometry.py", "study")

from corobot_drake.arguments import (
    TICKS_PER_REVOLUTION,
    ToolParser,
    bounded,
    existing_file,
    one_line_errors,
    output_directory,
    output_file,
    scenario_file,
)
from corobot_drake.limits import DRAKE_INT, Range
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.study.programs import LOOPS
from corobot_drake.tuning import odometry_calibration as oc
from corobot_drake.tuning.sysid import DriveField, scenario_robot, write_drive_fields

SIDE = Range(0.1, 100.0, unit="m")
"""--side: a square's side, from a short one to the DriveDistance command's longest."""


def _parser() -> ToolParser:
    p = ToolParser(description=__doc__.splitlines()[0])
    p.add_argument("log", nargs="?", help="log CSV with time, left_ticks, right_ticks, x, y, yaw")
    p.add_argument("--simulate", action="store_true",
                   help="drive UMBmark's squares in --scenario and fit their log")
    p.add_argument("--side", type=bounded(SIDE), default=oc.SQUARE_SIDE,
                   help="--simulate: the squares' side, m")
    p.add_argument("--scenario", type=scenario_file, default=str(DEFAULT_SCENARIO),
                   help="scenario to simulate in, or a shipped scenario's name (pioneer.yaml) "
                   "from any folder; its --robot is the robot a LOG is from")
    p.add_argument("--robot", default=None,
                   help="robot of --scenario (None: its only robot): its nominal radius and "
                   "track, its encoders")
    p.add_argument("--ticks-per-revolution", type=bounded(TICKS_PER_REVOLUTION, int),
                   default=None,
                   help="encoder counts per wheel revolution (None: the robot's)")
    p.add_argument("--out", type=output_directory, default=None,
                   help="directory for the squares' log and the plots (None: a new temporary "
                   "directory)")
    p.add_argument("--plot", type=output_file, default=None,
                   help="before/after plot of the log (None: OUT/calibrate_odometry.png)")
    p.add_argument("--write", metavar="SCENARIO", type=existing_file,
                   help="put the fit in this scenario file")
    p.add_argument("--drive-test", action="store_true",
                   help="check on the drive test, seed --seed")
    p.add_argument("--loops", type=bounded(LOOPS, int), default=3,
                   help="the drive test's loops")
    p.add_argument("--seed", type=bounded(DRAKE_INT, int), default=1, help="the drive test's seed")
    return p


@contextlib.contextmanager
def _progress(estimate: float, description: str):
    """A bar of simulated seconds, yielding the run's `progress(sim)`: `estimate` s long until
    the run ends (or outgrows it), then as long as the run was, so a finished run ends at
    100%."""
    with tqdm(total=round(estimate), desc=description, unit="sim s", file=sys.stderr) as bar:
        def update(sim):
            done = round(sim.time)
            bar.total = max(bar.total, done)
            bar.update(done - bar.n)
        yield update
        bar.total = bar.n
        bar.refresh()


def _make_out(args) -> None:
    """Makes `args.out` (None: a new temporary directory), says where it is, and puts the plot
    in it unless `--plot` names another file."""
    args.out = args.out or Path(tempfile.mkdtemp(prefix="calibrate_odometry-"))
    args.out.mkdir(parents=True, exist_ok=True)
    args.plot = args.plot or args.out / "calibrate_odometry.png"
    print(f"outputs in {args.out}", flush=True)


def _simulated_log(args) -> oc.PoseLog:
    commands = oc.square_commands(args.side)
    with _progress(110 * args.side, "UMBmark squares") as update:
        sim = oc.run_script(args.scenario, args.robot, commands, progress=update)
    path = args.out / "odometry_squares_log.csv"
    sim.robot(args.robot).write_log(path)
    print(f"simulated UMBmark squares ({sim.time:.1f} s) -> {path}", flush=True)
    return oc.read_pose_log(path, args.ticks_per_revolution)


def _write(args, fit: oc.OdometryFit, source: str) -> None:
    comment = f"calibrate_odometry.py from {source}"
    target = write_drive_fields(args.write, args.robot, [
        DriveField("effective_wheel_radius", fit.effective_wheel_radius, comment, digits=5),
        DriveField("effective_track_width", fit.effective_track_width, comment, digits=4)])
    print(f"wrote effective_wheel_radius {fit.effective_wheel_radius:.5g} and "
          f"effective_track_width {fit.effective_track_width:.4g} in {target}")


def _drive_test(args, fit: oc.OdometryFit) -> None:
    """The drive test run with the calibrated odometry; the nominal odometry's error is the
    same encoder ticks dead reckoned with the nominal radius and track."""
    with _progress(50 * args.loops, f"drive test, seed {args.seed}") as update:
        run = oc.drive_test_odometry_error(args.scenario, args.robot, fit.effective_wheel_radius,
                                           fit.effective_track_width, args.seed,
                                           args.loops, progress=update)
    log = run["log"]
    nominal = oc.end_error(log, *args.nominal)
    offline = oc.end_error(log, fit.effective_wheel_radius, fit.effective_track_width)
    calibrated = run["error"]
    radius_only = oc.end_error(log, args.nominal[0], fit.effective_track_width)
    print(f"drive test ({args.loops} loops, seed {args.seed}, {run['sim_time']:.1f} s): "
          f"dead-reckoned end position error {nominal * 1000:.1f} mm uncalibrated, "
          f"{calibrated * 1000:.1f} mm calibrated (Robot.odometry(); {offline * 1000:.1f} mm "
          f"from the log), ratio {calibrated / nominal:.4f} (target <= 0.2); heading error "
          f"calibrated {run['yaw_error_deg']:+.2f} deg")
    print(f"with the calibrated track but the nominal radius: {radius_only * 1000:.1f} mm")
    plot = Path(args.plot).with_name(Path(args.plot).stem + "_drive_test.png")
    oc.plot_paths(log, args.nominal,
                  (fit.effective_wheel_radius, fit.effective_track_width), plot,
                  f"drive test, {args.loops} loops, seed {args.seed}: odometry before and after "
                  "calibration")
    print(f"plot: {plot}")


@one_line_errors
def main(argv=None) -> int:
    p = _parser()
    args = p.parse_args(argv)
    if (args.log is None) == (not args.simulate):
        p.error("give a LOG or --simulate (not both)")
    args.robot, spec = scenario_robot(args.scenario, args.robot)  # wrong: one line
    args.nominal = (spec.wheel_radius, spec.track)
    if args.ticks_per_revolution is None:
        args.ticks_per_revolution = spec.encoder_ticks_per_revolution
    if args.simulate:
        _make_out(args)
        log = _simulated_log(args)
    else:
        log = oc.read_pose_log(args.log, args.ticks_per_revolution)
    fit = oc.fit_odometry(log)  # a bad log or scenario: one_line_errors' one line
    if args.plot is None:  # made once the log is good: no empty directory for a bad one
        _make_out(args)
    print(fit.describe(args.nominal))
    nominal = args.nominal
    fitted = (fit.effective_wheel_radius, fit.effective_track_width)
    print(f"end position error on this log: {oc.end_error(log, *nominal) * 1000:.1f} mm "
          f"nominal, {oc.end_error(log, *fitted) * 1000:.1f} mm calibrated")
    source = (f"simulated UMBmark squares, {args.side:g} m at power {oc.CALIBRATION_POWER:g}"
              if args.simulate
              else f"the log {Path(args.log).name}")
    oc.plot_paths(log, nominal, fitted, args.plot, f"odometry calibration: {source}")
    print(f"plot: {args.plot}")
    if args.write:
        _write(args, fit, source)  # a scenario it cannot write: one_line_errors' one line
    if args.drive_test:
        _drive_test(args, fit)
    return 0


if __name__ == "__main__":
    sys.exit(main())
