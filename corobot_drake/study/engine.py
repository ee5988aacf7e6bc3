"""Runs a study on Ray: a local instance started for the study (the default) or a cluster
joined by address. Rows are written to `runs.csv` as they arrive (the first at once, then at
most every `SAVE_EVERY` s), so a study stopped half way keeps what it finished and `resume`
runs the rest.
"""

from __future__ import annotations

import collections
import contextlib
import csv
import io
import math
import operator
import os
import re
import shutil
import signal
import socket
import stat
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

from tqdm import tqdm

from corobot_drake import limits
from corobot_drake.config.scenario import one_line
from corobot_drake.study import report
from corobot_drake.study.metrics import load_user_metrics
from corobot_drake.study.runner import TIMING_COLUMNS, StudyWorker, error_row, finite_or_text
from corobot_drake.study.spec import (
    DIGEST_COLUMN,
    Run,
    Study,
    expand,
    load_study,
    scenario_path,
    study_digest,
    study_path,
)

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
    if address is not None:
        cluster_host_port(address)
    return workers


class AddressError(ValueError):
    """A Ray cluster's address that is malformed or where no cluster answers; the message
    starts with `address` (the command line's `--address`)."""


CONNECT_TIMEOUT = 5.0
"""s to wait for a cluster's head to accept a connection before saying it does not."""
_ADDRESS = re.compile(r"^(?:ray://)?(\[[0-9a-fA-F:.]+\]|[A-Za-z0-9._-]+):(\d{1,5})$")


def cluster_host_port(address: str) -> tuple[str, int]:
    """(host, port) of a Ray cluster's address (`host:port`, `[v6]:port` or
    `ray://host:port`); AddressError for anything else."""
    m = _ADDRESS.match(address)
    if not m or not 1 <= int(m.group(2)) <= 65535:
        raise AddressError(f"address {address!r}: not a Ray cluster's address; expected "
                           "HOST:PORT (e.g. 10.0.0.1:6379, what `ray start --head` prints) or "
                           "ray://HOST:PORT")
    return m.group(1).strip("[]"), int(m.group(2))


def _probe(address: str) -> None:
    """AddressError within CONNECT_TIMEOUT when nothing accepts a connection at `address`
    (Ray itself retries for minutes)."""
    host, port = cluster_host_port(address)
    try:
        socket.create_connection((host, port), timeout=CONNECT_TIMEOUT).close()
    except OSError as e:
        reason = "timed out" if isinstance(e, TimeoutError) else e.strerror or one_line(e)
        raise AddressError(f"address {address}: no Ray cluster answers there ({reason}); "
                           "start one with `ray start --head`, or leave the address out for "
                           "a local instance") from None


def _join(address: str) -> None:
    """ray.init on a cluster's address; AddressError (one line) when it cannot be joined."""
    import ray

    _probe(address)
    try:
        ray.init(address=address, include_dashboard=False, log_to_driver=False,
                 configure_logging=False)
    except Exception as e:  # a port that is not Ray's, a token the cluster refuses, ...
        raise AddressError(f"address {address}: cannot join the Ray cluster there "
                           f"({one_line(e)}); a cluster with token authentication needs "
                           "RAY_AUTH_MODE=token and its token here too (docs/studies.md)") from None


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


class RayStartError(RuntimeError):
    """Ray's local instance did not start (on a loaded machine its processes can take longer
    than Ray waits for them); the message is the one line to show."""


LOOPBACK_RAY_ENV = {
    # Ray's non-cluster mode (its default on macOS and Windows): the node's address, which
    # every Ray server binds and advertises, is 127.0.0.1. On Linux Ray otherwise takes the
    # interface's address and binds its gRPC servers on all interfaces.
    "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0",
    # No usage reports to usage-stats.ray.io (an instance ray.init starts then sends none).
    "RAY_USAGE_STATS_ENABLED": "0",
}
"""The environment of the Ray instances this project starts: loopback only."""


