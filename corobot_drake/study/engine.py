"""Runs a study on Ray: a local instance started for the study (the default) or a cluster
joined by address. Rows are written to `runs.csv` as they arrive (the first at once, then at
most every `SAVE_EVERY` s), so a study stopped half way keeps what it finished and `resume`
runs the rest.
"""

from __future__ import annotations

import contextlib
import csv
import math
import operator
import os
import shutil
import time
from collections.abc import Iterator
from pathlib import Path

from tqdm import tqdm

from corobot_drake import limits
from corobot_drake.study import report
from corobot_drake.study.runner import TIMING_COLUMNS, StudyWorker, finite_or_text
from corobot_drake.study.spec import Run, Study, expand, load_study, scenario_path

SAVE_EVERY = 2.0
"""Wall-clock seconds between rewrites of runs.csv while runs arrive."""


def check_session(address, workers) -> int | None:
    """`workers` as an int (None stays None), after checking it is None or a whole number in
    `limits.WORKERS` (numpy's too) and that `address` is None or a string, as the command
    line's checks; ValueError naming the argument otherwise."""
    low, high = limits.WORKERS.low, limits.WORKERS.high
    if workers is not None:
        try:
            count = None if isinstance(workers, bool) else operator.index(workers)
        except TypeError:
            count = None
        if count is None or not low <= count <= high:
            raise ValueError(f"workers must be None (this machine's cores, or the cluster's "
                             f"CPUs) or a whole number in [{low}, {high}], got {workers!r}")
        workers = count
    if address is not None and not isinstance(address, str):
        raise ValueError(f"address must be None (a local Ray instance) or a Ray cluster's "
                         f"address as a string (e.g. '10.0.0.1:6379'), got {address!r}")
    return workers


def check_run(study_file, out_dir, workers, address, resume, progress) -> int | None:
    """`run_study`'s arguments: ValueError naming the first wrong one and what it allows (the
    study file's own content is `load_study`'s to check: ScenarioError); returns `workers` as
    `check_session` does."""
    for name, path in (("study_file", study_file), ("out_dir", out_dir)):
        if not isinstance(path, str | os.PathLike) or not str(path):
            raise ValueError(f"{name} must be a non-empty path (str or Path), got {path!r}")
    for name, flag in (("resume", resume), ("progress", progress)):
        if not isinstance(flag, bool):
            raise ValueError(f"{name} must be True or False, got {flag!r}")
    return check_session(address, workers)


@contextlib.contextmanager
def ray_session(address: str | None, workers: int | None) -> Iterator[int]:
    """Connects to Ray for the study; yields the number of workers to start. Without an
    address, starts a local instance with `workers` CPUs (default: this machine's cores) and
    stops it, with its processes, on exit. ValueError for a bad argument (`check_session`)."""
    workers = check_session(address, workers)
    import ray

    if ray.is_initialized():  # the caller's own Ray session (a notebook, a test): use it
        yield workers or int(ray.cluster_resources().get("CPU", 1))
        return
    if address:
        ray.init(address=address, include_dashboard=False, log_to_driver=False,
                 configure_logging=False)
    else:
        # "local": a new instance even when RAY_ADDRESS or a running cluster would be joined.
        ray.init(address="local", num_cpus=workers or os.cpu_count(), include_dashboard=False,
                 log_to_driver=False, configure_logging=False)
    try:
        yield workers or int(ray.cluster_resources().get("CPU", 1))
    finally:
        ray.shutdown()


def read_rows(path: Path) -> list[dict]:
    if not path.exists():
        return []
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


def columns(rows: list[dict], study: Study) -> list[str]:
    """run, seed, the parameters in study order, the metrics in order of appearance, status,
    error, then the timing columns."""
    fixed = ["run", "seed", *study.grid, *study.random]
    tail = ["status", "error", *TIMING_COLUMNS]
    metric_columns: dict[str, None] = {}
    for row in rows:
        metric_columns.update((k, None) for k in row if k not in fixed and k not in tail)
    return [*fixed, *metric_columns, *tail]


def write_rows(path: Path, rows: list[dict], study: Study) -> None:
    rows = sorted(rows, key=lambda r: int(r["run"]))
    tmp = path.with_suffix(".csv.tmp")
    with tmp.open("w", newline="") as f:
        writer = csv.DictWriter(f, columns(rows, study), restval="")
        writer.writeheader()
        writer.writerows({k: finite_or_text(v) for k, v in row.items()} for row in rows)
    tmp.replace(path)


def _results(todo: list[Run], study: Study, scenario_file: Path, workers: int) -> Iterator[dict]:
    """Rows as runs finish, in completion order, on `workers` Ray actors."""
    import ray
    from ray.util import ActorPool

    remote = ray.remote(num_cpus=1)(StudyWorker)
    actors = [remote.remote(study, str(scenario_file)) for _ in range(min(workers, len(todo)))]
    pool = ActorPool(actors)
    yield from pool.map_unordered(lambda actor, run: actor.run.remote(run), todo)


def run_study(study_file: str | Path, out_dir: str | Path, *, workers: int | None = None,
              address: str | None = None, resume: bool = False, progress: bool = True) -> Path:
    """Simulates every run of the study not yet in `out_dir/runs.csv` and writes the outputs
    (runs.csv, summary.md, plots, a copy of the study file); returns runs.csv's path.
    ValueError for a bad argument (`check_run`), before anything is read or started."""
    workers = check_run(study_file, out_dir, workers, address, resume, progress)
    study = load_study(study_file)
    scenario_file = scenario_path(study, study_file)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    runs_csv = out / "runs.csv"
    rows = read_rows(runs_csv) if resume else []
    finished = {int(r["run"]) for r in rows}
    todo = [run for run in expand(study) if run.index not in finished]
    copy = out / Path(study_file).name
    if not copy.exists() or not copy.samefile(study_file):
        shutil.copyfile(study_file, copy)
    if todo:
        _simulate_all(todo, study, scenario_file, rows, runs_csv, workers, address, progress)
    write_rows(runs_csv, rows, study)
    report.write(out, study, read_rows(runs_csv))
    return runs_csv


def _simulate_all(todo, study, scenario_file, rows, runs_csv, workers, address,
                  progress) -> None:
    saved = -math.inf  # the first row is written at once
    bar = tqdm(total=len(todo), unit="run", disable=not progress, smoothing=0.1)
    try:
        with ray_session(address, workers) as n:
            start = time.perf_counter()
            for row in _results(todo, study, scenario_file, n):
                # When the row arrived, from the workers' start: the study's steady rate is
                # read from these (`lab.bench_study`).
                row["finished_seconds"] = round(time.perf_counter() - start, 3)
                rows.append(row)
                bar.update()
                if time.monotonic() - saved > SAVE_EVERY:
                    write_rows(runs_csv, rows, study)
                    saved = time.monotonic()
    finally:  # Ctrl-C or an error: keep every finished row
        bar.close()
        write_rows(runs_csv, rows, study)
