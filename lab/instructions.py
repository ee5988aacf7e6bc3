"""Instructions per simulated second, counted by callgrind (`tools/count_instructions.py`).

Wall and CPU time move by 10-30% between identical runs on a shared machine; the instructions a
simulation executes do not (two counts of one row agree within 0.1% on one machine). So a change
to the code is measured here first; its effect on time, which also depends on caches and the
machine, is measured by `tools/bench.py`.

Each row is a child process under callgrind (`python -m lab.instructions
ROW SECONDS`), started with instrumentation off: it builds the row's diagram (a layer of
`bench_layers.LAYERS`, or the station, optionally with a scenario override), advances to
`WARM_UP` s, and counts only `seconds` of simulation after that (`callgrind_control -i on/off`
around the advance): the first segment of the benchmark's figure of eight (SetPower 1.0/0.6,
the first 3 s), building and start-up excluded.
"""

import os
import re
import shutil
import subprocess
import sys
import tempfile
import typing
from pathlib import Path

from lab import bench_layers

WARM_UP = 0.05
"""s simulated before counting: the first steps (the tyres settling) are not the run's."""
LONGEST = 2.9
"""s: the most a row counts (the figure of eight's first segment ends at 3 s)."""
STATION = "station"


class ValgrindMissingError(RuntimeError):
    """valgrind (with callgrind_control) is not installed."""


def rows() -> list[str]:
    """Row names: the layers (cumulative), the station, then the plant alone with Python
    updates that change nothing (`bench_layers.FLOORS`)."""
    return [*bench_layers.LAYERS, STATION, *bench_layers.FLOORS]


PLANT_STEPS = ("CenicIntegrator<double>::DoStep",
               "MultibodyPlant<double>::CalcStepUnrestricted",
               "MultibodyPlant<double>::CalcStepDiscrete")
"""The plant's step (its contact problem, the solve, the new state): CENIC's step on a
continuous plant; on SAP's discrete plant, with sampled output ports (Drake's default) an
unrestricted update, without them a discrete one. Callgrind's inclusive count of it is the
plant's share of a row; the rest is the framework's and the project's systems'."""

EVENT_HANDLERS = ("Simulator<double>::HandleDiscreteUpdate",
                  "Simulator<double>::HandleUnrestrictedUpdate",
                  "Simulator<double>::HandlePublish")
"""The Simulator's handlers of the systems' events (the robot's updates, the log sinks'
samples): of the rest, what the systems' events cost, each handler's inclusive count."""


def require_valgrind() -> None:
    """ValgrindMissingError unless valgrind and its two scripts are installed."""
    if not all(shutil.which(t) for t in ("valgrind", "callgrind_control", "callgrind_annotate")):
        raise ValgrindMissingError("counting instructions needs valgrind (with its "
                                   "callgrind_control and callgrind_annotate); install it "
                                   "(e.g. apt install valgrind)")


class Count(typing.NamedTuple):
    """What callgrind counted over a row's `seconds`."""

    instructions: int
    plant_step: int
    """Of them, in the plant's step (`PLANT_STEPS`, inclusive)."""
    i1_misses: int | None = None
    """First-level instruction-cache misses (callgrind's cache model; None: not simulated)."""
    event_handlers: int = 0
    """Of the instructions, in the systems' events: the Simulator's event handlers
    (`EVENT_HANDLERS`, inclusive), without a discrete plant's step (which is an update)."""
    event_i1_misses: int | None = None
    """Of the misses, in the systems' events (None: not simulated)."""


def count(row: str, seconds: float, override: str | None = None,
          cache: bool = False) -> Count:
    """Instructions executed simulating `seconds` (<= `LONGEST`) of `row` (`rows()`; an
    `override`, scenario YAML, applies to the station row only); with `cache`, also callgrind's
    first-level instruction-cache misses (its cache model, ~2x slower to run)."""
    require_valgrind()
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "callgrind.out"
        argv = ["valgrind", "--tool=callgrind", "--instr-atstart=no",
                *(["--cache-sim=yes"] if cache else []),
                f"--callgrind-out-file={out}", sys.executable, "-m", __name__, row,
                str(seconds), *([override] if override else [])]
        done = subprocess.run(argv, capture_output=True, text=True)
        if done.returncode != 0 or not out.exists():
            raise RuntimeError(f"callgrind failed on {row!r}: {done.stderr.strip()[-300:]}")
        annotated = subprocess.run(
            ["callgrind_annotate", "--inclusive=yes", "--threshold=100",
             f"--show={'Ir,I1mr' if cache else 'Ir'}", str(out)],
            capture_output=True, text=True, check=True).stdout
    return _parse(row, annotated, cache)


def _parse(row: str, annotated: str, cache: bool) -> Count:
    """The `Count` in `callgrind_annotate --inclusive=yes --show=Ir[,I1mr]` output: the
    totals' line and the plant step's (each number is followed by its percentage)."""
    def numbers(line: str) -> list[int]:
        return [int(n.replace(",", "")) for n in re.findall(r"([\d,]+) \(", line)]

    totals = [numbers(line) for line in annotated.splitlines() if "PROGRAM TOTALS" in line]
    if not totals:
        raise RuntimeError(f"callgrind counted nothing on {row!r}")
    lines = annotated.splitlines()
    step = max(([*numbers(line), 0][:2] for line in lines if any(f in line for f in PLANT_STEPS)),
               default=[0, 0])
    # Each handler's outermost line: a recursive call's (name'2) is inside it.
    handlers = [max(([*numbers(line), 0][:2] for line in lines if f"{name}(" in line),
                    default=[0, 0]) for name in EVENT_HANDLERS]
    events = [sum(h[i] for h in handlers) for i in (0, 1)]
    if not any(f"{PLANT_STEPS[0]}(" in line for line in lines):
        # A discrete plant steps in an update event: the systems' events are the rest of them.
        events = [events[0] - step[0], events[1] - step[1]]
    return Count(totals[0][0], step[0], totals[0][1] if cache else None, events[0],
                 events[1] if cache else None)


def _instrument(on: bool) -> None:
    subprocess.run(["callgrind_control", "-i", "on" if on else "off", str(os.getpid())],
                   check=True, capture_output=True)


def _child(row: str, seconds: float, override: str | None) -> None:
    """Builds `row`, warms up, counts `seconds` of simulation (under callgrind)."""
    scenario = bench_layers._scenario(*([override] if override and row == STATION else []))
    run = bench_layers.warmed_up(bench_layers.STATION if row == STATION else row, scenario,
                                 WARM_UP, seconds)
    _instrument(True)
    run()
    _instrument(False)


if __name__ == "__main__":
    from corobot_drake.simulation import quiet_drake_warnings

    quiet_drake_warnings()
    _child(sys.argv[1], float(sys.argv[2]), sys.argv[3] if len(sys.argv) > 3 else None)
