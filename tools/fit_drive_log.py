"""Fits MotorTorqueScaling and the slew limit to a run log (CSV) by least squares.

The log comes from a real robot or from the simulator (`python -m corobot_drake --log run.csv`
or `Robot.write_log`); columns in docs/tuning.md. Prints the fit, its residual and a plot of
measured vs modelled front-wheel speeds. A malformed CSV stops with one line naming the line.

Usage: python tools/fit_drive_log.py LOG.csv [--plot out/fit_drive_log.png] [--write SCENARIO]

With no LOG, `--simulate SCALING SLEW` first makes a log with the simulator (a self-check).
"""

import argparse
import sys
from pathlib import Path

from corobot_drake.analysis import sysid

REPO = Path(__file__).resolve().parent.parent
DEFAULT_SCENARIO = REPO / "scenarios" / "corobot.yaml"
EXCITATION = ((1.0, 1.0, 1.5), (0.0, 0.0, 1.0), (0.5, 0.5, 1.0), (-0.6, -0.6, 1.5),
              (0.0, 0.0, 1.0))
"""(left power, right power, seconds): straight ramps and plateaus both ways. A skid-steer turn
drags the tyres sideways and loads the motors to their effort limit (0.3 N m), and then the
wheels no longer follow the drive's command (the encoders lag or overrun it): log straight runs
for this fit, on a real robot too."""


def simulate_log(path: Path, scaling: float, slew: float, scenario=DEFAULT_SCENARIO) -> None:
    """Runs `EXCITATION` in the simulator at the given drive parameters and writes its log."""
    from corobot_drake.config.scenario import load_scenario
    from corobot_drake.simulation import Simulation, quiet_drake_warnings

    quiet_drake_warnings()
    robots = load_scenario(scenario).robots
    name = next(iter(robots))
    sim = Simulation(load_scenario(scenario, overrides=[
        f"robots: {{{name}: {{drive: {{motor_torque_scaling: {scaling!r}, "
        f"slew_rate: {slew!r}}}}}}}"]))
    robot = sim.robot(name)
    for left, right, seconds in EXCITATION:
        robot.set_power(left, right)
        sim.advance(seconds)
    path.parent.mkdir(parents=True, exist_ok=True)
    robot.write_log(path)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("log", nargs="?", help="run log CSV")
    p.add_argument("--simulate", nargs=2, type=float, metavar=("SCALING", "SLEW"),
                   help="make the log with the simulator at these parameters first")
    p.add_argument("--plot", default=str(REPO / "out" / "fit_drive_log.png"))
    p.add_argument("--ticks-per-revolution", type=int, default=600)
    p.add_argument("--write", metavar="SCENARIO",
                   help="put the fitted motor_torque_scaling in this scenario file")
    p.add_argument("--robot", default="corobot", help="robot to --write (default corobot)")
    args = p.parse_args(argv)
    if args.log is None and args.simulate is None:
        p.error("give a LOG or --simulate SCALING SLEW")
    path = Path(args.log or REPO / "out" / "simulated_drive_log.csv")
    if args.simulate:
        scaling, slew = args.simulate
        print(f"simulating a log at motor_torque_scaling {scaling:g}, slew {slew:g} rad/s^2 "
              f"-> {path}", flush=True)
        simulate_log(path, scaling, slew)
    try:
        log = sysid.read_log(path, args.ticks_per_revolution)
    except sysid.LogError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    print(f"read {len(log.time)} samples over {log.time[-1] - log.time[0]:.2f} s from {path}",
          flush=True)

    def progress(i, params, rms):
        print(f"  iteration {i}: scaling {params[0]:.4f}, slew {params[1]:.3f} rad/s^2, "
              f"delay {params[2] * 1000:.2f} ms, residual {rms:.4f} rad/s", flush=True)

    try:
        fit = sysid.fit_drive(log, progress=progress)
    except sysid.LogError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    print(fit.describe())
    _plot(log, fit, Path(args.plot))
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


def _plot(log, fit, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path.parent.mkdir(parents=True, exist_ok=True)
    t = log.time[1:-1]
    measured = sysid._central_speed(log.time, log.angle)
    model = sysid._central_speed(log.time, sysid.model_angle(
        log, fit.motor_torque_scaling, fit.slew_rate, fit.delay))
    fig, ax = plt.subplots(figsize=(9, 4.5))
    for side, name in enumerate(("left", "right")):
        ax.plot(t, measured[:, side], ".", markersize=2, alpha=0.5,
                label=f"{name} measured (encoder)")
        ax.plot(t, model[:, side], linewidth=1.5, label=f"{name} model")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("front wheel speed (rad/s)")
    ax.set_title(f"fit: scaling {fit.motor_torque_scaling:.3f}, slew {fit.slew_rate:.2f} rad/s^2,"
                 f" residual {fit.residual_rms:.3f} rad/s RMS")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
