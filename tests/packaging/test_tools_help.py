"""Every tool's --help shows each option's default (the project's rule for tools)."""

import argparse
import importlib.util
import sys
from pathlib import Path

import pytest

from conftest import REPO, load_tool

TOOLS = sorted((REPO / "tools").glob("*.py"))


class _ParsedError(Exception):
    """Raised by the patched parse_args: the tool built its parser."""


def _parser_of(tool: Path, monkeypatch) -> argparse.ArgumentParser:
    """The tool's argument parser, caught at its parse_args (nothing else of the tool runs)."""
    caught = []

    def parse_args(self, *args, **kwargs):
        caught.append(self)
        raise _ParsedError

    monkeypatch.setattr(argparse.ArgumentParser, "parse_args", parse_args)
    spec = importlib.util.spec_from_file_location(f"tool_{tool.stem}", tool)
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, spec.name, module)  # dataclasses look their module up
    spec.loader.exec_module(module)
    with pytest.raises(_ParsedError):
        module.main()
    return caught[0]


@pytest.mark.parametrize("tool", TOOLS, ids=[t.stem for t in TOOLS])
def test_help_shows_every_default(tool, monkeypatch):
    parser = _parser_of(tool, monkeypatch)
    assert parser.formatter_class is argparse.ArgumentDefaultsHelpFormatter
    formatter = parser._get_formatter()
    for action in parser._actions:
        if not action.option_strings or action.help == argparse.SUPPRESS \
                or isinstance(action, argparse._HelpAction):
            continue
        # The formatter appends "(default: ...)" only to an option with help text.
        assert action.help, f"{tool.name}: {action.option_strings[0]} has no help"
        assert f"(default: {action.default})" in formatter._expand_help(action), \
            f"{tool.name}: {action.option_strings[0]} does not show its default"


PLAIN_ARGPARSE = {"camera_cost", "hostile_inputs", "make_meshes", "make_model", "refresh_docs",
                  "step_limit", "cenic_pd_sign_repro"}
"""Tools still on plain argparse (not yet moved to ToolParser with bounded arguments), and
`cenic_pd_sign_repro` (standalone: pydrake only, for an upstream report)."""


@pytest.mark.parametrize("tool", [t for t in TOOLS if t.stem not in PLAIN_ARGPARSE],
                         ids=lambda t: t.stem)
def test_a_tool_parses_with_the_tools_parser(tool, monkeypatch):
    """Its bad arguments end in one `error:` line, exit 2
    (tests/packaging/test_hostile_inputs.py runs some of each: `hostile_inputs.TOOLS`)."""
    from corobot_drake.arguments import ToolParser

    assert isinstance(_parser_of(tool, monkeypatch), ToolParser), tool.name


OUTPUT_OPTIONS = {"out", "output", "plot", "table"}
"""The options that name what a tool writes."""
WRITES_THE_CHECKOUT = {"train_policy"}
"""Tools whose defaults still write into the checkout (the shipped policy and its picture)."""


@pytest.mark.parametrize("tool", [t for t in TOOLS if t.stem not in WRITES_THE_CHECKOUT],
                         ids=lambda t: t.stem)
def test_a_tool_writes_under_the_current_directory_by_default(tool, monkeypatch):
    """No default output is an absolute path or climbs out of the current directory: a tool
    writes into the package or the checkout only when told to (`--out models/meshes`)."""
    parser = _parser_of(tool, monkeypatch)
    for action in parser._actions:
        if action.dest in OUTPUT_OPTIONS and action.default is not None:
            path = Path(action.default)
            assert not path.is_absolute() and ".." not in path.parts, \
                f"{tool.name}: {action.option_strings[0]} defaults to {path}"


def test_the_generators_write_into_the_current_directory(tmp_path):
    """make_model and make_meshes, run with no option in an empty folder, write there what
    is shipped (byte for byte; the PNG texture, its pixels and palette) and leave the shipped
    files alone."""
    import subprocess

    from corobot_drake.resources import MODELS_DIR

    for tool in ("make_model", "make_meshes"):
        subprocess.run([sys.executable, str(REPO / "tools" / f"{tool}.py")], cwd=tmp_path,
                       check=True, capture_output=True)
    assert (tmp_path / "corobot.sdf").read_bytes() == (MODELS_DIR / "corobot.sdf").read_bytes()
    written = sorted(p.name for p in (tmp_path / "meshes").iterdir())
    assert "wheel.obj" in written
    same_content = load_tool("make_meshes").same_content  # a PNG by its pixels and palette
    for name in written:
        assert same_content(name, (tmp_path / "meshes" / name).read_bytes(),
                            MODELS_DIR / "meshes" / name), name


def test_tuning_writes_a_scenario_only_when_it_is_named(tmp_path):
    import subprocess

    run = subprocess.run([sys.executable, str(REPO / "tools" / "tune_motor_torque_scaling.py"),
                          "--write"], cwd=tmp_path, capture_output=True, text=True)
    assert run.returncode == 2
    assert run.stderr.splitlines() == [
        "error: --write: name the scenario file to write with --scenario (the shipped scenario "
        "is never written by default)"]


