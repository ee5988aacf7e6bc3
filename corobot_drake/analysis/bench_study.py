"""The study engine's costs (`tools/bench_study.py`): the same runs in one process (building
every diagram, or resetting one) and on Ray with 1 and 2 workers, and what a cluster would do.
"""

import statistics
import tempfile
import time
from pathlib import Path

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


def write_study(folder: Path, seeds: int, duration: float) -> Path:
    path = folder / "bench_study.yaml"
    path.write_text(STUDY.format(scenario=DEFAULT_SCENARIO, seeds=seeds, duration=duration))
    return path


def in_process(study_file: Path, reuse: bool) -> dict:
    """Every run in this process; per-run setup (build or reset) and run seconds."""
    study = load_study(study_file)
    scenario_file = scenario_path(study, study_file)
    cache = SimulationCache() if reuse else None
    start = time.perf_counter()
    rows = [simulate(study, scenario_file, run, cache) for run in expand(study)]
    wall = time.perf_counter() - start
    return {"wall": wall, "runs": len(rows),
            "setup": statistics.median(r["setup_seconds"] for r in rows[1:]),
            "run": statistics.median(r["wall_seconds"] - r["setup_seconds"] for r in rows[1:])}


def on_ray(study_file: Path, workers: int) -> dict:
    """The study with `run_study` on a local Ray instance it starts and stops (start-up
    included in `wall`)."""
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        rows = engine.read_rows(engine.run_study(study_file, out, workers=workers,
                                                 progress=False))
        wall = time.perf_counter() - start
    return {"wall": wall, "runs": len(rows),
            "run": statistics.median(float(r["wall_seconds"]) for r in rows)}


def ray_start_seconds() -> float:
    """A local Ray instance's start and stop with one worker that imports the package."""
    import ray

    start = time.perf_counter()
    ray.init(num_cpus=1, include_dashboard=False, log_to_driver=False, configure_logging=False)

    @ray.remote
    def ready() -> bool:
        import corobot_drake.simulation  # noqa: F401 - what a study worker imports first
        return True

    ray.get(ready.remote())
    ray.shutdown()
    return time.perf_counter() - start
