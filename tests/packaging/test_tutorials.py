"""The tutorials' code runs as written.

Every fenced code block of a tutorial page (and of the README) marked as Python
(```` ```python ````) or as shell commands (```` ```sh ````) runs here:

- A page's Python blocks run in order in one namespace, as a reader pastes them one after the
  other, in a scratch folder where `scenarios/` is the repository's.
- In a shell block, each `python -m corobot_drake ...` command (also `.venv/bin/python -m
  ...`; a line, a trailing backslash joining the next) runs in this process through
  `corobot_drake.cli.main` and must exit 0, in the same scratch folder. A command without
  `--headless` (Meshcat in a browser) gets it, and one without `--duration` (until Ctrl-C)
  gets `--duration 1`: the same run, ended. A `--serve` command is started as a server for
  the page's Python blocks instead (below). Comments and other lines (curl, cat, the tools,
  whose figures `tools/refresh_docs.py` and their own tests hold) are not run.
- To keep the suite cheap, a run is cut to `MAX_SECONDS` of simulated time: a longer
  `--duration`, and a longer literal `advance(S)` in a Python block, are cut to it (the
  code is otherwise as written: the same calls, the same outputs, a shorter run).
- A block right after a line `<!-- no-test: REASON -->` (the last non-blank line above its
  fence) is not run; the reason must be said (a display, a server left running until Ctrl-C,
  hours of training), and the page shows nothing of the comment.

docs/extending.md has its own test (tests/packaging/test_extending_docs.py: its excerpts are
held to the files), and docs/gallery.md's commands are the generated pictures' own.
"""

from __future__ import annotations

import contextlib
import os
import re
import shlex
import textwrap

import pytest

from conftest import REPO

PAGES = ("README.md", *(f"docs/{p}.md" for p in (
    "install", "usage", "commands", "services", "sensors", "recording", "ros2", "studies", "gym",
    "looks", "tuning")))
MAX_SECONDS = 2.0
"""s of simulated time a run here lasts at most."""
FENCE = re.compile(r"^(?P<indent> *)```(?P<lang>python|sh)\n(?P<body>.*?)^(?P=indent)```$",
                   re.MULTILINE | re.DOTALL)
"""A fenced block, also one indented under a list item."""
NO_TEST = re.compile(r"^<!-- no-test: (?P<reason>\S.*?) -->$")
CLI = re.compile(r"^(?:\.venv/bin/)?python -m corobot_drake ")


def blocks(page: str) -> list[tuple[str, str, int, str | None]]:
    """(language, code, line, no-test reason or None) of each Python or shell block."""
    text = (REPO / page).read_text()
    out = []
    for m in FENCE.finditer(text):
        above = [ln for ln in text[:m.start()].splitlines() if ln.strip()]
        skip = NO_TEST.match(above[-1].strip()) if above else None
        out.append((m["lang"], textwrap.dedent(m["body"]), text.count("\n", 0, m.start()) + 1,
                    skip["reason"] if skip else None))
    return out


def cli_commands(code: str) -> list[list[str]]:
    """The `python -m corobot_drake` commands of a shell block, as argument lists."""
    joined = re.sub(r"\\\n\s*", " ", code)
    return [shlex.split(line.strip(), comments=True)[3:] for line in joined.splitlines()
            if CLI.match(line.strip())]


def cut(argv: list[str]) -> list[str]:
    """A command as the test runs it: headless, ended, at most MAX_SECONDS long."""
    argv = [*argv, *(["--headless"] if "--headless" not in argv else []),
            *(["--duration", "1"] if "--duration" not in argv else [])]
    at = argv.index("--duration") + 1
    argv[at] = str(min(float(argv[at]), MAX_SECONDS))
    return argv


def shortened(code: str) -> str:
    """A Python block with each literal `advance(S)` longer than MAX_SECONDS cut to it."""
    return re.sub(r"\.advance\((\d+(?:\.\d*)?)\)",
                  lambda m: f".advance({min(float(m[1]), MAX_SECONDS)!r})", code)


@pytest.fixture
def scratch(tmp_path, monkeypatch):
    """A folder a reader works in, with the repository's scenarios beside them."""
    (tmp_path / "scenarios").symlink_to(REPO / "scenarios")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_the_tutorials_have_code_and_every_skip_says_why():
    found = {page: blocks(page) for page in PAGES}
    assert sum(len(b) for b in found.values()) >= 25
    for page, page_blocks in found.items():
        for _, _, line, reason in page_blocks:
            assert reason is None or len(reason) > 10, f"{page}:{line}: say why: {reason!r}"
    shells = [b for page_blocks in found.values() for b in page_blocks if b[0] == "sh"]
    assert sum(len(cli_commands(code)) for _, code, _, skip in shells if skip is None) >= 5


def served(page: str) -> list[str] | None:
    """The arguments of the page's `python -m corobot_drake --serve ...` command, if any."""
    return next((argv for lang, code, _, reason in blocks(page) if lang == "sh" and not reason
                 for argv in cli_commands(code) if "--serve" in argv), None)


@pytest.mark.parametrize("page", PAGES)
def test_a_pages_python_blocks_run_in_order(page, scratch):
    """A page that starts a server for its Python (services.md) has it served here, on a free
    port in place of the page's 50000."""
    from corobot_drake.serving.serve import ServerProcess

    serve = served(page)
    with contextlib.ExitStack() as stack:
        url = None
        if serve:
            args = [a for a in serve if a != "--serve"]
            url = stack.enter_context(ServerProcess(args)).url
        namespace = {"__name__": "docs_" + re.sub(r"\W", "_", page)}
        for lang, code, line, reason in blocks(page):
            if lang == "python" and reason is None:
                if url:
                    code = code.replace("http://127.0.0.1:50000", url)
                exec(compile(shortened(code), f"{page}:{line}", "exec"), namespace)


@pytest.mark.parametrize("page", PAGES)
def test_a_pages_commands_run(page, scratch, capsys):
    from corobot_drake.cli import main

    for lang, code, line, reason in blocks(page):
        if lang != "sh" or reason is not None:
            continue
        for argv in cli_commands(code):
            if "--serve" in argv:  # runs until Ctrl-C: served for the page's Python blocks
                continue
            argv = cut(argv)
            try:
                status = main(argv)
            except SystemExit as exit_:
                status = exit_.code
            out = capsys.readouterr()
            assert status == 0, f"{page}:{line}: {shlex.join(argv)}\n{out.err[-2000:]}"
    assert os.getcwd() == str(scratch)
