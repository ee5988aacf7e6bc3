"""Fits MotorTorqueScaling and the slew limit to a run log (CSV) by least squares.

The log comes from a real robot or from the simulator (`python -m corobot_drake --log run.csv`
or `Robot.write_log`); columns in docs/tuning.md. Prints the fit, its residual and a plot of
measured vs modelled front-wheel speeds. A malformed CSV stops with one line naming the line.
The fit is `corobot_drake.analysis.sysid`; the simulated log and the plot
`corobot_drake.analysis.drive_tuning`.

Usage: python tools/fit_drive_log.py LOG.csv [--plot out/fit_drive_log.png] [--write SCENARIO]

With no LOG, `--simulate SCALING SLEW` first makes a log with the simulator (a self-check).
"""

import argparse
import sys
from pathlib import Path

from corobot_drake.analysis import drive_tuning, sysid

REPO = Path(__file__).resolve().parent.parent


def _fit(path: Path, ticks_per_revolution: int):
    """(log, fit), printing progress; raises sysid.LogError."""
    log = sysid.read_log(path, ticks_per_revolution)
    print(f"read {len(log.time)} samples over {log.time[-1] - log.time[0]:.2f} s from {path}",
          flush=True)

    def progress(i, params, rms):
        print(f"  iteration {i}: scaling {params[0]:.4f}, slew {params[1]:.3f} rad/s^2, "
              f"delay {params[2] * 1000:.2f} ms, residual {rms:.4f} rad/s", flush=True)

    return log, sysid.fit_drive(log, progress=progress)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("log", nargs="?", help="run log CSV")
    p.add_argument("--simulate", nargs=2, type=float, metavar=("SCALING", "SLEW"),
                   help="make the log with the simulator at these parameters first")
    p.add_argument("--plot", default=str(REPO / "out" / "fit_drive_log.png"), help="PNG of the fit")
    p.add_argument("--ticks-per-revolution", type=int, default=600, help="encoder counts")
    p.add_argument("--write", metavar="SCENARIO",
                   help="put the fitted motor_torque_scaling in this scenario file")
    p.add_argument("--robot", default="corobot", help="robot to --write")
    args = p.parse_args(argv)
    if args.log is None and args.simulate is None:
        p.error("give a LOG or --simulate SCALING SLEW")
    path = Path(args.log or REPO / "out" / "simulated_drive_log.csv")
    if args.simulate:
        scaling, slew = args.simulate
        print(f"simulating a log at motor_torque_scaling {scaling:g}, slew {slew:g} rad/s^2 "
              f"-> {path}", flush=True)
        drive_tuning.simulate_log(path, scaling, slew)
    try:
        log, fit = _fit(path, args.ticks_per_revolution)
    except sysid.LogError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    print(fit.describe())
    drive_tuning.plot_fit(log, fit, Path(args.plot))
    print(f"plot: {args.plot}")
    if args.write:
        target = Path(args.write)
        try:
            target.write_text(sysid.set_motor_torque_scaling(
                target.read_text(), args.robot, fit.motor_torque_scaling))
        except (OSError, ValueError) as e:
            print(f"error: {target}: {e}", file=sys.stderr)
            return 2
        print(f"wrote motor_torque_scaling {fit.motor_torque_scaling:.4g} in {target}")
    print(f"motor_torque_scaling: {fit.motor_torque_scaling:.4f}  slew_rate: "
          f"{fit.slew_rate:.3f}  (residual {fit.residual_rms:.4f} rad/s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
