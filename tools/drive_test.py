#!/usr/bin/env python3
"""The book's drive test: random legs out and back, and the drift they accumulate.

Each loop: rotate a random angle in [-45, 45] deg, drive a random 0.5-1.5 m, rotate 180 deg,
drive the same distance back, rotate 180 deg - angle (all at `--power`, default 0.2). The drift
is the distance from the start position after each loop. Same seed, same numbers.

    python tools/drive_test.py --loops 3 --seed 1 [--profile seed] [--plot path.png]
    python tools/drive_test.py --loops 3 --seeds 20 --jobs 2 [--profile seed]   # mean drift
"""

import argparse
import dataclasses as dc
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from corobot_drake.config import scenario as sc  # noqa: E402
from corobot_drake.simulation import Simulation, quiet_drake_warnings  # noqa: E402

SAMPLE_EVERY = 6
"""Path samples: one every this many control periods (0.1 s)."""


def fast_overrides(profile: str) -> list[str]:
    """The default scene with the chosen profile, without camera rendering (not needed here)."""
    robot = f"motion: {{profile: {profile}}}"
    if "camera" in {f.name for f in dc.fields(sc.Robot)}:
        robot += ", camera: {rgb: false}"
    return [f"robots: {{corobot: {{{robot}}}}}"]


def run(seed: int, loops: int, profile: str, power: float = 0.2, verbose: bool = True) -> dict:
    """Runs the test; returns {drift: [m after each loop], heading_error: [deg], path: [[x, y]],
    failures: [...], legs: [(angle_deg, distance_m)]}."""
    quiet_drake_warnings()
    sim = Simulation(sc.load_scenario(REPO / "scenarios" / "corobot.yaml",
                                      overrides=fast_overrides(profile)))
    robot = sim.robot()
    rng = np.random.default_rng(seed)
    x0, y0, _ = robot.position()
    heading0 = robot.heading()
    path, drift, heading_error, failures, legs = [[x0, y0]], [], [], [], []
    period = robot._parts.motion.drive_period

    def follow(handle):
        frames = 0
        while not handle.done():
            sim.advance(period)
            frames += 1
            if frames % SAMPLE_EVERY == 0:
                path.append(list(robot.position()[:2]))
        result = handle.result()
        if not result.succeeded:
            failures.append(f"{result.command} {result.status} {result.reason} "
                            f"at {result.end_time:.2f} s")

    for loop in range(1, loops + 1):
        angle = float(rng.uniform(-45.0, 45.0))
        distance = float(rng.uniform(0.5, 1.5))
        legs.append((angle, distance))
        follow(robot.rotate_degrees_async(angle, power))
        follow(robot.drive_distance_async(distance, power))
        follow(robot.rotate_degrees_async(180.0, power))
        follow(robot.drive_distance_async(distance, power))
        follow(robot.rotate_degrees_async(180.0 - angle, power))
        x, y, _ = robot.position()
        path.append([x, y])
        drift.append(math.hypot(x - x0, y - y0))
        heading_error.append(math.degrees(math.remainder(robot.heading() - heading0,
                                                         2 * math.pi)))
        if verbose:
            print(f"loop {loop}: angle {angle:+6.2f} deg, distance {distance:.3f} m -> "
                  f"drift {drift[-1] * 1000:7.2f} mm, heading error {heading_error[-1]:+.3f} deg",
                  flush=True)
    return {"seed": seed, "profile": profile, "drift": drift, "heading_error": heading_error,
            "path": path, "failures": failures, "legs": legs, "sim_time": sim.time}


def plot(result: dict, filename: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    xy = np.array(result["path"])
    fig, ax = plt.subplots(figsize=(6, 6))
    ax.plot(xy[:, 0], xy[:, 1], lw=1.0, label="path (GPS)")
    ax.plot(xy[0, 0], xy[0, 1], "g*", ms=14, label="start")
    ax.plot(xy[-1, 0], xy[-1, 1], "rx", ms=10, label="end")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, alpha=0.3)
    ax.set_title(f"drive test, profile {result['profile']}, seed {result['seed']}: "
                 f"drift {result['drift'][-1] * 1000:.1f} mm after {len(result['drift'])} loops",
                 fontsize=9)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(filename, dpi=120)
    plt.close(fig)


def _quiet_run(args):
    return run(*args, verbose=False)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--loops", type=int, default=3)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--profile", choices=sc.PROFILES, default="closed_loop")
    p.add_argument("--power", type=float, default=0.2)
    p.add_argument("--plot", default="drive_test.png", help="PNG of the path (single seed)")
    p.add_argument("--seeds", type=int, default=1,
                   help="run seeds SEED .. SEED+N-1 and report the mean drift (no plot)")
    p.add_argument("--jobs", type=int, default=1, help="processes for --seeds")
    args = p.parse_args(argv)
    if args.seeds == 1:
        result = run(args.seed, args.loops, args.profile, args.power)
        for failure in result["failures"]:
            print(f"failed: {failure}")
        drift = result["drift"][-1]
        print(f"summary: profile {args.profile}, seed {args.seed}, {args.loops} loops: "
              f"drift {drift * 1000:.2f} mm ({drift * 1000 / args.loops:.2f} mm per loop), "
              f"heading error {result['heading_error'][-1]:+.3f} deg, "
              f"{len(result['failures'])} failed commands, {result['sim_time']:.1f} s simulated")
        if args.plot:
            plot(result, args.plot)
            print(f"path plot: {args.plot}")
        return 0
    jobs = [(s, args.loops, args.profile, args.power)
            for s in range(args.seed, args.seed + args.seeds)]
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        results = list(pool.map(_quiet_run, jobs))
    drift = np.array([r["drift"] for r in results]) * 1000  # mm, seeds x loops
    for r, d in zip(results, drift, strict=True):
        print(f"seed {r['seed']:3d}: drift after each loop (mm) "
              + " ".join(f"{v:7.2f}" for v in d)
              + (f"  failures: {r['failures']}" if r["failures"] else ""))
    per_loop = drift[:, -1] / args.loops
    print(f"summary: profile {args.profile}, seeds {args.seed}..{args.seed + args.seeds - 1}, "
          f"{args.loops} loops: mean drift after each loop (mm) "
          + " ".join(f"{v:.2f}" for v in drift.mean(axis=0))
          + f"; drift per loop {per_loop.mean():.2f} mm mean, {per_loop.max():.2f} max; "
          f"{sum(len(r['failures']) for r in results)} failed commands")
    return 0


if __name__ == "__main__":
    sys.exit(main())
