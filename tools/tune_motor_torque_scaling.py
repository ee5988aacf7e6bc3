"""Tunes MotorTorqueScaling so that full power gives the target top speed (SPEC "Drive").

Drives the robot at full power headless, measures its steady top speed (the mean forward speed
over the last `--measure` s, after `--settle` s: not the average including the ramp), prints
new = old x target / measured and repeats with the new value until the top speed is within
`--tolerance` of the target. The last line is `motor_torque_scaling: <value>` and the speed it
gives. `--write` puts the value in the scenario file (only that number changes).
A plot of speed vs time per iteration goes to `--plot`.

Usage: python tools/tune_motor_torque_scaling.py [--scenario S] [--scaling 20] [--target 0.6096]
"""

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from corobot_drake.analysis.sysid import set_motor_torque_scaling
from corobot_drake.config.scenario import ScenarioError, load_scenario
from corobot_drake.model import dimensions as dim
from corobot_drake.simulation import Simulation, quiet_drake_warnings

REPO = Path(__file__).resolve().parent.parent
DEFAULT_SCENARIO = REPO / "scenarios" / "corobot.yaml"
SAMPLE_PERIOD = 0.02


def measure_top_speed(scenario_path, robot_name, scaling: float, settle: float, measure: float):
    """(steady speed m/s, slope over the window m/s^2, times, speeds) at full power."""
    override = f"robots: {{{robot_name}: {{drive: {{motor_torque_scaling: {scaling!r}}}}}}}"
    scenario = load_scenario(scenario_path, overrides=[override])
    sim = Simulation(scenario)
    robot = sim.robot(robot_name)
    robot.set_power(1.0, 1.0)
    times, speeds = [], []
    t0 = sim.time
    steps = round((settle + measure) / SAMPLE_PERIOD)
    for _ in range(steps):
        sim.advance(SAMPLE_PERIOD)
        times.append(sim.time - t0)
        speeds.append(robot.velocity().forward)
    times, speeds = np.array(times), np.array(speeds)
    window = times > settle + 1e-9
    slope = float(np.polyfit(times[window], speeds[window], 1)[0]) if window.sum() > 2 else 0.0
    return float(np.mean(speeds[window])), slope, times, speeds


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenario", default=str(DEFAULT_SCENARIO))
    p.add_argument("--robot", help="robot name (default: the scenario's only robot)")
    p.add_argument("--scaling", type=float, default=dim.MOTOR_TORQUE_SCALING_UNTUNED,
                   help="starting MotorTorqueScaling (default 20, the untuned value)")
    p.add_argument("--target", type=float, default=dim.TARGET_TOP_SPEED,
                   help="top speed wanted, m/s (default 0.6096 = 2 ft/s)")
    p.add_argument("--tolerance", type=float, default=0.005, help="relative (default 0.5%%)")
    p.add_argument("--max-iterations", type=int, default=8)
    p.add_argument("--settle", type=float, default=2.0,
                   help="s at full power before measuring (the ramp takes ~0.4-0.7 s)")
    p.add_argument("--measure", type=float, default=1.0, help="s averaged for the top speed")
    p.add_argument("--plot", default=str(REPO / "out" / "tune_motor_torque_scaling.png"))
    p.add_argument("--write", action="store_true",
                   help="write the value into --scenario (only that number changes)")
    args = p.parse_args(argv)
    quiet_drake_warnings()
    try:
        scenario = load_scenario(args.scenario)
    except ScenarioError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    names = list(scenario.robots)
    robot_name = args.robot or (names[0] if len(names) == 1 else None)
    if robot_name not in scenario.robots:
        print(f"error: {args.scenario}: name a robot with --robot (robots: {', '.join(names)})",
              file=sys.stderr)
        return 2
    if not (args.scaling > 0 and args.target > 0):
        print("error: --scaling and --target must be > 0", file=sys.stderr)
        return 2

    scaling = args.scaling
    curves = []
    converged = False
    measured = float("nan")
    print(f"tuning {robot_name}: target {args.target:.4f} m/s, start scaling {scaling:g}, "
          f"settle {args.settle:g} s, measure {args.measure:g} s", flush=True)
    for iteration in range(1, args.max_iterations + 1):
        start = time.perf_counter()
        measured, slope, times, speeds = measure_top_speed(
            args.scenario, robot_name, scaling, args.settle, args.measure)
        curves.append((scaling, measured, times, speeds))
        error = measured / args.target - 1.0
        new = scaling * args.target / measured
        steady = "steady" if abs(slope) * args.measure < 0.002 * measured else \
            f"NOT steady (slope {slope:+.4f} m/s^2: raise --settle)"
        print(f"iteration {iteration}: scaling {scaling:.4f} -> top speed {measured:.4f} m/s "
              f"({error * 100:+.2f}%, {steady}); new scaling {new:.4f}  "
              f"[{time.perf_counter() - start:.1f} s]", flush=True)
        if abs(error) <= args.tolerance:
            converged = True
            break
        scaling = new
    _plot(curves, args.target, args.settle, Path(args.plot))
    print(f"plot: {args.plot}")
    if not converged:
        print(f"did not converge within {args.tolerance * 100:g}% in {args.max_iterations} "
              f"iterations", flush=True)
    else:
        print(f"converged in {len(curves)} iteration(s) (within {args.tolerance * 100:g}%)")
    if args.write:
        path = Path(args.scenario)
        try:
            path.write_text(set_motor_torque_scaling(path.read_text(), robot_name, scaling))
        except ValueError as e:
            print(f"error: {path}: {e}", file=sys.stderr)
            return 2
        print(f"wrote motor_torque_scaling {scaling:.4g} for {robot_name} in {path}")
    print(f"motor_torque_scaling: {scaling:.4f}  (top speed {measured:.4f} m/s, "
          f"target {args.target:.4f})")
    return 0 if converged else 1


def _plot(curves, target: float, settle: float, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for i, (scaling, measured, times, speeds) in enumerate(curves, start=1):
        ax.plot(times, speeds, label=f"iteration {i}: scaling {scaling:.3f} -> {measured:.4f} m/s")
    ax.axhline(target, color="k", linestyle="--", linewidth=1, label=f"target {target:.4f} m/s")
    ax.axvspan(settle, max(c[2][-1] for c in curves), color="0.9", label="measured window")
    ax.set_xlabel("time at full power (s)")
    ax.set_ylabel("forward speed (m/s)")
    ax.set_title("MotorTorqueScaling tuning: speed at full power")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
