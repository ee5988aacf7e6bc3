"""Running the blocks' commands: their outputs, the machine's load while they ran, and what each
block is (`Spec`)."""

from __future__ import annotations

import dataclasses as dc
import datetime
import os
import shlex
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

from corobot_drake.config.scenario import SAP_PLANT

REPO = Path(__file__).resolve().parents[2]
DOCS = ("README.md", *sorted(f"docs/{p.name}" for p in (REPO / "docs").glob("*.md")))
DETERMINISTIC, PICTURE, TIMING = "deterministic", "picture", "timing"
ORDER = {DETERMINISTIC: 0, PICTURE: 1, TIMING: 2}
CHECK_SECONDS = 30.0
"""`--check` without `--only` re-renders the deterministic blocks estimated to cost this or less."""
NO_CAMERA = "robots: {corobot: {cameras: {front: {rgb: false}}}}"
SAP_OVERRIDE = SAP_PLANT % 0.01
"""`scenario.SAP_PLANT` at 10 ms, as the command line writes it."""
OLD_CHECKOUT = "/tmp/corobot-268a52c"
"""The checkout `bench_compare` measures against: `git worktree add /tmp/corobot-268a52c
268a52c` (the commit before CENIC and the lean per-step path)."""



@dc.dataclass
class Output:
    """What one run of a command printed, and the machine's state while it ran."""

    command: str
    stdout: str
    seconds: float
    load: tuple[float, float]
    """Smallest and largest 1-minute load average sampled during the run."""
    started: datetime.datetime


def _argv(command: str) -> list[str]:
    argv = shlex.split(command)
    return [sys.executable, *argv[1:]] if argv[0] == "python" else argv


def run_command(command: str, label: str, ok: tuple[int, ...] = (0,)) -> Output:
    """Runs `command` (as shown in the docs, from the repository's top) and streams its output,
    each line prefixed with `label`, to stderr as progress."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(REPO), *filter(None, [os.environ.get("PYTHONPATH")])]))
    loads = [os.getloadavg()[0]]
    started, start = datetime.datetime.now(), time.perf_counter()
    print(f"[{label}] $ {command}", file=sys.stderr, flush=True)
    proc = subprocess.Popen(_argv(command), cwd=REPO, env=env, stdout=subprocess.PIPE,
                            text=True, bufsize=1)
    done = threading.Event()
    last = [start]

    def sample() -> None:
        """Samples the load; says the command is still running after a minute of silence."""
        while not done.wait(5.0):
            loads.append(os.getloadavg()[0])
            if time.perf_counter() - last[0] > 60.0:
                last[0] = time.perf_counter()
                print(f"[{label} {last[0] - start:5.0f} s] (running; load average "
                      f"{loads[-1]:.1f})", file=sys.stderr, flush=True)

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    lines = []
    for line in proc.stdout:
        lines.append(line)
        last[0] = time.perf_counter()
        print(f"[{label} {time.perf_counter() - start:5.0f} s] {line.rstrip()}",
              file=sys.stderr, flush=True)
    code = proc.wait()
    done.set()
    loads.append(os.getloadavg()[0])
    if code not in ok:
        raise RuntimeError(f"{command}: exit status {code}")
    return Output(command, "".join(lines), time.perf_counter() - start,
                  (min(loads), max(loads)), started)


class Runner:
    """Runs each command once per refresh, however many blocks show its output."""

    def __init__(self):
        self._done: dict[tuple[str, int], Output] = {}

    def outputs(self, block: Spec) -> list[list[Output]]:
        """For each of the block's commands, its `repeats` outputs."""
        result = []
        for cmd in block.commands:
            runs = []
            for i in range(cmd.repeats):
                key = (cmd.text, i)
                if key not in self._done:
                    label = block.name + (f" {i + 1}/{cmd.repeats}" if cmd.repeats > 1 else "")
                    self._done[key] = run_command(cmd.text, label, cmd.ok)
                runs.append(self._done[key])
            result.append(runs)
        return result


@dc.dataclass(frozen=True)
class Command:
    text: str
    """As the docs show it: `python tools/x.py --option value`, run from the repository's top."""
    repeats: int = 1
    """Runs (timings: each run gives one figure, the block shows their range)."""
    ok: tuple[int, ...] = (0,)
    """Exit statuses that still mean the output is good."""


@dc.dataclass(frozen=True)
class Spec:
    name: str
    file: str
    commands: tuple[Command, ...]
    render: Callable[[list[list[Output]]], str]
    kind: str
    seconds: float
    """Rough cost on the project's 2-core machine, all commands and repeats."""

    @property
    def cheap(self) -> bool:
        """`--check` without `--only` re-renders it: deterministic, and within CHECK_SECONDS."""
        return self.kind == DETERMINISTIC and self.seconds <= CHECK_SECONDS

    @property
    def shown(self) -> str:
        return "; ".join(c.text + (f" (x{c.repeats})" if c.repeats > 1 else "")
                         for c in self.commands)


