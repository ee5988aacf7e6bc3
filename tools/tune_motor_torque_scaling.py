"""Tunes MotorTorqueScaling so that full power gives the target top speed.

Drives the robot at full power headless, measures its steady top speed (the mean forward speed
over the last `--measure` s, after `--settle` s: not the average including the ramp), prints
new = old x target / measured and repeats with the new value until the top speed is within
`--tolerance` of the target. The last line is `motor_torque_scaling: <value>` and the speed it
gives. `--write` puts the value in the scenario file (only that number changes).
A plot of speed vs time per iteration goes to `--plot`. The measurement is
`corobot_drake.tuning.drive_tuning.measure_top_speed`.

`--sweep` instead runs `scenarios/studies/motor_torque_scaling.yaml` on the study engine (the
same steady speed over a grid of scalings, in parallel) and interpolates the target's scaling.

Usage: python tools/tune_motor_torque_scaling.py [--scenario S] [--scaling 20] [--target 0.6096]
       python tools/tune_motor_torque_scaling.py --sweep [--workers N]
"""

import sys
import time
from pathlib import Path

try:  # without the [study] extra: one line naming it, before any work
    # (the plot needs Matplotlib, --sweep Ray: the same extra)
    import matplotlib  # noqa: F401
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/tune_motor_torque_scaling.py", "study")

from corobot_drake.arguments import (
    WORKERS,
    ToolParser,
    bounded,
    one_line_errors,
    output_directory,
    output_file,
)
from corobot_drake.config.scenario import ScenarioError, load_scenario
from corobot_drake.limits import AXLE_SPEED, Range
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.robots import robot_spec
from corobot_drake.simulation import quiet_drake_warnings
from corobot_drake.tuning.drive_tuning import (
    COROBOT_TOP_SPEED,
    COROBOT_UNTUNED_SCALING,
    measure_top_speed,
    plot_sweep,
    plot_top_speed,
    run_sweep,
    scaling_for,
)
from corobot_drake.tuning.sysid import DriveField, write_drive_fields

TOP_SPEED = Range(0.0, 5.0, low_open=True, unit="m/s", why="the top speed wanted")


def _parser() -> ToolParser:
    p = ToolParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenario", help="scenario file (None: the shipped default scene, which "
                   "--write never changes: name the file to write)")
    p.add_argument("--robot", help="robot name (None: the scenario's only robot)")
    p.add_argument("--scaling", type=bounded(AXLE_SPEED), default=None,
                   help="starting MotorTorqueScaling (None: the Corobot's untuned 20; another "
                   "robot's --target over its wheel radius, rolling without slip)")
    p.add_argument("--target", type=bounded(TOP_SPEED), default=None,
                   help="top speed wanted, m/s (None: the Corobot's 0.6096 = 2 ft/s; another "
                   "robot's top speed at power 1, as its robot file states it)")
    p.add_argument("--tolerance", type=bounded(Range(0.0, 0.5, low_open=True)), default=0.005,
                   help="relative")
    p.add_argument("--max-iterations", type=bounded(Range(1, 100), int), default=8,
                   help="iterations at most")
    p.add_argument("--settle", type=bounded(Range(0.0, 60.0, unit="s")), default=2.0,
                   help="s at full power before measuring (the ramp takes ~0.4-0.7 s)")
    p.add_argument("--measure", type=bounded(Range(0.0, 60.0, low_open=True, unit="s")),
                   default=1.0, help="s averaged for the top speed")
    p.add_argument("--plot", type=output_file,
                   default="out/tune_motor_torque_scaling.png",
                   help="PNG: speed against time per iteration (or against scaling, --sweep)")
    p.add_argument("--write", action="store_true",
                   help="write the value into --scenario (only that number changes)")
    p.add_argument("--sweep", action="store_true",
                   help="run the sweep study (the default scene's robot) instead of iterating")
    p.add_argument("--workers", type=bounded(WORKERS, int), default=None,
                   help="Ray workers for --sweep (None: the machine's cores)")
    p.add_argument("--out", type=output_directory,
                   default="out/motor_torque_scaling",
                   help="the sweep study's output directory")
    return p


