"""The tools' command lines (`tools/*.py`): every bad argument or input file is one line
`error: <flag or file>[:line]: <what is wrong and what is allowed>`, exit status 2.

- `ToolParser`: argparse with each option's default in `--help` and argparse's own errors on
  one line;
- `bounded(Range)`, `bounded_list(Range)`, `output_file`, `output_directory`: argparse
  `type=`s that check a number (or each of a comma-separated list) against its bound, or that
  an output can be written, before anything runs;
- `one_line_errors(main)`: runs a tool's `main`, turning a bad input file (ScenarioError,
  LogError) or an output that cannot be written (OSError) into its one line.
"""

from __future__ import annotations

import argparse
import functools
import sys
from pathlib import Path

from corobot_drake import limits
from corobot_drake.cli import directory_problem, file_problem
from corobot_drake.config.scenario import ScenarioError
from corobot_drake.limits import Range
from corobot_drake.tuning.sysid import LogError

WORKERS = limits.WORKERS
"""--workers of the tools that run a study (as `python -m corobot_drake.study`)."""
TICKS_PER_REVOLUTION = Range(1, 1_000_000, why="encoder counts per wheel revolution")
BENCH_SECONDS = Range(0.0, 3600.0, low_open=True, unit="s")
"""--seconds of the benchmarks: simulated seconds per timed run."""
REPEATS = Range(1, 1000, why="runs of each, the median kept")
"""--repeats of the benchmarks."""


class ToolParser(argparse.ArgumentParser):
    """An argument parser whose `--help` shows every default and whose errors are one line."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", argparse.ArgumentDefaultsHelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message):
        self.exit(2, f"error: {message}\n")


def bounded(bound: Range, kind=float):
    """An argparse `type`: a `kind` number within `bound` (argparse names the flag)."""

    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected {'an integer' if kind is int else 'a number'}, got {text!r}"
            ) from None
        problem = bound.problem(value)
        if problem:
            raise argparse.ArgumentTypeError(problem)
        return value

    parse.__name__ = kind.__name__  # argparse's "invalid int value" names the type
    return parse


def bounded_list(bound: Range, kind=int):
    """An argparse `type`: comma-separated `kind` numbers, each within `bound` (`1,2,4`)."""
    each = bounded(bound, kind)

    def parse(text: str) -> list:
        return [each(item.strip()) for item in text.split(",")]

    parse.__name__ = f"list of {kind.__name__}"
    return parse


def output_file(text: str) -> Path:
    """An argparse `type`: a file that can be written (its missing directories are made)."""
    path = Path(text)
    parent = path.parent
    problem = ("is a directory; name a file" if path.is_dir()
               else f"{parent} is not a directory" if parent.exists() and not parent.is_dir()
               else directory_problem(parent))
    if problem:
        raise argparse.ArgumentTypeError(f"{text}: {problem}")
    return path


def output_directory(text: str) -> Path:
    """An argparse `type`: a directory files can be written under (made when needed)."""
    problem = directory_problem(Path(text))
    if problem:
        raise argparse.ArgumentTypeError(f"{text}: {problem}")
    return Path(text)


def existing_file(text: str) -> Path:
    """An argparse `type`: a file to rewrite in place (`--write SCENARIO`)."""
    path = Path(text)
    problem = ("no such file" if not path.exists() else "is not a regular file"
               if not path.is_file() else file_problem(path))
    if problem:
        raise argparse.ArgumentTypeError(f"{text}: {problem}")
    return path


def scenario_file(text: str) -> str:
    """An argparse `type`: a scenario file to read, or a shipped scenario's name
    (`pioneer.yaml`) from any folder, as the main command line takes it
    (`resources.scenario_path`; a file that is neither: the load's one line)."""
    from corobot_drake.resources import scenario_path

    return str(scenario_path(text))


def one_line_errors(main):
    """`main` with a bad input file (ScenarioError, LogError) or an unwritable output
    (OSError) as its one line, exit status 2."""

    @functools.wraps(main)
    def wrapped(argv=None) -> int:
        try:
            return main(argv)
        except (ScenarioError, LogError) as e:
            print(f"error: {e}", file=sys.stderr)
            return 2
        except OSError as e:  # an output that passed its check but could not be written
            print(f"error: {e.filename}: cannot write ({e.strerror})", file=sys.stderr)
            return 2

    return wrapped
