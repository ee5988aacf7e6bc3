"""What a misspelt name gets: the closest names that exist (difflib's), in every message that
refuses a name a user typed (a robot's in Python, a scenario, over HTTP, on a command line).

No Drake import here (the HTTP process reads it).
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable


def close_names(name: str, known: Iterable[str], n: int = 3) -> list[str]:
    """The names in `known` closest to `name` (at most `n`, best first; difflib's ratio at
    least 0.6), matched without regard to case."""
    known = list(known)
    by_folded = {k.casefold(): k for k in reversed(known)}  # the first of equal foldings
    return [by_folded[m] for m in difflib.get_close_matches(str(name).casefold(), by_folded,
                                                           n=n)]


def did_you_mean(name: str, known: Iterable[str]) -> str:
    """' (did you mean 'corobot'?)' naming the closest of `known` to `name`, or '' if none
    is close."""
    close = close_names(name, known)
    return f" (did you mean {' or '.join(repr(c) for c in close)}?)" if close else ""


def unknown_robot(name: str, known: Iterable[str]) -> str:
    """The one line for a robot name that is not one of `known`:
    "no robot named 'corobt' (did you mean 'corobot'?); robots: corobot"."""
    known = list(known)
    return (f"no robot named {name!r}{did_you_mean(name, known)}; robots: "
            f"{', '.join(known) or '(none)'}")


def unknown_robot_kind(name: str, shipped: Iterable[str]) -> str:
    """The one line for a robot's kind (a scenario's `robot:`) that is neither a shipped
    robot nor a robot file: "'burgr' is neither a shipped robot (corobot, burger, pioneer) nor
    a robot file (did you mean 'burger'?)"."""
    shipped = list(shipped)
    return (f"{name!r} is neither a shipped robot ({', '.join(shipped)}) nor a robot "
            f"file{did_you_mean(name, shipped)}")
