"""The book's drive test: random legs out and back, and the drift they accumulate
(`tools/drive_test.py`).

Each loop: rotate a random angle in [-45, 45] deg, drive a random 0.5-1.5 m, rotate 180 deg,
drive the same distance back, rotate 180 deg - angle (all at `power`, default 0.2). The drift
is the distance from the start position after each loop. Same seed, same numbers.
"""

import json
from pathlib import Path

import numpy as np
from tqdm import tqdm

from corobot_drake.config import scenario as sc
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.simulation import Simulation, quiet_drake_warnings
from corobot_drake.study import engine
from corobot_drake.study.metrics import METRICS, RobotRun
from corobot_drake.study.programs import DriveTest
from corobot_drake.study.runner import commands_ended

ROBOT = "corobot"
PATH_PERIOD = 0.1
"""s between the path's samples."""


def fast_overrides(profile: str) -> list[str]:
    """The default scene with the chosen profile, without camera rendering (not needed here)."""
    return [f"robots: {{{ROBOT}: {{motion: {{profile: {profile}}}, "
            "cameras: {front: {rgb: false}}}}"]


def run(seed: int, loops: int, profile: str, power: float = 0.2, verbose: bool = True,
        overrides: list[str] = ()) -> dict:
    """Runs the test (the legs as the robot's script, as a study's `drive_test` runs it) on
    the default scene with `overrides` (scenario YAML) merged on top; returns {drift: [m after
    each loop], heading_error: [deg], path: [[x, y]], failures: [...], legs: [(angle_deg,
    distance_m)]}."""
    quiet_drake_warnings()
    test = DriveTest(loops, power, ROBOT)
    scenario = sc.load_scenario(DEFAULT_SCENARIO,
                                overrides=[*fast_overrides(profile), *overrides])
    scenario.robots[ROBOT].commands = test.commands(seed)
    sim = Simulation(scenario)
    robot = sim.robot()
    measured = RobotRun(sim, robot, robot.pose(), robot.heading())
    path = [list(robot.position()[:2])]
    done = tqdm(total=len(test.commands(seed)), unit="command", disable=not verbose,
                desc=f"seed {seed}")
    while not commands_ended(sim):
        sim.advance(PATH_PERIOD)
        path.append(list(robot.position()[:2]))
        done.update(sum(r.end_time is not None for r in robot.command_log()) - done.n)
    done.close()
    drift = [v / 1000.0 for v in METRICS["drive_test_drift"](measured).values()]
    heading_error = list(METRICS["drive_test_heading_error"](measured).values())
    commands = scenario.robots[ROBOT].commands
    legs = [(commands[5 * k].degrees, commands[5 * k + 1].distance) for k in range(loops)]
    failures = [f"{r.command} {r.status} {r.reason} at {r.end_time:.2f} s"
                for r in robot.command_log() if r.status == "failed"]
    if verbose:
        for loop, ((angle, distance), d, h) in enumerate(zip(legs, drift, heading_error,
                                                             strict=True), 1):
            print(f"loop {loop}: angle {angle:+6.2f} deg, distance {distance:.3f} m -> "
                  f"drift {d * 1000:7.2f} mm, heading error {h:+.3f} deg", flush=True)
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


def plot_drift(table: list[dict], profile: str, filename: str | Path) -> None:
    """Drift from the start after each loop: every seed (thin) and the mean +- sd over seeds."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    drift = np.array([r["drift_mm"] for r in table])  # seeds x loops
    loops = np.arange(1, drift.shape[1] + 1)
    fig, ax = plt.subplots(figsize=(6, 4))
    for row in drift:
        ax.plot(loops, row, color="0.7", linewidth=0.8)
    mean, sd = np.nanmean(drift, axis=0), np.nanstd(drift, axis=0, ddof=1 if len(drift) > 1
                                                    else 0)
    ax.errorbar(loops, mean, yerr=sd, color="k", marker="o", capsize=4,
                label=f"mean +- sd over {len(drift)} seeds")
    ax.set_xticks(loops)
    ax.set_xlabel("loop")
    ax.set_ylabel("drift from the start (mm)")
    ax.set_title(f"drive test, profile {profile}: drift per loop "
                 f"{np.nanmean(drift[:, -1]) / drift.shape[1]:.2f} mm (mean)", fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    Path(filename).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(filename, dpi=110)
    plt.close(fig)


def study_text(seeds: list[int], loops: int, profile: str, power: float,
               overrides: list[str] = ()) -> str:
    """The drive test over `seeds` as a study file (see scenarios/studies/drive_test.yaml),
    with `overrides` (scenario YAML) merged into every run."""
    return "\n".join([
        f"scenario: {DEFAULT_SCENARIO}",
        "duration: 900.0", "until: commands", "settle: 0.0",
        f"seeds: {list(seeds)}",
        f"grid: {{robots.{ROBOT}.motion.profile: [{profile}]}}",
        f"drive_test: {{loops: {loops}, power: {power}, robot: {ROBOT}}}",
        "metrics: [drive_test_drift, drive_test_heading_error, command_status]",
        f"overrides: {json.dumps(list(overrides))}", ""])  # a JSON list is YAML


def run_study_of_seeds(seeds: list[int], loops: int, profile: str, power: float, out: Path,
                       workers: int | None = None, overrides: list[str] = ()) -> list[dict]:
    """The drive test for each seed as a study on Ray (files in `out`), `overrides` merged
    into every run; per seed: {seed, drift_mm: [after each loop], failures: [index:
    status]}."""
    out.mkdir(parents=True, exist_ok=True)
    study_file = out / "drive_test.yaml"
    study_file.write_text(study_text(seeds, loops, profile, power, overrides))
    rows = engine.read_rows(engine.run_study(study_file, out, workers=workers))
    table = []
    for row in rows:
        drift = [float(row.get(f"{ROBOT}.drive_test_drift.{k}") or "nan")
                 for k in range(1, loops + 1)]
        failures = [f"{key.rsplit('.', 1)[1]}: {v}" for key, v in row.items()
                    if ".command_status." in key and v != "succeeded"]
        if row["status"] != "ok":
            failures.append(row["error"])
        table.append({"seed": int(row["seed"]), "drift_mm": drift, "failures": failures})
    return table
