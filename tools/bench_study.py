#!/usr/bin/env python3
"""The study engine's throughput in one process and on Ray with 1 and 2 workers.

The same runs in one process (diagram built per run, or reset) and on Ray with 1 and 2
workers, with and without Ray's start and stop, and steady (once every worker has started);
each run's CPU seconds; and the projected wall time of a big study on a cluster
(`lab.bench_study`).

    python tools/bench_study.py [--seeds 12] [--duration 4]
"""

import os
import sys
import tempfile
from pathlib import Path

try:  # without the [study] extra: one line naming it, not a traceback
    from tqdm import tqdm
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/bench_study.py", "study")

from corobot_drake.arguments import BENCH_SECONDS, ToolParser, bounded, one_line_errors
from corobot_drake.limits import Range
from corobot_drake.simulation import quiet_drake_warnings
from lab import bench_study

SEEDS = Range(1, 10_000, why="runs of the study")


@one_line_errors
def main(argv=None) -> int:
    p = ToolParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=bounded(SEEDS, int), default=12,
                   help="runs (seeds of one scenario)")
    p.add_argument("--duration", type=bounded(BENCH_SECONDS), default=4.0,
                   help="simulated s per run")
    args = p.parse_args(argv)
    quiet_drake_warnings()
    load = [os.getloadavg()[0]]
    with tempfile.TemporaryDirectory() as folder:
        study = bench_study.write_study(Path(folder), args.seeds, args.duration)
        cases = [("one process, a new diagram per run",
                  lambda: bench_study.in_process(study, reuse=False)),
                 ("one process, diagram reset per run",
                  lambda: bench_study.in_process(study, reuse=True)),
                 ("Ray, 1 worker", lambda: bench_study.on_ray(study, 1)),
                 ("Ray, 2 workers", lambda: bench_study.on_ray(study, 2))]
        results = {}
        for name, case in tqdm(cases, unit="case"):
            results[name] = case()
            load.append(os.getloadavg()[0])
    print_table(args, results, load)
    return 0


def print_table(args, results: dict, load: list[float]) -> None:
    n = args.seeds
    print(f"{n} runs of {args.duration:g} simulated s (default scene, driving, 2 IR, no camera),"
          f" {os.cpu_count()} cores, load average {min(load):.1f}-{max(load):.1f}, every case at"
          f" niceness {os.nice(0)} (Ray's workers too)")
    print("| how | wall (s) | runs per s | wall without Ray's start and stop (s) | "
          "runs per s, steady | per-run setup (s, median) | per-run CPU (s, median) |")
    print("|---|---|---|---|---|---|---|")
    for name, r in results.items():
        study = f"{r['study']:.1f}" if "study" in r else "-"
        steady = f"{r['steady']:.2f}" if r.get("steady") else "-"
        print(f"| {name} | {r['wall']:.1f} | {n / r['wall']:.2f} | {study} | {steady} | "
              f"{r['setup']:.3f} | {r['cpu']:.2f} |")
    one, two = results["Ray, 1 worker"], results["Ray, 2 workers"]
    steady = (f"{two['steady'] / one['steady']:.2f}x" if one.get("steady") and two.get("steady")
              else "-")
    print(f"\nRay's start and stop: {one['start']:.1f} s (1 worker), {two['start']:.1f} s (2). "
          f"2 workers vs 1: {one['wall'] / two['wall']:.2f}x; without Ray's start and stop: "
          f"{one['study'] / two['study']:.2f}x; steady (past each worker's first run, which "
          f"carries its start-up): {steady}. A run's CPU on a Ray worker vs in one process: "
          f"{one['cpu'] / results['one process, diagram reset per run']['cpu']:.2f}x.")
    # Core-seconds per run on this machine: the steady rate, as a long study runs.
    per_run = 2 / two["steady"] if two.get("steady") else two["study"] * 2 / n
    cores, runs = 320, 10_000
    print(f"A {runs}-run study of these runs on 10 nodes x 32 cores, at this machine's "
          f"{per_run:.2f} core-s per run (Ray's per-task cost included, cores as fast as these, "
          f"every run the same length): ~{runs * per_run / cores / 60:.1f} min plus start-up.")


if __name__ == "__main__":
    sys.exit(main())
