"""The study engine's costs (`tools/bench_study.py`): the same runs in one process (building
every diagram, or resetting one) and on Ray with 1 and 2 workers, and what a cluster would do.

Every case runs at this process's niceness: Ray's workers too (`RAY_worker_niceness`; a study
runs them at Ray's default, 15), so on a shared machine both compete alike for the cores and
the in-process and Ray figures compare. Each case gives its wall time and the median CPU
seconds of a run in its process (`cpu_seconds` of runs.csv), which the machine's load changes
much less than wall time.
"""

import os
import statistics
import tempfile
import time
from pathlib import Path
from unittest import mock

from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.study import engine
from corobot_drake.study.runner import SimulationCache, simulate
from corobot_drake.study.spec import expand, load_study, scenario_path

STUDY = """\
scenario: {scenario}
duration: {duration}
seeds: {seeds}
overrides:
  - "robots: {{corobot: {{commands: [!SetPower {{left: 1.0, right: 0.8}}]}}}}"
metrics: [x, y, speed, max_tilt_deg, ir]
"""
WORKER_NICENESS = "RAY_worker_niceness"
"""Ray's setting (an environment variable, read as Ray starts; its case is Ray's) of its
workers' niceness."""


def write_study(folder: Path, seeds: int, duration: float) -> Path:
    path = folder / "bench_study.yaml"
    path.write_text(STUDY.format(scenario=DEFAULT_SCENARIO, seeds=seeds, duration=duration))
    return path


def _medians(rows: list[dict]) -> dict:
    """Median setup and CPU seconds of the runs that reset a diagram (without a reset: of
    the runs after the first, whose process may still be warming up)."""
    later = [r for r in rows if r.get("setup") == "reset"] or rows[1:] or rows
    return {"setup": statistics.median(float(r["setup_seconds"]) for r in later),
            "cpu": statistics.median(float(r["cpu_seconds"]) for r in later)}


def in_process(study_file: Path, reuse: bool) -> dict:
    """Every run in this process; wall seconds, and each run's median setup (build or reset)
    and CPU seconds."""
    study = load_study(study_file)
    scenario_file = scenario_path(study, study_file)
    cache = SimulationCache() if reuse else None
    start = time.perf_counter()
    rows = [simulate(study, scenario_file, run, cache) for run in expand(study)]
    return {"wall": time.perf_counter() - start, "runs": len(rows), **_medians(rows)}


def on_ray(study_file: Path, workers: int) -> dict:
    """The study with `run_study` on a local Ray instance of `workers` CPUs started here, its
    workers at this process's niceness. `wall` is the whole (Ray's start and stop included),
    `study` the study alone (its workers' start-up included: their imports and first build),
    `start` Ray's start and stop, `steady` the runs per second past the workers' start-up
    (`steady_rate`)."""
    with (tempfile.TemporaryDirectory() as out,
          mock.patch.dict(os.environ, {WORKER_NICENESS: str(os.nice(0))})):
        begin = time.perf_counter()
        with engine.ray_session(None, workers):
            started = time.perf_counter()
            rows = engine.read_rows(engine.run_study(study_file, out, workers=workers,
                                                     progress=False))
            ended = time.perf_counter()
        wall = time.perf_counter() - begin
    return {"wall": wall, "study": ended - started, "start": wall - (ended - started),
            "steady": steady_rate(rows, workers), "runs": len(rows), **_medians(rows)}


def steady_rate(rows: list[dict], workers: int) -> float | None:
    """Runs per second after the first `workers` rows arrived (`finished_seconds`): the rate a
    long study keeps once every worker has started (its first run carries its imports and first
    build). An approximation: the first rows are taken to be one per worker, as they are when
    the workers start together (a row does not say which worker ran it). None when no run
    finished after them."""
    times = sorted(float(r["finished_seconds"]) for r in rows)
    if len(times) <= workers or times[-1] <= times[workers - 1]:
        return None
    return (len(times) - workers) / (times[-1] - times[workers - 1])
