"""Robots: any small wheeled robot from a robot file; the Corobot is one of them.

A robot is a robot file (YAML, `robots/file.py`: its URDF/SDFormat/MJCF model, base link,
wheel joints per side, drive, tyres, casters and sensors) measured once into a `RobotSpec`
(`robots/spec.py`): the wheels in actuator order with their sides, radius, track,
wheelbase, mass, the links a sensor may ride on, the drive and tyres the scenario starts
from, the sensors. Every module reads a robot's figures from its spec, never from one
robot's constants; a default with no robot at hand is the Corobot's, read from its robot file
(`robots/corobot.py`). What the Corobot's model is generated from (its CAD,
`model/dimensions.py`) only model generation reads.

The scenario names the robot: `robots.<name>.robot: corobot` (the default) names a shipped
robot of `ROBOTS`, any other value a robot file (relative to the scenario file).

How a front end gets a robot's RobotSpec:

- from a built station: `station.robots[name].spec` (`station.RobotParts.spec`);
- from a `Simulation`: `sim.robot(name).spec` (`simulation.Robot.spec`);
- from a scenario: `robot_spec(scenario.robots[name].robot)`.

Each spec is measured once per file (cached by path and modification time).
"""

from __future__ import annotations

from pathlib import Path

from corobot_drake.resources import MODELS_DIR
from corobot_drake.robots.spec import LEFT, RIGHT, RobotSpec, Wheel  # noqa: F401

DEFAULT_ROBOT = "corobot"

ROBOTS: dict[str, Path] = {
    "corobot": MODELS_DIR / "corobot" / "robot.yaml",
    "burger": MODELS_DIR / "burger" / "robot.yaml",  # TurtleBot3 Burger class
    "pioneer": MODELS_DIR / "pioneer" / "robot.yaml",  # Pioneer 3-AT class
}
"""The shipped robots: name -> robot file. A scenario's `robot:` names one of them or a
robot file."""

GENERATED_MODELS = {(MODELS_DIR / "corobot.sdf").resolve()}
"""Models the project generates from its own figures (`model/sdf.py`): the station builds
them from the generator with the scenario's tyres and look (the file is its output at the
defaults, `tools/make_model.py`), so the scenario's `contact` and `visual` shape them."""


def robot_file_path(robot: str) -> Path:
    """The robot file a scenario's `robot:` names: a shipped robot's, or the path itself
    (the loader has made a scenario's relative path absolute)."""
    return ROBOTS[robot] if robot in ROBOTS else Path(robot)


def robot_spec(robot: str = DEFAULT_ROBOT) -> RobotSpec:
    """The RobotSpec of a scenario's `robot:` (a shipped name or a robot file's path);
    ScenarioError (one line naming the robot file's field) when it is wrong."""
    from corobot_drake.robots.load import load_spec

    path = robot_file_path(robot).resolve()
    kind = robot if robot in ROBOTS else None
    cached = _MEASURED.get((path, kind))
    if cached is not None and cached[0] == _stamps(path, cached[1].model_file):
        return cached[1]
    spec = load_spec(path, kind)
    if len(_MEASURED) >= 32:
        _MEASURED.pop(next(iter(_MEASURED)))
    _MEASURED[path, kind] = (_stamps(path, spec.model_file), spec)
    return spec


_MEASURED: dict = {}
"""(robot file, kind) -> (its and its model's modification times, RobotSpec): each robot
measured once, again when either file changes (the oldest of 32 goes first)."""


def _stamps(*paths: Path) -> tuple:
    stamps = []
    for path in paths:
        try:
            stamps.append(path.stat().st_mtime_ns)
        except OSError:
            stamps.append(None)
    return tuple(stamps)


def robot_defaults(robot: str):
    """The scenario `Robot` a robot starts as before a scenario's fields apply: the robot
    file's drive, tyres and sensors (for the Corobot, `config.scenario.Robot()`)."""
    import copy

    from corobot_drake.config import schema as sc

    if robot == DEFAULT_ROBOT:
        return sc.Robot()
    spec = robot_spec(robot)
    n = len(spec.wheels)
    defaults = sc.Robot(robot=robot, drive=copy.deepcopy(spec.drive),
                        contact=copy.deepcopy(spec.contact), wheel_angles=[0.0] * n,
                        wheel_speeds=[0.0] * n)
    for field, configs in spec.sensors.items():
        setattr(defaults, field, copy.deepcopy(configs))
    return defaults
