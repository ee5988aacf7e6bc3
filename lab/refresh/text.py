"""Helpers that turn commands' outputs into Markdown: numbers and tables found in them, load and
date lines."""

from __future__ import annotations

import os
import re
from collections.abc import Callable

from lab.refresh.runner import Output


def find(pattern: str, text: str, group: int | str = 1) -> str:
    m = re.search(pattern, text, re.MULTILINE)
    if not m:
        raise ValueError(f"no match for {pattern!r} in:\n{text}")
    return m[group]


def number(pattern: str, text: str) -> float:
    return float(find(pattern, text))


def table(text: str) -> str:
    """The Markdown table lines of a tool's output."""
    return "\n".join(line for line in text.splitlines() if line.startswith("|"))


def load_line(outputs: list[Output]) -> str:
    lo = min(o.load[0] for o in outputs)
    hi = max(o.load[1] for o in outputs)
    return f"{lo:.1f}" if f"{lo:.1f}" == f"{hi:.1f}" else f"{lo:.1f}-{hi:.1f}"


def measured_line(outputs: list[Output]) -> str:
    """'2025-01-31, load average 1.2-3.4 on 2 cores' for a timing block."""
    day = min(o.started for o in outputs).strftime("%Y-%m-%d")
    return f"{day}, load average {load_line(outputs)} on {os.cpu_count()} cores"


def flat(outs: list[list[Output]]) -> list[Output]:
    return [o for runs in outs for o in runs]


def value_range(values: list[float], fmt: str = "{:.1f}") -> str:
    lo, hi = fmt.format(min(values)), fmt.format(max(values))
    return lo if lo == hi else f"{lo}-{hi}"


def as_markdown(text: str) -> str:
    """A tool's output as Markdown: its tables kept, every other line a list item."""
    out, previous = [], ""
    for line in text.strip().splitlines():
        line = line.rstrip()
        if not line:
            continue
        kind = "table" if line.startswith("|") else "item"
        if out and kind != previous:
            out.append("")
        out.append(line if kind == "table" else f"- {line.strip()}")
        previous = kind
    return "\n".join(out)


def picture(alt: str, path: str, command: str) -> Callable:
    def render(outs):
        return f"![{alt}]({path})\n\n    {command}"
    return render


