"""The docs' indented command lines (synopses and the commands of generated blocks, which the
tutorials' test does not run) name only options their program has: each `--flag` is one its
own `--help` lists, read from the program's parser in this process. A synopsis may leave
options out (the generated command reference has them all); it may not name one that is gone
or misspelt."""

from __future__ import annotations

import contextlib
import importlib
import io
import re
import runpy
import sys

import pytest

from conftest import REPO

SYNOPSIS = re.compile(r"^    (python (?:-m corobot_drake[\w.]*|(?:tools|examples)/\w+\.py)\b.*)$",
                      re.MULTILINE)
FLAG = re.compile(r"(?<![\w-])--[a-z][\w-]*")


def synopses() -> dict[str, list[tuple[str, str]]]:
    """{program: [(where, the line)]} of the docs pages' indented command lines."""
    out: dict[str, list[tuple[str, str]]] = {}
    for page in sorted((REPO / "docs").glob("*.md")):
        text = page.read_text()
        for m in SYNOPSIS.finditer(text):
            line = m[1].split("  #")[0]
            name = re.match(r"python (?:-m )?(\S+)", line)[1]
            where = f"docs/{page.name}:{text.count(chr(10), 0, m.start()) + 1}"
            out.setdefault(name, []).append((where, line))
    return out


def help_text(program: str) -> str:
    """`program --help`'s text: a module's `main` or a script run as `__main__`."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit):
        if program.endswith(".py"):
            saved, sys.argv = sys.argv, [str(REPO / program), "--help"]
            try:
                runpy.run_path(str(REPO / program), run_name="__main__")
            finally:
                sys.argv = saved
        else:
            module = importlib.import_module("corobot_drake.cli" if program == "corobot_drake"
                                             else program)
            if not hasattr(module, "main"):
                module = importlib.import_module(program + ".__main__")
            module.main(["--help"])
    return out.getvalue()


def test_the_docs_have_synopses():
    assert sum(len(v) for v in synopses().values()) >= 40


@pytest.mark.parametrize("program", sorted(synopses()))
def test_a_synopsis_names_only_options_its_program_has(program):
    known = set(FLAG.findall(help_text(program)))
    assert known, f"{program} --help lists no options"
    wrong = [f"{where}: {flag}" for where, line in synopses()[program]
             for flag in FLAG.findall(line) if flag not in known]
    assert not wrong, f"options {program} does not have: {wrong}"