@contextlib.contextmanager
def loopback_ray(**env: str) -> Iterator[None]:
    """Ray instances started in this block listen on and connect to 127.0.0.1 only: their
    processes get LOOPBACK_RAY_ENV (and `env`), and this process Ray's non-cluster mode too
    (Ray reads that variable once, when imported). Joining such an instance by its address
    needs the block as well: Ray otherwise turns 127.0.0.1 into the interface's address."""
    from unittest import mock

    from ray._private import ray_constants

    with (mock.patch.dict(os.environ, {**LOOPBACK_RAY_ENV, **env}),
          mock.patch.object(ray_constants, "ENABLE_RAY_CLUSTER", False)):
        yield


def _start_local(workers: int | None) -> None:
    """ray.init of a new local instance on loopback (`loopback_ray`); RayStartError (one line)
    when it does not start."""
    import ray

    try:
        # "local": a new instance even when RAY_ADDRESS or a running cluster would be joined.
        with loopback_ray():
            ray.init(address="local", num_cpus=workers or os.cpu_count(),
                     include_dashboard=False, log_to_driver=False, configure_logging=False)
    except Exception as e:  # Ray raises bare Exceptions and TimeoutErrors starting up
        raise RayStartError(
            f"Ray's local instance did not start ({one_line(e)}); Ray waits a fixed time for "
            "its processes, which a busy machine can exceed: run the study again when the "
            "machine is less loaded, or start Ray yourself (`ray start --head`) and pass its "
            "address with --address") from None


@contextlib.contextmanager
def ray_session(address: str | None, workers: int | None) -> Iterator[int]:
    """Connects to Ray for the study; yields the number of workers to start. Without an
    address, starts a local instance with `workers` CPUs (default: this machine's cores) and
    stops it, with its processes, on exit. ValueError for a bad argument (`check_session`);
    RayStartError when the local instance does not start."""
    workers = check_session(address, workers)
    import ray

    if ray.is_initialized():  # the caller's own Ray session (a notebook, a test): use it
        yield workers or int(ray.cluster_resources().get("CPU", 1))
        return
    # ray.init sets a SIGTERM handler of its own (sys.exit: no line, no --resume hint); a
    # program's own (`cli.ctrl_c_stops`: stop cleanly, shut Ray down) is put back after it.
    on_sigterm = signal.getsignal(signal.SIGTERM)
    try:
        if address:
            _join(address)
        else:
            _start_local(workers)
        if callable(on_sigterm) and threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGTERM, on_sigterm)
        yield workers or int(ray.cluster_resources().get("CPU", 1))
    finally:  # also after a stop while Ray started
        ray.shutdown()


def read_rows(path: Path) -> list[dict]:
    if not path.exists():
        return []
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


class ResumeError(ValueError):
    """A runs.csv that `resume` cannot continue: not a runs table, or not this study's."""


MAX_RUNS_CSV = 1 << 30
"""Largest runs.csv `resume` reads (a row is ~1-4 kB; the most runs a study has, 100000, fit
in well under this)."""


def resumed_rows(path: Path, study: Study, runs: list[Run], digest: str) -> list[dict]:
    """The rows of `path` (none when it does not exist), each checked to be a run of this
    study: its run index one of `runs`, its seed and parameter values that run's, its
    `study_digest` `digest` (the rest of what makes the study), no run twice. ResumeError
    (one line, with the row's line) otherwise, or when the file is not a readable CSV table
    (a FIFO or a device: refused unread)."""
    if not path.exists():
        return []
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except OSError as e:
        raise ResumeError(f"{path}: cannot read it ({e.strerror})") from None
    with os.fdopen(fd, "rb") as f:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode) or info.st_size > MAX_RUNS_CSV:
            raise ResumeError(f"{path}: not a runs table (a regular file of at most "
                              f"{MAX_RUNS_CSV >> 20} MiB); resume reads the runs.csv a study "
                              "wrote")
        data = f.read()
    reader = csv.DictReader(io.StringIO(data.decode("utf-8", "replace"), newline=""),
                            strict=True)
    rows: list[dict] = []
    try:
        for row in reader:
            if None in row:  # more cells than the header has columns
                raise csv.Error(f"{len(row) - 1 + len(row[None])} cells under "
                                f"{len(row) - 1} columns")
            rows.append(row)
    except csv.Error as e:  # the row after the last good one (a study's cells are one line)
        raise ResumeError(f"{path}:{len(rows) + 2}: not a CSV runs table ({e})") from None
    _check_rows(path, rows, study, runs, reader.fieldnames or [], digest)
    return rows


