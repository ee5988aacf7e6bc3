"""The Corobot, the default robot, as its robot file says: the figures a default needs when
no robot is at hand.

`models/corobot/robot.yaml` and the model it names (`models/corobot.sdf`) are the one place
the Corobot's figures live. The scenario schema's defaults (the drive, the IR sensors, the
camera) are the Corobot's, so they read the file untyped (`figures()`: the schema can't need
itself); everything else reads the measured `spec()` (`robots.robot_spec`), as it reads any
robot's. What the model is generated from (its CAD) is `model/`'s alone.
"""

from __future__ import annotations

import functools

from pydrake.common.yaml import yaml_load

from corobot_drake.resources import MODELS_DIR

FILE = MODELS_DIR / "corobot" / "robot.yaml"
"""The Corobot's robot file."""


@functools.cache
def figures() -> dict:
    """The Corobot's robot file as plain YAML (maps, lists, numbers: each figure exactly as
    written; a tagged value is a map with its `_tag`)."""
    return yaml_load(filename=str(FILE))


def wheel_count() -> int:
    """How many wheels the Corobot drives (its robot file's, both sides)."""
    wheels = figures()["wheels"]
    return len(wheels["left"]) + len(wheels["right"])


@functools.cache
def wheel_names() -> tuple[str, ...]:
    """The Corobot's wheels' short names in its model's joint order (its `RobotSpec.
    wheel_names`, `front_left` ...), from its robot file's wheels and its model's joints as
    Drake's parser orders them: for the tables built at import, before a spec can be measured
    (measuring needs the scenario schema)."""
    from pydrake.multibody.plant import MultibodyPlant

    from corobot_drake.resources import make_parser
    from corobot_drake.robots.spec import short_name

    plant = MultibodyPlant(0.0)
    (instance,) = make_parser(plant).AddModels(str(model_file()))
    wheels = {*figures()["wheels"]["left"], *figures()["wheels"]["right"]}
    joints = [plant.get_joint(i).name() for i in plant.GetJointIndices(instance)]
    return tuple(short_name(j) for j in joints if j in wheels)


def model_file():
    """The Corobot's model file (the robot file's `model:`, relative to it)."""
    return (FILE.parent / figures()["model"]).resolve()


def spec():
    """The Corobot's RobotSpec (measured once from its robot file and model)."""
    from corobot_drake.robots import robot_spec

    return robot_spec("corobot")


def drive(field: str):
    """The robot file's `drive.<field>` (a scenario `Drive` default)."""
    return figures()["drive"][field]


def wheels(field: str) -> float:
    """The robot file's `wheels.<field>` (radius, track, wheelbase), m."""
    return figures()["wheels"][field]


def sensor(kind_field: str, name: str) -> dict:
    """The robot file's sensor `name` of a kind (`ir_sensors`, `cameras`, ...), plain YAML."""
    return figures()[kind_field][name]


def mount_of(kind_field: str, name: str) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """(translation m, roll-pitch-yaw deg) of a sensor's `X_PB` in the robot file."""
    X_PB = sensor(kind_field, name)["X_PB"]
    return tuple(X_PB["translation"]), tuple(X_PB["rotation"]["deg"])


def box(name: str) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """(size, centre) m of the Corobot's box-shaped collision part `name` (`chassis`,
    `platform`) in its base frame, as its model has it (its measured spec's shapes)."""
    for shape_name, shape, X_BG in spec().shapes:
        if shape_name.split("/")[-1] == name and hasattr(shape, "size"):
            return tuple(float(v) for v in shape.size()), tuple(
                float(v) for v in X_BG.translation())
    raise KeyError(f"the Corobot's model has no box {name!r}")
