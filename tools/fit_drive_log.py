"""Fits MotorTorqueScaling and the slew limit to a run log (CSV) by least squares.

The log comes from a real robot or from the simulator (`python -m corobot_drake --log run.csv`
or `Robot.write_log`); columns in docs/tuning.md. Prints the fit, its residual and a plot of
measured vs modelled front-wheel speeds. A malformed CSV stops with one line naming the line.
Stalls (power commanded, the wheels still: e.g. pushing the giant box) and outliers are dropped
with a warning naming their times; a log that is mostly stalls is refused (exit status 2).
`--write` puts every fitted parameter (motor_torque_scaling, slew_rate) in the scenario, each
with a comment saying where it came from. The fit is `corobot_drake.tuning.sysid`; the
simulated log and the plot `corobot_drake.tuning.drive_tuning`.

Usage: python tools/fit_drive_log.py LOG.csv [--plot out/fit_drive_log.png] [--write SCENARIO]

With no LOG, `--simulate SCALING SLEW` first makes a log with the simulator (a self-check);
`--stall` makes that log end backing into the giant box.
"""

import dataclasses as dc
import sys
from pathlib import Path

try:  # without the [study] extra: one line naming it, before any work
    # (the fit needs SciPy, the plot Matplotlib)
    import matplotlib  # noqa: F401
    import scipy  # noqa: F401
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/fit_drive_log.py", "study")

from corobot_drake.arguments import (
    TICKS_PER_REVOLUTION,
    ToolParser,
    bounded,
    existing_file,
    one_line_errors,
    output_file,
    scenario_file,
)
from corobot_drake.config.scenario import Drive
from corobot_drake.limits import bound_of
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.tuning import drive_tuning, sysid


def _fit(path: Path, ticks_per_revolution: int):
    """(log, fit, dropped), printing progress; raises sysid.LogError."""
    log = sysid.read_log(path, ticks_per_revolution)
    print(f"read {len(log.time)} samples over {log.time[-1] - log.time[0]:.2f} s from {path}",
          flush=True)

    def progress(i, params, rms):
        print(f"  iteration {i}: scaling {params[0]:.4f}, slew {params[1]:.3f} rad/s^2, "
              f"delay {params[2] * 1000:.2f} ms, residual {rms:.4f} rad/s", flush=True)

    return (log, *sysid.robust_fit(log, progress=progress))


def _write(args, fit: sysid.DriveFit, source: str) -> None:
    where = (f"fit_drive_log.py from {source} ({fit.samples} speed samples, residual "
             f"{fit.residual_rms:.2f} rad/s RMS)")
    target = sysid.write_drive_fields(args.write, args.robot, [
        sysid.DriveField("motor_torque_scaling", fit.motor_torque_scaling,
                         f"{where}: axle rad/s at power 1"),
        sysid.DriveField("slew_rate", fit.slew_rate, f"{where}: rad/s^2")])
    print(f"wrote motor_torque_scaling {fit.motor_torque_scaling:.4g} and slew_rate "
          f"{fit.slew_rate:.4g} in {target}")


@one_line_errors
def main(argv=None) -> int:
    p = ToolParser(description=__doc__.splitlines()[0])
    p.add_argument("log", nargs="?", help="run log CSV")
    p.add_argument("--simulate", nargs=2, type=float, metavar=("SCALING", "SLEW"),
                   help="make the log with the simulator at these parameters first")
    p.add_argument("--stall", action="store_true",
                   help="with --simulate: end the log backing into the giant box")
    p.add_argument("--plot", type=output_file, default="out/fit_drive_log.png",
                   help="PNG of the fit")
    p.add_argument("--ticks-per-revolution", type=bounded(TICKS_PER_REVOLUTION, int),
                   default=None, help="encoder counts (None: the robot's)")
    p.add_argument("--write", metavar="SCENARIO", type=existing_file,
                   help="put the fitted motor_torque_scaling and slew_rate in this scenario file")
    p.add_argument("--scenario", type=scenario_file, default=None,
                   help="the scenario whose --robot the log is from and --simulate drives, "
                   "or a shipped scenario's name (pioneer.yaml) from any folder (None: "
                   "--write's, else the shipped default scene)")
    p.add_argument("--robot", default=None,
                   help="robot of --scenario to --write (None: its only robot)")
    args = p.parse_args(argv)
    if args.log is None and args.simulate is None:
        p.error("give a LOG or --simulate SCALING SLEW")
    args.scenario = args.scenario or args.write or str(DEFAULT_SCENARIO)
    args.robot, spec = sysid.scenario_robot(args.scenario, args.robot)  # wrong: one line
    if args.ticks_per_revolution is None:
        args.ticks_per_revolution = spec.encoder_ticks_per_revolution
    for value, field in zip(args.simulate or (), ("motor_torque_scaling", "slew_rate"),
                            strict=False):
        problem = bound_of(next(f for f in dc.fields(Drive) if f.name == field)).problem(value)
        if problem:
            p.error(f"--simulate: {field} {problem}")
    path = Path(args.log or Path("out") / "simulated_drive_log.csv")
    if args.simulate:
        scaling, slew = args.simulate
        print(f"simulating a log at motor_torque_scaling {scaling:g}, slew {slew:g} rad/s^2"
              f"{', ending in a stall against the giant box' if args.stall else ''} -> {path}",
              flush=True)
        drive_tuning.simulate_log(path, scaling, slew, args.scenario, args.robot,
                                  excitation=drive_tuning.STALL_EXCITATION
                                  if args.stall else drive_tuning.EXCITATION)
    log, fit, dropped = _fit(path, args.ticks_per_revolution)  # a bad log: one line
    for d in dropped:
        print(f"warning: {path}: dropped {d.describe()}", file=sys.stderr)
    print(fit.describe())
    if dropped:
        print(f"dropped {len(dropped)} stretch(es) of the log: " + "; ".join(
            f"{d.start:.2f}-{d.end:.2f} s {d.reason.split(':')[0]}" for d in dropped))
    drive_tuning.plot_fit(log, fit, Path(args.plot))
    print(f"plot: {args.plot}")
    if args.write:
        source = (f"a simulated log at {args.simulate[0]:g}, {args.simulate[1]:g}"
                  if args.simulate else f"the log {path.name}")
        _write(args, fit, source)  # a scenario it cannot write: one_line_errors' one line
    print(f"motor_torque_scaling: {fit.motor_torque_scaling:.4f}  slew_rate: "
          f"{fit.slew_rate:.3f}  (residual {fit.residual_rms:.4f} rad/s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
