#!/usr/bin/env python3
"""The study engine's throughput: the same runs in one process (diagram built per run, or
reset) and on Ray with 1 and 2 workers; Ray's start-up; and the projected wall time of a big
study on a cluster (`corobot_drake.analysis.bench_study`).

    python tools/bench_study.py [--seeds 12] [--duration 4]
"""

import argparse
import os
import sys
import tempfile
from pathlib import Path

from corobot_drake.analysis import bench_study
from corobot_drake.simulation import quiet_drake_warnings


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--seeds", type=int, default=12, help="runs (seeds of one scenario)")
    p.add_argument("--duration", type=float, default=4.0, help="simulated s per run")
    args = p.parse_args(argv)
    quiet_drake_warnings()
    with tempfile.TemporaryDirectory() as folder:
        study = bench_study.write_study(Path(folder), args.seeds, args.duration)
        built = bench_study.in_process(study, reuse=False)
        reset = bench_study.in_process(study, reuse=True)
        one = bench_study.on_ray(study, 1)
        two = bench_study.on_ray(study, 2)
    start = bench_study.ray_start_seconds()
    n = args.seeds
    print(f"{n} runs of {args.duration:g} simulated s (default scene, driving, 2 IR, no camera),"
          f" {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}")
    print("| how | wall (s) | runs per s | per-run setup (s, median) |")
    print("|---|---|---|---|")
    for name, r in (("one process, a new diagram per run", built),
                    ("one process, diagram reset per run", reset),
                    ("Ray, 1 worker (start-up included)", one),
                    ("Ray, 2 workers (start-up included)", two)):
        setup = f"{r['setup']:.3f}" if "setup" in r else "-"
        print(f"| {name} | {r['wall']:.1f} | {n / r['wall']:.2f} | {setup} |")
    print(f"\nRay start + stop with one worker importing the package: {start:.1f} s. "
          f"2 workers vs 1: {one['wall'] / two['wall']:.2f}x; without start-up: "
          f"{(one['wall'] - start) / max(two['wall'] - start, 1e-9):.2f}x.")
    per_run = (two["wall"] - start) * 2 / n  # core-seconds per run on this machine
    cores, runs = 320, 10_000
    print(f"A {runs}-run study of these runs on 10 nodes x 32 cores, at this machine's "
          f"{per_run:.2f} core-s per run (Ray's per-task cost included, cores as fast as these, "
          f"every run the same length): ~{runs * per_run / cores / 60:.1f} min plus start-up.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
