"""The house rules a reader relies on: no function needs scrolling, the scenario layer stands
on the ground floor, and the package imports nothing of the lab."""

import ast

import pytest

from conftest import REPO

MAX_FUNCTION_LINES = 80
CODE = ("corobot_drake", "lab", "tools", "tests", "examples")
GROUND_FLOOR = ("config", "model", "limits", "resources", "extras", "commands", "signals")
"""The package's modules and folders that import none of the floors above them."""
UPPER_FLOORS = ("systems", "sensors", "station", "simulation", "serving", "recording", "study",
                "gym", "tuning", "ros2", "cli")


def _python_files(*roots: str):
    for root in roots:
        yield from sorted((REPO / root).rglob("*.py"))


def _imported_modules(path) -> set[str]:
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found |= {node.module, *(f"{node.module}.{a.name}" for a in node.names)}
    return found


def test_no_function_is_over_80_lines():
    long = [f"{path.relative_to(REPO)}:{node.lineno} {node.name} "
            f"({node.end_lineno - node.lineno + 1} lines)"
            for path in _python_files(*CODE)
            for node in ast.walk(ast.parse(path.read_text()))
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
            and node.end_lineno - node.lineno + 1 > MAX_FUNCTION_LINES]
    assert long == []


@pytest.mark.parametrize("floor", GROUND_FLOOR)
def test_the_ground_floor_imports_nothing_above_it(floor):
    paths = ([REPO / "corobot_drake" / f"{floor}.py"] if (REPO / "corobot_drake" / f"{floor}.py")
             .exists() else list(_python_files(f"corobot_drake/{floor}")))
    up = {f"{p.relative_to(REPO)}: {m}" for p in paths for m in _imported_modules(p)
          if any(m == f"corobot_drake.{u}" or m.startswith(f"corobot_drake.{u}.")
                 for u in UPPER_FLOORS)}
    assert up == set()


def test_the_package_imports_no_lab():
    assert {f"{p.relative_to(REPO)}: {m}" for p in _python_files("corobot_drake")
            for m in _imported_modules(p) if m == "lab" or m.startswith("lab.")} == set()