def _robot_name(args) -> str | None:
    """The robot to tune, or None after printing why there is none; the --target and
    --scaling left out are that robot's (`_defaults`)."""
    try:
        scenario = load_scenario(args.scenario)
    except ScenarioError as e:
        print(f"error: {e}", file=sys.stderr)
        return None
    names = list(scenario.robots)
    robot_name = args.robot or (names[0] if len(names) == 1 else None)
    if robot_name not in scenario.robots:
        print(f"error: {args.scenario}: name a robot with --robot (robots: {', '.join(names)})",
              file=sys.stderr)
        return None
    _defaults(args, robot_spec(scenario.robots[robot_name].robot))
    return robot_name


def _defaults(args, spec) -> None:
    """The --target and --scaling left out: the Corobot's documented ones (its 2 ft/s and its
    untuned 20); another robot's top speed at power 1 (its robot file's `drive.top_speed`)
    and the scaling that gives it rolling without slip."""
    if spec.generated:
        target, scaling = COROBOT_TOP_SPEED, COROBOT_UNTUNED_SCALING
    else:
        target = spec.top_speed()
        scaling = (args.target or target) / spec.wheel_radius
    args.target = args.target or target
    args.scaling = args.scaling or scaling


def _tune(args, robot_name: str):
    """Iterates the scaling toward the target, printing each iteration; returns
    (scaling, measured top speed, converged, curves)."""
    scaling = args.scaling
    curves = []
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
            return scaling, measured, True, curves
        scaling = new
    return scaling, measured, False, curves


def _sweep(args, robot_name: str) -> int:
    """The sweep study, the interpolated scaling and its plot (and --write)."""
    scalings, speeds = run_sweep(Path(args.out), args.workers)
    for scaling, speed in zip(scalings, speeds, strict=True):
        print(f"scaling {scaling:g}: steady speed {speed:.4f} m/s")
    try:
        tuned = scaling_for(args.target, scalings, speeds)
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    plot_sweep(scalings, speeds, args.target, tuned, Path(args.plot))
    print(f"plot: {args.plot}")
    if args.write:
        _write(args, robot_name, tuned)
    print(f"motor_torque_scaling: {tuned:.4f}  (interpolated between the sweep's scalings for "
          f"{args.target:.4f} m/s)")
    return 0


def _write(args, robot_name: str, scaling: float) -> None:
    """Puts the value in --scenario (only that number changes); a scenario it cannot write:
    ScenarioError, one_line_errors' one line."""
    path = write_drive_fields(args.scenario, robot_name,
                              [DriveField("motor_torque_scaling", scaling)])
    print(f"wrote motor_torque_scaling {scaling:.4g} for {robot_name} in {path}")


@one_line_errors
def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    if args.write and args.scenario is None:
        print("error: --write: name the scenario file to write with --scenario (the shipped "
              "scenario is never written by default)", file=sys.stderr)
        return 2
    args.scenario = args.scenario or str(DEFAULT_SCENARIO)
    quiet_drake_warnings()
    robot_name = _robot_name(args)
    if robot_name is None:
        return 2
    if not (args.scaling > 0 and args.target > 0):
        print("error: --scaling and --target must be > 0", file=sys.stderr)
        return 2
    if args.sweep:
        if Path(args.scenario).resolve() != Path(DEFAULT_SCENARIO).resolve():
            print("error: --scenario: --sweep measures its study's scenario (the default scene; "
                  "edit scenarios/studies/motor_torque_scaling.yaml for another)", file=sys.stderr)
            return 2
        return _sweep(args, robot_name)
    scaling, measured, converged, curves = _tune(args, robot_name)
    plot_top_speed(curves, args.target, args.settle, Path(args.plot))
    print(f"plot: {args.plot}")
    if not converged:
        print(f"did not converge within {args.tolerance * 100:g}% in {args.max_iterations} "
              f"iterations", flush=True)
    else:
        print(f"converged in {len(curves)} iteration(s) (within {args.tolerance * 100:g}%)")
    if args.write:
        _write(args, robot_name, scaling)
    print(f"motor_torque_scaling: {scaling:.4f}  (top speed {measured:.4f} m/s, "
          f"target {args.target:.4f})")
    return 0 if converged else 1


if __name__ == "__main__":
    sys.exit(main())
