"""The set-up and test commands of README.md and docs/install.md are the ones CI runs, and
what follows the set-up on their lines runs here.

The suite cannot run the set-up that made its own environment, nor itself; CI runs both,
`.ci/run` being exactly the pages' test command (checked here). On a page's line
`tools/setup && CMD`, CMD runs by tests/packaging/test_tutorials.py's rules (`python -m
corobot_drake` headless and cut short); a `pytest` line's folders hold tests and its options
are pytest's.
"""

from __future__ import annotations

import re
import shlex
import subprocess
import sys

from test_tutorials import PYTHON, blocks, run_line, shell_lines

from conftest import REPO

PAGES = ("README.md", "docs/install.md")
SETUP = "tools/setup"


def ci_commands() -> list[list[str]]:
    """The commands `.ci/run` runs, as argument lists (its shell options and `cd` left out)."""
    lines = shell_lines((REPO / ".ci" / "run").read_text())
    return [argv for argv in lines if argv[0] not in ("set", "cd")]


def and_chains(argv: list[str]) -> list[list[str]]:
    """`a && b` as [a, b]."""
    out = [[]]
    for word in argv:
        if word == "&&":
            out.append([])
        else:
            out[-1].append(word)
    return out


def setup_lines() -> list[tuple[str, list[list[str]]]]:
    """(where, the line's commands) of each shell line of the pages that starts with the set-up."""
    return [(f"{page}:{line}", chain) for page in PAGES
            for lang, code, line, _ in blocks(page) if lang == "sh"
            for argv in shell_lines(code) if (chain := and_chains(argv))[0] == [SETUP]]


def pytest_lines() -> list[tuple[str, list[str]]]:
    """(where, pytest's arguments) of each shell line of the pages that runs the suite alone."""
    return [(f"{page}:{line}", argv[3:]) for page in PAGES
            for lang, code, line, _ in blocks(page) if lang == "sh"
            for argv in shell_lines(code)
            if argv[0] in PYTHON and argv[1:3] == ["-m", "pytest"]]


def test_ci_runs_the_pages_test_command_and_nothing_else():
    ci = ci_commands()
    assert ci == [[SETUP, "&&", ".venv/bin/python", "-m", "pytest"]], shlex.join(ci[0])
    test_commands = [chain for _, chain in setup_lines() if chain[1][2:] == ["pytest"]]
    assert test_commands, "no page gives the test command"
    assert all(chain == and_chains(ci[0]) for chain in test_commands)


def test_both_pages_give_the_set_up_then_the_first_run():
    first_runs = {where.split(":")[0]: chain[1] for where, chain in setup_lines()
                  if chain[1][1:3] == ["-m", "corobot_drake"]}
    assert set(first_runs) == set(PAGES)
    assert all(argv == [".venv/bin/python", "-m", "corobot_drake"]
               for argv in first_runs.values())


def test_what_follows_the_set_up_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    for where, chain in setup_lines():
        for argv in chain[1:]:
            if argv[1:3] != ["-m", "pytest"]:  # the suite itself: collected below
                run_line(argv, where, None, capsys)


def test_a_pages_pytest_lines_name_folders_of_tests_and_options_pytest_has():
    """The suite's own lines (CI runs the suite whole): each path is a folder of tests, each
    option one `pytest --help` lists (xdist's `-n` among them)."""
    lines = pytest_lines()
    assert len(lines) >= 3
    options = subprocess.run([sys.executable, "-m", "pytest", "--help"], cwd=REPO,
                             capture_output=True, text=True, timeout=60, check=True).stdout
    for where, args in lines:
        for arg in args:
            if arg.startswith("-"):
                assert re.search(rf"^  (-\w, )?{re.escape(arg)}\b", options, re.MULTILINE), \
                    f"{where}: pytest has no option {arg}"
            elif not arg.isdigit():
                assert any((REPO / arg).glob("test_*.py")), f"{where}: {arg} holds no tests"


def test_the_readmes_set_up_figures_are_the_measured_blocks_rounded():
    """README.md rounds the set-up's time and size; install.md's generated block
    (`tools/measure_setup.py`) holds them: a refresh that moves them fails here until the
    README follows."""
    readme = (REPO / "README.md").read_text()
    said = re.search(r"about (\d+) minutes and (\d+(?:\.\d+)?) GB", readme)
    assert said, "README.md says no 'about N minutes and M GB' for the set-up"
    install = (REPO / "docs" / "install.md").read_text()
    block = install[install.index("<!-- BEGIN generated: setup-cost"):
                    install.index("<!-- END generated: setup-cost")]
    measured = re.search(r"in all: (\d+) min (\d+) s; \.venv (\d+(?:\.\d+)?)GB", block)
    assert measured, "install.md's setup-cost block has no 'in all' line"
    minutes = int(measured[1]) + int(measured[2]) / 60
    assert abs(int(said[1]) - minutes) <= 1.0, (said[0], measured[0])
    assert abs(float(said[2]) - float(measured[3])) <= 0.6, (said[0], measured[0])
