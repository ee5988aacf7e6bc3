"""The house rules a reader relies on: no function needs scrolling, the scenario layer stands
on the ground floor, and the package imports nothing of the lab."""

import ast
import subprocess
import sys

import pytest

from conftest import REPO

MAX_FUNCTION_LINES = 80
CODE = ("corobot_drake", "lab", "tools", "tests", "examples")
GROUND_FLOOR = ("config", "model", "limits", "resources", "extras", "commands", "signals",
                "topics")
"""The package's modules and folders that import none of the floors above them."""
UPPER_FLOORS = ("systems", "sensors", "station", "markers", "simulation", "serving", "recording",
                "study", "gym", "tuning", "ros2", "cli")
FRONT_ENDS = ("markers", "simulation", "serving", "recording", "study", "gym", "tuning", "ros2",
              "cli", "systems.slip_markers")
"""What attaches to the station through its hooks (`build_station`'s `extras`): the Meshcat
markers, the recording and Foxglove topics, ROS 2, and the front ends above them."""


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


SENSOR_KINDS = {"corobot_drake.sensors.registry", "corobot_drake.sensors.registry.KINDS"}
"""What the ground floor may import of the floors above: the registered kinds of sensor, of
which the scenario's robot is made (a map per kind) and whose checks the loader runs."""


@pytest.mark.parametrize("floor", GROUND_FLOOR)
def test_the_ground_floor_imports_nothing_above_it(floor):
    paths = ([REPO / "corobot_drake" / f"{floor}.py"] if (REPO / "corobot_drake" / f"{floor}.py")
             .exists() else list(_python_files(f"corobot_drake/{floor}")))
    up = {f"{p.relative_to(REPO)}: {m}" for p in paths for m in _imported_modules(p)
          if any(m == f"corobot_drake.{u}" or m.startswith(f"corobot_drake.{u}.")
                 for u in UPPER_FLOORS) and m not in SENSOR_KINDS}
    assert up == set()


def test_the_package_imports_no_lab():
    assert {f"{p.relative_to(REPO)}: {m}" for p in _python_files("corobot_drake")
            for m in _imported_modules(p) if m == "lab" or m.startswith("lab.")} == set()


def test_the_station_knows_no_front_end_and_finds_sensors_through_the_registry():
    """Meshcat markers, recording, Foxglove and ROS 2 attach through the station's hooks; each
    kind of sensor is added through `sensors.registry`, not by name."""
    imported = _imported_modules(REPO / "corobot_drake" / "station.py")
    front_ends = {m for m in imported for f in FRONT_ENDS
                  if m == f"corobot_drake.{f}" or m.startswith(f"corobot_drake.{f}.")}
    sensors = {m for m in imported if m.startswith("corobot_drake.sensors.")
               and m.split(".")[2] not in ("registry", "site")}
    assert front_ends | sensors == set()


BLOCK_AND_IMPORT = """
import sys
blocked = {blocked!r}
class Block:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in blocked:
            raise ImportError(f"{{name}} is another extra's")
sys.meta_path.insert(0, Block())
import {module}
"""


@pytest.mark.parametrize(("module", "others"), [
    ("corobot_drake.ros2.run", ("foxglove", "mcap", "ray", "gymnasium")),
    ("corobot_drake.ros2.bag", ("foxglove", "mcap", "ray", "gymnasium", "fastapi", "uvicorn")),
    ("corobot_drake.simulation", ("foxglove", "mcap", "ray", "gymnasium", "fastapi", "uvicorn",
                                  "rclpy", "rosbags")),
])
def test_a_front_end_imports_without_the_other_extras(module, others):
    # `--ros2` needs the [ros2] extra only (with --serve, [serve] too), not [record]'s Foxglove.
    code = BLOCK_AND_IMPORT.format(blocked=set(others), module=module)
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
