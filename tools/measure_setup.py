"""Benchmark: what `tools/setup` takes on a fresh clone, step by step, and its sizes.

Clones this checkout (its committed tree, as CI does) into a temporary folder, runs
`tools/setup` there with its output in a log, prints when each step started, the total time
and the sizes `tools/setup` reports, then removes the clone. Downloads come from the package
index (pip's cache, if warm, makes them faster); run as root, apt's packages are installed
only when missing. Takes as long as the set-up: about 7 minutes on 2 cores.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from corobot_drake.arguments import ToolParser

REPO = Path(__file__).resolve().parents[1]
STEP = re.compile(r"^\[(\d+)/(\d+)\] (.*?)(?: \(at (\d+) s\))?$")
DONE = re.compile(r" in (\d+) min (\d+) s; \.venv takes (\S+), \.venv-ros (\S+)$")


def steps(log: str) -> list[tuple[str, int]]:
    """(step, s from the start when it began) of each of tools/setup's step lines."""
    return [(m[3].split(":")[0], int(m[4])) for line in log.splitlines()
            if (m := STEP.match(line)) and m[4]]


def summary(log: str) -> tuple[int, str, str]:
    """(s in all, .venv's size, .venv-ros's size) from tools/setup's last line."""
    m = next((m for line in log.splitlines() if (m := DONE.search(line))), None)
    if m is None:
        raise ValueError("tools/setup printed no closing line with its time and sizes")
    return int(m[1]) * 60 + int(m[2]), m[3], m[4]


def main(argv=None) -> int:
    ToolParser(description=__doc__.splitlines()[0]).parse_args(argv)
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory(prefix="measure-setup-") as folder:
        clone = Path(folder) / "corobot-drake"
        subprocess.run(["git", "clone", "-q", str(REPO), str(clone)], check=True)
        done = subprocess.run([str(clone / "tools" / "setup")], cwd=clone, text=True,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        if done.returncode != 0:
            print(done.stdout[-3000:], file=sys.stderr)
            print(f"error: tools/setup exited {done.returncode} (its output above)",
                  file=sys.stderr)
            return 1
    total, venv, venv_ros = summary(done.stdout)
    starts = steps(done.stdout)
    for (name, start), (_, end) in zip(starts, [*starts[1:], ("end", total)], strict=True):
        print(f"{name}: {(end - start) / 60:.1f} min")
    print(f"in all: {total // 60} min {total % 60} s; .venv {venv}B, .venv-ros {venv_ros}B")
    return 0


if __name__ == "__main__":
    sys.exit(main())