def _check_rows(path: Path, rows: list[dict], study: Study, runs: list[Run],
                header: list[str], digest: str) -> None:
    """ResumeError at the first row (or the header) that is not one of this study's runs."""
    fixed = ["run", "seed", *study.grid, *study.random, "status", DIGEST_COLUMN]
    missing = [c for c in fixed if c not in header]
    if missing:
        raise ResumeError(f"{path}:1: no column {missing[0]!r}: not the runs table of this "
                          "study (its columns: " + ", ".join(fixed) + ", ...)")
    seen = set()
    for line, row in enumerate(rows, start=2):
        text = row.get("run") or ""
        run = runs[int(text)] if text.isdigit() and int(text) < len(runs) else None
        expected = {} if run is None else {"seed": str(run.seed), **{
            k: str(finite_or_text(v)) for k, v in run.params}}
        if run is not None:  # last: a parameter's value says more than the digest
            expected[DIGEST_COLUMN] = digest
        wrong = next((k for k, v in expected.items() if row.get(k) != v), None)
        if run is None or wrong or text in seen:
            what = (f"run {text!r} is not one of this study's {len(runs)} runs" if run is None
                    else f"run {text} is listed twice" if text in seen else
                    f"run {text}'s {wrong} is {row.get(wrong)!r}, this study's is "
                    f"{expected[wrong]!r}")
            if wrong == DIGEST_COLUMN:
                what += (" (its scenario file, overrides, duration, until, settle, metrics, "
                         "programs or cameras differ)")
            raise ResumeError(f"{path}:{line}: {what}: these rows are another study's; resume "
                              "with the study that wrote them, or write to another --out")
        seen.add(text)


def columns(rows: list[dict], study: Study) -> list[str]:
    """run, seed, the parameters in study order, the metrics in order of appearance, status,
    error, then the timing columns."""
    fixed = ["run", "seed", *study.grid, *study.random]
    tail = ["status", "error", DIGEST_COLUMN, *TIMING_COLUMNS]
    metric_columns: dict[str, None] = {}
    for row in rows:
        metric_columns.update((k, None) for k in row if k not in fixed and k not in tail)
    return [*fixed, *metric_columns, *tail]


def write_rows(path: Path, rows: list[dict], study: Study) -> None:
    rows = sorted(rows, key=lambda r: int(r["run"]))
    tmp = path.with_suffix(".csv.tmp")
    with report.writing(path, partial=tmp):  # a full disk leaves the last runs.csv whole
        with tmp.open("w", newline="") as f:
            writer = csv.DictWriter(f, columns(rows, study), restval="")
            writer.writeheader()
            writer.writerows({k: finite_or_text(v) for k, v in row.items()} for row in rows)
        tmp.replace(path)


RETRIES = 1
"""Times a run is tried again when its worker process dies under it (killed, out of memory,
a crash); then it is an error row and the study goes on."""


