#!/usr/bin/env python3
"""GoToGoal environment steps per second, in process, vectorized and on Ray.

One env in this process, AsyncVectorEnv with 1 and 2 envs, and rollouts on Ray with 1 and 2
workers (`corobot_drake.gym.bench`).

    python tools/bench_gym.py [--steps 100] [--episodes 4]
"""

import argparse
import os
import sys

from tqdm import tqdm

from corobot_drake.gym import bench
from corobot_drake.simulation import quiet_drake_warnings


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--steps", type=int, default=100,
                   help="env steps in process; vector steps per vector env")
    p.add_argument("--episodes", type=int, default=4,
                   help="episodes (60 steps each with random actions) per Ray run")
    args = p.parse_args(argv)
    quiet_drake_warnings()
    cases = [
        ("one env, this process", "startup", lambda: bench.in_process(args.steps)),
        ("AsyncVectorEnv, 1 env", "startup", lambda: bench.vector(1, args.steps)),
        ("AsyncVectorEnv, 2 envs", "startup", lambda: bench.vector(2, args.steps)),
        ("Ray rollouts, 1 worker (start-up included)", None,
         lambda: bench.on_ray(1, args.episodes)),
        ("Ray rollouts, 2 workers (start-up included)", None,
         lambda: bench.on_ray(2, args.episodes)),
    ]
    rows = []
    for name, setup, run in tqdm(cases, unit="case"):
        rows.append((name, setup, run()))
    print(f"Random actions, IR only (no camera), 0.1 s per step; {os.cpu_count()} cores, load "
          f"average {os.getloadavg()[0]:.1f} at the end")
    print("| how | env steps | wall (s) | env steps per s | start-up (s) |")
    print("|---|---|---|---|---|")
    for name, setup, r in rows:
        extra = f"{r[setup]:.1f}" if setup else "-"
        print(f"| {name} | {r['steps']} | {r['wall']:.1f} | {r['steps'] / r['wall']:.1f} | "
              f"{extra} |")
    rate = {name: r["steps"] / r["wall"] for name, _, r in rows}
    print(f"\n2 envs vs 1 (AsyncVectorEnv): "
          f"{rate['AsyncVectorEnv, 2 envs'] / rate['AsyncVectorEnv, 1 env']:.2f}x; 2 Ray workers "
          f"vs 1: {rate[rows[4][0]] / rate[rows[3][0]]:.2f}x.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
