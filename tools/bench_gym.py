#!/usr/bin/env python3
"""GoToGoal environment steps per second, in process, vectorized and on Ray.

One env in this process, AsyncVectorEnv with 1 and 2 envs, and rollouts on Ray with 1 and 2
workers (`lab.bench_gym`).

    python tools/bench_gym.py [--steps 100] [--episodes 4]
"""

import os
import sys

from corobot_drake.arguments import ToolParser, bounded, one_line_errors
from corobot_drake.limits import Range
from corobot_drake.simulation import quiet_drake_warnings

try:  # without the [gym] extra: one line naming it, not a traceback
    from tqdm import tqdm

    from lab import bench_gym as bench
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/bench_gym.py", "gym")

STEPS = Range(1, 1_000_000, why="env steps per case")
EPISODES = Range(1, 10_000, why="episodes per Ray run")


@one_line_errors
def main(argv=None) -> int:
    p = ToolParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=bounded(STEPS, int), default=100,
                   help="env steps in process; vector steps per vector env")
    p.add_argument("--episodes", type=bounded(EPISODES, int), default=4,
                   help="episodes (60 steps each with random actions) per Ray run")
    args = p.parse_args(argv)
    quiet_drake_warnings()
    cases = [
        ("one env, this process", lambda: bench.in_process(args.steps)),
        ("AsyncVectorEnv, 1 env", lambda: bench.vector(1, args.steps)),
        ("AsyncVectorEnv, 2 envs", lambda: bench.vector(2, args.steps)),
        ("Ray rollouts, 1 worker", lambda: bench.on_ray(1, args.episodes)),
        ("Ray rollouts, 2 workers", lambda: bench.on_ray(2, args.episodes)),
    ]
    rows = [(name, run()) for name, run in tqdm(cases, unit="case")]
    print(f"Random actions, IR only (no camera), 0.1 s per step; {os.cpu_count()} cores, load "
          f"average {os.getloadavg()[0]:.1f} at the end")
    print("| how | env steps | wall (s) | env steps per s | start-up (s) |")
    print("|---|---|---|---|---|")
    for name, r in rows:
        print(f"| {name} | {r['steps']} | {r['wall']:.1f} | {r['steps'] / r['wall']:.1f} | "
              f"{r['startup']:.1f} |")
    rate = {name: r["steps"] / r["wall"] for name, r in rows}
    vector = rate["AsyncVectorEnv, 2 envs"] / rate["AsyncVectorEnv, 1 env"]
    ray = rate["Ray rollouts, 2 workers"] / rate["Ray rollouts, 1 worker"]
    print(f"\n2 envs vs 1 (AsyncVectorEnv): {vector:.2f}x; 2 Ray workers vs 1: {ray:.2f}x "
          f"(start-up excluded).")
    return 0


if __name__ == "__main__":
    sys.exit(main())
