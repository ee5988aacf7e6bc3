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




DATE = re.compile(r"\b20\d\d-\d\d-\d\d\b")
"""A date in a block: a timing's day, or the day a deterministic block or picture was made."""
PRODUCED = re.compile(r"(?:\n\n\*Produced 20\d\d-\d\d-\d\d\b(?:(?!\n\n).)*\*"
                      r"| \(produced 20\d\d-\d\d-\d\d\b[^()]*\))\Z",
                      re.DOTALL)
"""The date line `stamp` ends an undated block with (a multi-line block's last paragraph, an
inline block's last parenthesis)."""
FROM_GIT = "from git: the last commit that changed it"


def stamp(content: str, day: str, commands: list[str], multiline: bool,
          from_git: bool = False) -> str:
    """`content` ending with the day it was made and the command(s) that made it (unless the
    content shows them already); `from_git`: the day is not a run's but git's (`FROM_GIT`)."""
    shown = [c for c in commands if c not in content]
    by = " by " + "; ".join(f"`{c}`" for c in shown) if shown else " by the command above"
    if multiline:
        why = f" ({FROM_GIT})" if from_git else ""
        return f"{content.rstrip()}\n\n*Produced {day}{why}{by}.*"
    why = f", {FROM_GIT}," if from_git else ""
    return f"{content} (produced {day}{why}{by if shown else ''})"


def unstamped(content: str) -> str:
    """`content` without `stamp`'s date line: what `--check` compares (the figures, not when
    they were made)."""
    return PRODUCED.sub("", content)