def _first_paragraph(doc: str) -> str:
    """A docstring's first paragraph, its whitespace as --help wraps it."""
    return " ".join(doc.strip().split("\n\n")[0].split())


@pytest.mark.parametrize("tool", TOOLS, ids=lambda t: t.stem)
def test_help_describes_a_tool_in_its_whole_first_paragraph(tool, monkeypatch):
    """Not its first line alone: a sentence running over two lines was cut off."""
    import ast

    parser = _parser_of(tool, monkeypatch)
    assert " ".join(parser.description.split()) == \
        _first_paragraph(ast.get_docstring(ast.parse(tool.read_text())))


@pytest.mark.parametrize("module", ["corobot_drake.cli", "corobot_drake.study.__main__",
                                    "corobot_drake.ros2.inspection", "corobot_drake.ros2.build"])
def test_help_describes_a_module_in_its_whole_first_paragraph(module, monkeypatch, capsys):
    monkeypatch.setattr(sys, "argv", ["corobot_drake/__main__.py"])  # as `python -m` runs it
    imported = importlib.import_module(module)
    with pytest.raises(SystemExit) as stop:
        imported.main(["--help"])
    assert stop.value.code == 0
    assert _first_paragraph(imported.__doc__) in " ".join(capsys.readouterr().out.split())


WITHOUT_EXTRAS = """
import contextlib, io, json, runpy, sys

from corobot_drake.extras import EXTRAS

for module in {m for modules in EXTRAS.values() for m in modules}:
    sys.modules[module] = None  # as if no extra were installed: its import fails
results = {}
for tool in sys.argv[1:]:
    out, err = io.StringIO(), io.StringIO()
    sys.argv = [tool, "--help"]
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            runpy.run_path(tool, run_name="__main__")
            status = None
        except SystemExit as e:
            status = e.code
        except BaseException as e:  # what a user would see as a traceback
            status = f"{type(e).__name__}: {e}"
    results[tool] = [status, out.getvalue(), err.getvalue()]
print(json.dumps(results))
"""


def test_a_tool_without_its_extra_says_which_in_one_line():
    """Every tool's and example's --help with no extra installed: its help, or one line
    naming the extras it needs (exit status 2), never a traceback. One process runs them all
    (each import of a missing module fails again)."""
    import json
    import re
    import subprocess

    programs = [*TOOLS, *sorted((REPO / "examples").glob("*.py"))]
    run = subprocess.run([sys.executable, "-c", WITHOUT_EXTRAS, *map(str, programs)], cwd=REPO,
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    needs = re.compile(r"error: (?:tools|examples)/(\w+)\.py needs the \[(\w+)\]"
                       r"( and \[(\w+)\] extras| extra)"
                       r": pip install '\.\[[\w,]+\]' in corobot-drake's clone or unpacked "
                       r"sdist \(it is not on PyPI; tools/setup installs every extra\)\n")
    wrong, said = [], set()
    for tool, (status, out, err) in json.loads(run.stdout).items():
        name = Path(tool).stem
        if status in (0, None) and out.startswith("usage: ") and not err:
            continue
        match = needs.fullmatch(err)
        if status == 2 and not out and match and match[1] == name:
            said.add(name)
            continue
        wrong.append(f"{name}: exit {status}: {(err or out)[-300:]}")
    assert not wrong, "\n".join(wrong)
    assert {"train_policy", "bench", "bench_server_flood", "bench_recording", "drive_legs",
            "ros2_square", "ros2_teleop", "ros2_magellan", "ros2_referee", "fit_drive_log",
            "tune_motor_torque_scaling"} <= said


def test_a_tool_without_the_guard_imports_no_extra_later():
    """A tool that starts without an extra (no `exit_without`) imports none of an extra's
    modules in its functions either: else it would stop with a traceback after its work (as
    tools/snapshot.py once did, writing its PNG with Matplotlib after the render)."""
    import ast

    from corobot_drake.extras import EXTRAS

    extra_modules = {m for modules in EXTRAS.values() for m in modules}
    late = []
    for tool in TOOLS:
        text = tool.read_text()
        if "exit_without(" in text:
            continue
        functions = [f for f in ast.walk(ast.parse(text))
                     if isinstance(f, ast.FunctionDef | ast.AsyncFunctionDef)]
        for node in (n for f in functions for n in ast.walk(f)):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module] if isinstance(node, ast.ImportFrom) and node.level == 0 else []
            late += [f"{tool.name}:{node.lineno}: {n}" for n in names
                     if n.split(".")[0] in extra_modules]
    assert late == []


EXAMPLES = sorted((REPO / "examples").glob("*.py"))


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda e: e.stem)
def test_help_describes_an_example_in_its_whole_first_paragraph(example):
    import ast
    import subprocess

    run = subprocess.run([sys.executable, str(example), "--help"], capture_output=True,
                         text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert _first_paragraph(ast.get_docstring(ast.parse(example.read_text()))) in \
        " ".join(run.stdout.split())
