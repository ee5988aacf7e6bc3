"""Where the CPU goes in a step, sampled by Linux `perf` (`tools/profile_step.py`).

`tools/bench.py --layers` says how much the robot's systems add to the plant's CPU time, and
`tools/count_instructions.py` counts their instructions and callgrind's modelled cache misses.
Neither says where the added time is spent on the real processor. This does: each run is a
child process (`python -m lab.profile_step ROW SECONDS`) that builds its row (the plant alone
or the station, as `bench_layers` builds them) and waits. `perf record` then attaches to it and
samples its CPU clock (`cpu-clock`) while it simulates `seconds`. Each sample counts for the
function it landed in (its own time: Drake's library has no frame pointers, so call chains,
and with them a function's time including what it calls, are not reliable), sorted into the
`KINDS` below by library and name.

Sampling is statistical: a kind's time in one run moves by several percent. The rows run
interleaved, `repeats` rounds, and the table gives medians.
"""

import os
import re
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from lab import bench_layers

PLANT = bench_layers.LAYERS[0]
STATION = bench_layers.STATION
ROWS = (PLANT, STATION)
WARM_UP = 0.2
"""s simulated before sampling (the tyres settle; first-time allocations)."""
SAMPLE_RATE = 1000
"""Samples per CPU second."""

TRACKING = ("DependencyTracker::", "PropagateTimeChange", "PropagateBulkChange",
            "ContextBase::NoteAll")
"""Drake's dependency tracking: every change of the Context's time and state is noted in every
subsystem's Context and passed on to whatever depends on it, down the diagram's wiring (a
Context's trackers; CENIC changes time and state inside its step, the Simulator at events)."""
PYTHON_LIBRARIES = ("libpython", "nanobind", "framework.so", "__init__.so", "analysis.so",
                    "primitives.so", "_multiarray_umath", "_umath")
"""The interpreter, pydrake's bindings and numpy: the Python systems' updates and outputs."""
PHYSICS = ("drake::multibody", "drake::geometry", "drake::math::", "Eigen::",
           "drake::SortedPair")
"""The plant's step: contact geometry, the contact problem and its solver, kinematics."""
KINDS = ("the plant's physics (contact, solver, kinematics)",
         "Drake's dependency tracking (noting time and state changes)",
         "Drake's systems framework (events, ports, caches)",
         "Python and its bindings (the Python systems)",
         "memory allocation and the rest")
"""How `classify` sorts a sample, in the table's order."""
ALL = "all of the run"
"""The sum of the `KINDS`: the child's CPU time while it simulated."""


def classify(library: str, function: str) -> str:
    """The `KINDS` entry of a sample in `library` (file name) and `function` (demangled)."""
    if any(name in function for name in TRACKING):
        return KINDS[1]
    if any(name in library for name in PYTHON_LIBRARIES):
        return KINDS[3]
    if "libdrake" in library and any(name in function for name in PHYSICS):
        return KINDS[0]
    if "libdrake" in library and "drake::systems::" in function:
        return KINDS[2]
    return KINDS[4]


class PerfMissingError(RuntimeError):
    """Linux `perf` is not installed, or cannot sample this process."""


def require_perf() -> None:
    """PerfMissingError unless `perf` is installed."""
    if not shutil.which("perf"):
        raise PerfMissingError("profiling needs Linux perf (e.g. apt install linux-perf)")


def record(row: str, seconds: float, out: Path) -> float:
    """Samples `seconds` of `row` (`ROWS`) into the perf data file `out`; returns the CPU s the
    child spent in them (its own clock)."""
    child = subprocess.Popen([sys.executable, "-m", __name__, row, str(seconds)],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    perf = None
    try:
        if child.stdout.readline().strip() != "ready":
            raise RuntimeError(f"profile_step: the child for {row!r} did not start")
        perf = subprocess.Popen(
            ["perf", "record", "-q", "-e", "cpu-clock", "-F", str(SAMPLE_RATE),
             "-p", str(child.pid), "-o", str(out)],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        time.sleep(0.5)  # perf attaches before the run starts
        if perf.poll() is not None:
            raise PerfMissingError(f"perf record failed: {perf.stderr.read().strip()[-200:]}")
        child.stdin.write("go\n")
        child.stdin.flush()
        cpu = float(child.stdout.readline())
        child.stdin.close()
        child.wait(timeout=60)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
        if perf is not None and perf.poll() is None:
            perf.send_signal(signal.SIGINT)  # perf writes its file on SIGINT
            perf.wait(timeout=60)
    return cpu


def kinds(perf_data: Path) -> dict[str, float]:
    """{each of `KINDS`: CPU ms} sampled in `perf_data`."""
    report = subprocess.run(
        ["perf", "report", "-i", str(perf_data), "--no-children", "--sort=dso,sym", "-g",
         "none", "--stdio", "-F", "sample,dso,sym"],
        capture_output=True, text=True, check=True).stdout
    return parse(report)


def parse(report: str) -> dict[str, float]:
    """`kinds` from the text of `perf report --no-children --sort=dso,sym -F sample,dso,sym
    --stdio`: its total (cpu-clock's event count, ns) shared out by each function's samples;
    `ALL` is their sum."""
    total = re.search(r"Event count \(approx\.\): (\d+)", report)
    rows = [(int(m.group(1)), classify(m.group(2), m.group(3))) for m in (
        re.match(r"\s*(\d+)\s+(\S+)\s+\[.\]\s+(.*)", line) for line in report.splitlines())
        if m]
    samples = sum(n for n, _ in rows)
    if not total or not samples:
        raise RuntimeError("profile_step: perf recorded no samples")
    ms_per_sample = int(total.group(1)) / 1e6 / samples
    result = dict.fromkeys(KINDS, 0.0)
    for n, kind in rows:
        result[kind] += n * ms_per_sample
    result[ALL] = sum(result.values())
    return result


def profile(seconds: float, repeats: int, progress=None) -> dict[str, dict[str, float]]:
    """{row: {kind: median CPU ms per simulated second}} over `repeats` interleaved rounds of
    `ROWS`, each `seconds` simulated; `progress()` after each run."""
    require_perf()
    runs = {row: [] for row in ROWS}
    with tempfile.TemporaryDirectory() as folder:
        for _ in range(repeats):
            for row in ROWS:
                out = Path(folder) / "perf.data"
                record(row, seconds, out)
                runs[row].append({k: v / seconds for k, v in kinds(out).items()})
                if progress:
                    progress()
    return {row: {k: statistics.median(r[k] for r in rows) for k in rows[0]}
            for row, rows in runs.items()}


def _child(row: str, seconds: float) -> None:
    """Builds `row`, warms up, says ready, waits for a line, simulates `seconds`, prints the
    CPU s that took."""
    run = bench_layers.warmed_up(row, bench_layers._scenario(), WARM_UP, seconds)
    print("ready", flush=True)
    sys.stdin.readline()
    start = time.process_time()
    run()
    print(time.process_time() - start, flush=True)
    sys.stdin.read()  # exits when the parent closes the pipe, after perf has the samples
    os._exit(0)  # skips the interpreter's teardown: nothing left to sample


if __name__ == "__main__":
    from corobot_drake.simulation import quiet_drake_warnings

    quiet_drake_warnings()
    _child(sys.argv[1], float(sys.argv[2]))
