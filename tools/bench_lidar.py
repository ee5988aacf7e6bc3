"""Benchmark: what one planar lidar scan costs, and what a lidar costs a running simulation.

Run: ``.venv/bin/python tools/bench_lidar.py [--scans 2000] [--seconds 5] [--repeats 3]``.
It prints

1. the CPU time of one scan (median and best of ``--scans`` calls of the Lidar's own
   periodic-update handler: the body pose from the QueryObject, the rays posed, the exact
   cast of every ray, the noise, the state written), for a 360-ray full circle on the
   Corobot's platform in the default scene (scenarios/corobot.yaml: the ground, the giant
   box, the robot itself excluded), then with noise and dropouts, then in the lidar room
   (scenarios/corobot_lidar.yaml: four walls, a crate, a pillar, a step), and at 1080 rays;
2. in place: the default scene standing still for ``--seconds`` simulated s with and
   without the 10 Hz lidar, CPU s per simulated s (median of ``--repeats`` runs each, taken
   in turn), and from them the extra CPU per scan.

The target is a 360-ray scan within 1 ms of CPU.
"""

import os
import statistics
import sys
import time

from corobot_drake.arguments import BENCH_SECONDS, REPEATS, ToolParser, bounded, one_line_errors
from corobot_drake.config.scenario import load_scenario
from corobot_drake.limits import Range
from corobot_drake.resources import DEFAULT_SCENARIO, SCENARIOS_DIR
from corobot_drake.simulation import Simulation, quiet_drake_warnings

NO_CAMERA = "robots: {corobot: {cameras: {front: {rgb: false}}}}"
LIDAR = "robots: {corobot: {lidars: {top: {samples: %d, noise_std: %g, dropout: %g}}}}"
SCANS = Range(10, 1_000_000, why="handler calls, the median kept")


def scan_cost(scenario, samples: int = 360, noise: float = 0.0, dropout: float = 0.0,
              scans: int = 2000) -> tuple[float, float]:
    """(median, best) CPU s of one call of the lidar's periodic-scan handler, in `scenario`
    (a file) with the lidar `top` of `samples` rays, standing at its start."""
    sim = Simulation(load_scenario(scenario, overrides=[NO_CAMERA, LIDAR % (
        samples, noise, dropout)]))
    sim.advance(0.05)
    lidar = sim.station.robots["corobot"].sensors["lidars"]["top"].system
    context = lidar.GetMyContextFromRoot(sim.context)
    state = lidar.AllocateDiscreteVariables()
    state.SetFrom(context.get_discrete_state())
    times = []
    for _ in range(scans):
        start = time.process_time()
        lidar._periodic_scan(context, state)
        times.append(time.process_time() - start)
    return statistics.median(times), min(times)


def cpu_per_second(with_lidar: bool, seconds: float) -> float:
    """CPU s per simulated s of the default scene standing still (camera off)."""
    overrides = [NO_CAMERA] + ([LIDAR % (360, 0.0, 0.0)] if with_lidar else [])
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=overrides))
    sim.advance(0.1)
    start = time.process_time()
    sim.advance(seconds)
    return (time.process_time() - start) / seconds


def _print_scan_costs(scans: int) -> None:
    room = SCENARIOS_DIR / "corobot_lidar.yaml"
    for label, scenario, args in (
            ("360 rays, default scene", DEFAULT_SCENARIO, (360,)),
            ("360 rays, default scene, noise 0.01 m and 5% dropouts", DEFAULT_SCENARIO,
             (360, 0.01, 0.05)),
            ("360 rays, the lidar room (7 bodies)", room, (360,)),
            ("1080 rays, the lidar room", room, (1080,))):
        median, best = scan_cost(scenario, *args, scans=scans)
        print(f"one scan, {label}: {median * 1e6:.0f} us CPU (median of {scans}), "
              f"{best * 1e6:.0f} us (best)", flush=True)


@one_line_errors
def main(argv=None) -> int:
    parser = ToolParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scans", type=bounded(SCANS, int), default=2000,
                        help="handler calls per scan figure; the median")
    parser.add_argument("--seconds", type=bounded(BENCH_SECONDS), default=5.0,
                        help="simulated s per in-place run")
    parser.add_argument("--repeats", type=bounded(REPEATS, int), default=3,
                        help="in-place runs of each; the median")
    args = parser.parse_args(argv)
    quiet_drake_warnings()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    _print_scan_costs(args.scans)
    runs = {False: [], True: []}
    for _ in range(args.repeats):
        for with_lidar in runs:
            runs[with_lidar].append(cpu_per_second(with_lidar, args.seconds))
    without, with_ = (statistics.median(runs[k]) for k in (False, True))
    print(f"in place, default scene standing: {without * 1e3:.1f} ms CPU per simulated s "
          f"without a lidar, {with_ * 1e3:.1f} ms with a 10 Hz 360-ray lidar: "
          f"{(with_ - without) / 10 * 1e3:.3f} ms per scan (median of {args.repeats} runs of "
          f"{args.seconds:g} s; load average now {os.getloadavg()[0]:.1f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