def _results(todo: list[Run], study: Study, scenario_file: Path, workers: int,
             user: dict) -> Iterator[dict]:
    """Rows as runs finish, in completion order, on `workers` Ray actors (an actor whose
    process dies is replaced by a new one, and the run it was doing tried again, RETRIES
    times)."""
    import ray
    from ray.exceptions import RayActorError

    for fn in user.values():  # the user's module travels with the study: workers need not
        ray.cloudpickle.register_pickle_by_value(sys.modules[fn.__module__])  # import it
    remote = ray.remote(num_cpus=1)(StudyWorker)
    idle = [remote.remote(study, str(scenario_file), user)
            for _ in range(min(workers, len(todo)))]
    queue, pending, deaths = collections.deque(todo), {}, collections.Counter()
    while queue or pending:
        while idle and queue:
            actor, run = idle.pop(), queue.popleft()
            pending[actor.run.remote(run)] = (actor, run)
        (ref,), _ = ray.wait(list(pending), num_returns=1)
        actor, run = pending.pop(ref)
        try:
            row = ray.get(ref)
            idle.append(actor)
        except RayActorError as e:  # its process died: a new worker takes its place
            ray.kill(actor)
            idle.append(remote.remote(study, str(scenario_file), user))
            deaths[run.index] += 1
            if deaths[run.index] <= RETRIES:
                queue.appendleft(run)
                continue
            row = error_row(run, f"its worker process died {deaths[run.index]} times running "
                            f"it ({one_line(e)})")
        yield row


def run_study(study_file: str | Path, out_dir: str | Path, *, workers: int | None = None,
              address: str | None = None, resume: bool = False, progress: bool = True) -> Path:
    """Simulates every run of the study not yet in `out_dir/runs.csv` and writes the outputs
    (runs.csv, summary.md, plots, a copy of the study file); returns runs.csv's path.
    ValueError for a bad argument (`check_run`), before anything is read or started;
    ScenarioError for a bad study file, AddressError when no Ray cluster answers at `address`,
    ResumeError for a runs.csv `resume` cannot continue, each before Ray starts or anything is
    written."""
    workers = check_run(study_file, out_dir, workers, address, resume, progress)
    study_file = study_path(study_file)
    study = load_study(study_file)
    scenario_file = scenario_path(study, study_file)
    user = load_user_metrics(study.metrics, Path(study_file).parent)
    if address and not ("ray" in sys.modules and sys.modules["ray"].is_initialized()):
        _probe(address)  # nothing is written for a study that cannot start
    out = Path(out_dir)
    runs_csv = out / "runs.csv"
    runs = expand(study)
    digest = study_digest(study, study_file)
    rows = resumed_rows(runs_csv, study, runs, digest) if resume else []
    out.mkdir(parents=True, exist_ok=True)
    finished = {int(r["run"]) for r in rows}
    todo = [run for run in runs if run.index not in finished]
    copy = out / Path(study_file).name
    if not copy.exists() or not copy.samefile(study_file):
        with report.writing(copy):
            shutil.copyfile(study_file, copy)
    if todo:
        _simulate_all(todo, study, scenario_file, rows, runs_csv, workers, address, progress,
                      user, digest)
    write_rows(runs_csv, rows, study)
    from corobot_drake.study.resolve import parameter_units

    report.write(out, study, read_rows(runs_csv), Path(study_file).stem,
                 parameter_units(study, study_file), user)
    return runs_csv


def _simulate_all(todo, study, scenario_file, rows, runs_csv, workers, address,
                  progress, user, digest) -> None:
    saved = -math.inf  # the first row is written at once
    bar = None
    try:
        with ray_session(address, workers) as n:
            # Once Ray has started: the lines it prints starting (token authentication's)
            # then come before the bar instead of inside it.
            bar = tqdm(total=len(todo), unit="run", disable=not progress, smoothing=0.1)
            start = time.perf_counter()
            for row in _results(todo, study, scenario_file, n, user):
                # When the row arrived, from the workers' start: the study's steady rate is
                # read from these (`lab.bench_study`).
                row["finished_seconds"] = round(time.perf_counter() - start, 3)
                row[DIGEST_COLUMN] = digest  # what `resume` checks the row against
                rows.append(row)
                bar.update()
                if time.monotonic() - saved > SAVE_EVERY:
                    write_rows(runs_csv, rows, study)
                    saved = time.monotonic()
    finally:  # Ctrl-C or an error: keep every finished row
        if bar is not None:
            bar.close()
        write_rows(runs_csv, rows, study)
