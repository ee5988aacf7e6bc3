"""The book's drive test: random legs out and back, and the drift they accumulate
(`tools/drive_test.py`).

Each loop: rotate a random angle in [-45, 45] deg, drive a random 0.5-1.5 m, rotate 180 deg,
drive the same distance back, rotate 180 deg - angle (all at `power`, default 0.2). The drift
is the distance from the start position after each loop. Same seed, same numbers.
"""

import math
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from corobot_drake.config import scenario as sc
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.simulation import Simulation, quiet_drake_warnings

ROBOT = "corobot"
SAMPLE_EVERY = 6
"""Path samples: one every this many control periods (0.1 s)."""


def fast_overrides(profile: str) -> list[str]:
    """The default scene with the chosen profile, without camera rendering (not needed here)."""
    return [f"robots: {{{ROBOT}: {{motion: {{profile: {profile}}}, camera: {{rgb: false}}}}}}"]


def run(seed: int, loops: int, profile: str, power: float = 0.2, verbose: bool = True) -> dict:
    """Runs the test; returns {drift: [m after each loop], heading_error: [deg], path: [[x, y]],
    failures: [...], legs: [(angle_deg, distance_m)]}."""
    quiet_drake_warnings()
    sim = Simulation(sc.load_scenario(DEFAULT_SCENARIO, overrides=fast_overrides(profile)))
    robot = sim.robot()
    rng = np.random.default_rng(seed)
    x0, y0, _ = robot.position()
    heading0 = robot.heading()
    path, drift, heading_error, failures, legs = [[x0, y0]], [], [], [], []
    period = sim.station.robots[ROBOT].motion.drive_period

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


def _quiet_run(args) -> dict:
    return run(*args, verbose=False)


def run_seeds(seeds: range, loops: int, profile: str, power: float, jobs: int) -> list[dict]:
    """`run` for each seed, quietly, in `jobs` processes; the results in seed order."""
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        return list(pool.map(_quiet_run, [(s, loops, profile, power) for s in seeds]))
