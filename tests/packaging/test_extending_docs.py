"""docs/extending.md's Python blocks run, and its excerpts are the files' own lines.

A block whose first line is a comment naming a file (`# corobot_drake/sensors/bumper.py`) is
an excerpt: each stretch of its lines between `...` lines (`...,` in a tuple) must stand in
that file as it is, in order, and the block runs in a copy of that module's namespace (its
definitions compile and execute with the module's imports). Every other block is an
example, run in order in one namespace, from the repository's root, as a reader would paste
them. A YAML or XML block that opens with a file's path (the robot chapter's robot file and
URDF, which its examples load) is an excerpt of that file in the same way.

Its shell blocks (```` ```sh ````) run line by line by the tutorials' rules
(tests/packaging/test_tutorials.py: `python -m corobot_drake ...` headless and cut short,
`python -m corobot_drake.<module> ...` through the module's `main`), in a scratch folder with
the repository's scenarios and examples beside it."""

import importlib
import json
import re

import pytest
from test_tutorials import blocks as page_blocks
from test_tutorials import run_line, shell_lines

from conftest import REPO

DOC = REPO / "docs" / "extending.md"
BLOCK = re.compile(r"^```python\n(.*?)^```$", re.MULTILINE | re.DOTALL)
SOURCE = re.compile(r"^# (?P<path>[\w/]+\.py)$")
ELISION = re.compile(r"^\s*\.\.\.,?$")
"""A line that stands for lines left out (`...,` among the items of a tuple)."""
FILE_BLOCK = re.compile(r"^```(?:yaml|xml)\n(.*?)^```$", re.MULTILINE | re.DOTALL)
FILE_SOURCE = re.compile(r"^(?:# |<!-- )(?P<path>[\w/.]+\.(?:yaml|urdf|sdf))(?: -->)?$")
"""A YAML or XML block whose first line names a file (`# examples/my_robot/robot.yaml`,
`<!-- examples/my_robot/my_robot.urdf -->`) is an excerpt of that file."""


def blocks() -> list[str]:
    return BLOCK.findall(DOC.read_text())


def excerpt_of(block: str) -> str | None:
    """The file a block is an excerpt of (relative to the repository), or None."""
    match = SOURCE.match(block.splitlines()[0])
    return match["path"] if match else None


def stretches(block: str) -> list[str]:
    """The runs of lines between elisions (the first, naming the file, left out)."""
    runs, run = [], []
    for line in block.splitlines()[1:]:
        if ELISION.match(line):
            runs.append(run)
            run = []
        else:
            run.append(line)
    runs.append(run)
    return ["\n".join(r).strip("\n") for r in runs if "".join(r).strip()]


EXCERPTS = [(i, b) for i, b in enumerate(blocks()) if excerpt_of(b)]


def test_the_guide_has_excerpts_and_examples():
    assert len(EXCERPTS) >= 8
    assert len(blocks()) - len(EXCERPTS) >= 3


@pytest.mark.parametrize(("index", "block"), EXCERPTS, ids=[f"block{i}" for i, _ in EXCERPTS])
def test_an_excerpt_is_the_files_own_text_and_runs(index, block):
    path = excerpt_of(block)
    source = (REPO / path).read_text()
    at = 0
    for stretch in stretches(block):
        found = source.find(stretch, at)
        assert found >= 0, f"block {index}: not in {path} (after offset {at}):\n{stretch}"
        at = found + len(stretch)
    module = importlib.import_module(path.removesuffix(".py").replace("/", "."))
    exec(compile(block, f"{DOC.name} block {index}", "exec"), dict(vars(module)))


FILE_EXCERPTS = [(i, b) for i, b in enumerate(FILE_BLOCK.findall(DOC.read_text()))
                 if FILE_SOURCE.match(b.splitlines()[0])]


def test_a_robot_file_or_model_excerpt_is_the_files_own_text():
    """The robot chapter's robot file and URDF, which its examples load, are as shown."""
    assert len(FILE_EXCERPTS) >= 3
    for index, block in FILE_EXCERPTS:
        path = FILE_SOURCE.match(block.splitlines()[0])["path"]
        source = (REPO / path).read_text()
        at = 0
        for stretch in stretches(block):
            found = source.find(stretch, at)
            assert found >= 0, f"block {index}: not in {path} (after offset {at}):\n{stretch}"
            at = found + len(stretch)


def test_the_examples_run_in_order(monkeypatch):
    monkeypatch.chdir(REPO)
    namespace = {"__name__": "extending_md"}
    for index, block in enumerate(blocks()):
        if not excerpt_of(block):
            exec(compile(block, f"{DOC.name} block {index}", "exec"), namespace)


def test_the_shell_commands_run(tmp_path, monkeypatch, capsys):
    """The bumper override with its summary, `robot check` of the example robot (its URDF
    written beside), and the example robot driven beside the Corobot."""
    for folder in ("scenarios", "examples"):
        (tmp_path / folder).symlink_to(REPO / folder)
    monkeypatch.chdir(tmp_path)
    page = str(DOC.relative_to(REPO))
    shells = [(code, line) for lang, code, line, reason in page_blocks(page)
              if lang == "sh" and reason is None]
    assert len(shells) >= 3
    for code, line in shells:
        for argv in shell_lines(code):
            run_line(argv, f"{page}:{line}", None, capsys)
    summary = json.loads((tmp_path / "s.json").read_text())
    assert "front_bumper" in json.dumps(summary)  # the override's bumper is in the summary
    assert "<robot" in (tmp_path / "my_robot.urdf").read_text()
