"""Every command's `--help`: the set-up script's (`tools/setup`, bash), as it prints it, run at
each build; the package's, tools/*.py's and examples/*.py's as its argparse parser prints it,
caught in this process.

Each program's `main()` is called with `ArgumentParser.parse_args` replaced by a catch: the
parser it built is kept, and nothing else of the program runs (as
tests/packaging/test_tools_help.py does). Subcommands get their own help below their parent's.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import importlib.util
import os
import subprocess
import sys
import warnings
from pathlib import Path

from corobot_docs.markdown import fenced

REPO = Path(__file__).resolve().parents[3]
MODULES = (
    ("python -m corobot_drake", "corobot_drake.cli"),
    ("python -m corobot_drake.study", "corobot_drake.study.__main__"),
    ("python -m corobot_drake.ros2", "corobot_drake.ros2.inspection"),
    ("python -m corobot_drake.ros2.build", "corobot_drake.ros2.build"),
    ("python -m corobot_drake.robot", "corobot_drake.robot"),
)
"""(command, the module whose `main()` parses its arguments)."""
SCRIPTS = ("tools/setup",)
"""Shell scripts whose `--help` prints their usage and does nothing else (tools/setup's:
tests/packaging/test_setup.py), by path from the repository's root."""
WIDTH = "100"
"""Columns argparse wraps the help to (it reads $COLUMNS): the same on every machine."""


class _CaughtError(Exception):
    def __init__(self, parser):
        super().__init__()
        self.parser = parser


def _catch(self, *args, **kwargs):
    raise _CaughtError(self)


@contextlib.contextmanager
def _catching(prog: str):
    saved = (os.environ.get("COLUMNS"), sys.argv, warnings.formatwarning,
             argparse.ArgumentParser.parse_args, argparse.ArgumentParser.parse_known_args)
    os.environ["COLUMNS"] = WIDTH
    sys.argv = [prog]
    argparse.ArgumentParser.parse_args = _catch
    argparse.ArgumentParser.parse_known_args = _catch
    try:
        yield
    finally:
        columns, sys.argv, warnings.formatwarning, argparse.ArgumentParser.parse_args, \
            argparse.ArgumentParser.parse_known_args = saved
        if columns is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = columns


def parser_of(main, prog: str) -> argparse.ArgumentParser:
    """The parser `main()` builds, caught at its parse_args."""
    with _catching(prog):
        try:
            main()
        except _CaughtError as caught:
            return caught.parser
    raise RuntimeError(f"{prog}: main() returned without parsing its arguments")


def _tool_main(path: Path):
    spec = importlib.util.spec_from_file_location(f"docs_tool_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module.main


def _helps(parser: argparse.ArgumentParser, command: str):
    """(command, help text) of the parser and of each of its subcommands."""
    with _width():
        yield command, parser.format_help()
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    yield from _helps(sub, f"{command} {name}")


@contextlib.contextmanager
def _width():
    saved = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = WIDTH
    try:
        yield
    finally:
        if saved is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = saved


def script_help(script: str) -> str:
    """What `bash <script> --help` prints (run in the repository's root)."""
    done = subprocess.run(["bash", script, "--help"], capture_output=True, text=True,
                          cwd=REPO, timeout=60, check=False)
    if done.returncode != 0 or not done.stdout.strip():
        raise RuntimeError(f"{script} --help: status {done.returncode}: {done.stderr.strip()}")
    return done.stdout


def programs():
    """(command, its main()) of the package's commands, every tool and every example (each
    takes --help: tests/packaging/test_tools_help.py)."""
    for command, module in MODULES:
        yield command, importlib.import_module(module).main
    for folder in ("tools", "examples"):
        for path in sorted((REPO / folder).glob("*.py")):
            yield f"python {folder}/{path.name}", _tool_main(path)


def page() -> str:
    out = ["Each command's `--help` at each build (`docs/_ext/corobot_docs/cli.py`): the "
           "set-up script's as it prints it, the others' caught from their own parser."]
    out += [f"## `{script}`\n\n{fenced(script_help(script))}" for script in SCRIPTS]
    for command, main in programs():
        parser = parser_of(main, command)
        parser.prog = command
        for name, text in _helps(parser, command):
            level = "##" if name == command else "###"
            out.append(f"{level} `{name}`\n\n{fenced(text)}")
    return "\n\n".join(out) + "\n"
