"""The scenario: a typed description of a world and its robots, loaded from YAML.

In the style of Drake's `examples/hardware_sim`: a `Scenario` dataclass read with
`pydrake.common.yaml.yaml_load_typed`, with Drake's own config structs where they fit.
Before the typed load, the raw YAML is checked against the schema so that a bad file stops
with one line naming the file, the line and the field (`ScenarioError`).
"""


import dataclasses as dc
import math
import types
import typing
from pathlib import Path
from typing import Union

import yaml
from pydrake.common.yaml import yaml_dump_typed, yaml_load_typed
from pydrake.multibody.plant import MultibodyPlantConfig
from pydrake.systems.analysis import SimulatorConfig
from pydrake.systems.sensors import CameraConfig

from corobot_drake.model import dimensions as dim
from corobot_drake.model.sdf import VISUALS, WheelContact
from corobot_drake.sensors.camera import check_camera_config, default_camera_config
from corobot_drake.sensors.ir_sensor import (
    IrSensorConfig,
    check_ir_sensor_config,
    check_ir_sensor_name,
    default_ir_sensors,
)

# --- poses and shapes -------------------------------------------------------------------


@dc.dataclass
class Pose:
    """A pose in the world: position (m) and roll-pitch-yaw (degrees, extrinsic x-y-z)."""

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    roll_deg: float = 0.0
    pitch_deg: float = 0.0
    yaw_deg: float = 0.0


@dc.dataclass
class Box:
    """Box with edge lengths (x, y, z), metres."""

    size: list[float] = dc.field(default_factory=lambda: [1.0, 1.0, 1.0])


@dc.dataclass
class Sphere:
    radius: float = 0.5


@dc.dataclass
class Cylinder:
    """Cylinder along its z axis."""

    radius: float = 0.5
    length: float = 1.0


@dc.dataclass
class Capsule:
    """Capsule along its z axis (length excludes the end caps)."""

    radius: float = 0.5
    length: float = 1.0


@dc.dataclass
class Ellipsoid:
    """Ellipsoid with semi-axes a, b, c along x, y, z."""

    a: float = 0.5
    b: float = 0.5
    c: float = 0.5


# typing.Union, not `|`: the YAML tags (!Box ...) are read from a Union's members.
Shape = Union[Box, Sphere, Cylinder, Capsule, Ellipsoid]  # noqa: UP007

# --- world ------------------------------------------------------------------------------


@dc.dataclass
class Ground:
    """The ground: a rigid hydroelastic half-space at z = 0."""

    friction: float = dim.GROUND_FRICTION
    color: list[float] = dc.field(default_factory=lambda: [0.45, 0.5, 0.4, 1.0])


@dc.dataclass
class WorldBody:
    """A body of the world: free (it has mass and moves) or fixed (welded to the world)."""

    shape: Shape = dc.field(default_factory=Box)
    mass: float = 1.0
    """kg; ignored when fixed."""
    pose: Pose = dc.field(default_factory=Pose)
    velocity: list[float] = dc.field(default_factory=lambda: [0.0] * 6)
    """Initial spatial velocity in the world [wx, wy, wz, vx, vy, vz] (rad/s, m/s)."""
    fixed: bool = False
    friction: float = 0.5
    hydroelastic_modulus: float = 1.0e7
    """Pa: the body is compliant-hydroelastic (a cheap contact patch on the ground and with
    the tyres); 0 makes it rigid, touching everything by point contact."""
    color: list[float] = dc.field(default_factory=lambda: [0.75, 0.55, 0.3, 1.0])


@dc.dataclass
class Sun:
    """A directional light: `direction` is the way the light travels, in the world frame."""

    direction: list[float] = dc.field(default_factory=lambda: [0.3, 0.2, -1.0])
    intensity: float = 1.0


@dc.dataclass
class World:
    ground: Ground = dc.field(default_factory=Ground)
    bodies: dict[str, WorldBody] = dc.field(default_factory=dict)
    sun: Sun = dc.field(default_factory=Sun)
    sky_color: list[float] = dc.field(default_factory=lambda: [0.53, 0.73, 0.92])
    """RGB in [0, 1]: the background of the camera images and of Meshcat."""


# --- robots -----------------------------------------------------------------------------


@dc.dataclass
class Drive:
    """Drive parameters of one robot (SPEC "Drive")."""

    motor_torque_scaling: float = dim.MOTOR_TORQUE_SCALING
    """Axle speed (rad/s) at power 1."""
    slew_rate: float = dim.SLEW_RATE
    """rad/s^2: how fast the commanded axle speed may change."""
    max_axle_speed: float = dim.MAX_AXLE_SPEED
    """rad/s: set_speed clamps to +-this."""
    control_period: float = dim.CONTROL_PERIOD
    """s: the drive controller's update period."""


@dc.dataclass
class SetPower:
    """Wheel power per side in [-1, 1] (clamped): axle speed = power x MotorTorqueScaling."""

    left: float = 0.0
    right: float = 0.0


@dc.dataclass
class SetSpeed:
    """Rim speed per side in m/s (axle speed = v / R, clamped to the max axle speed)."""

    left: float = 0.0
    right: float = 0.0


@dc.dataclass
class AllStop:
    """Command both sides to zero speed."""


@dc.dataclass
class Enable:
    """Enable or disable the drive (disabled: wheels held at zero speed, motion ignored)."""

    enabled: bool = True


@dc.dataclass
class Wait:
    """Let the previous command run for this long (s) before the next one."""

    seconds: float = 1.0


@dc.dataclass
class DriveDistance:
    """Drive straight until |distance| m from the start pose (negative: backwards), at
    `power` in (0, 1]; ends succeeded on arrival (SPEC "Commands that complete")."""

    distance: float = 0.0
    power: float = 0.5


@dc.dataclass
class RotateDegrees:
    """Turn in place by `degrees` (positive: counter-clockwise seen from above, i.e. left),
    at `power` in (0, 1]; ends succeeded on arrival."""

    degrees: float = 0.0
    power: float = 0.5


@dc.dataclass
class SetPose:
    """Teleport the robot to (x, y) m facing `yaw_deg`: on the ground, at rest, wheels stopped."""

    x: float = 0.0
    y: float = 0.0
    yaw_deg: float = 0.0


Command = Union[SetPower, SetSpeed, AllStop, Enable, Wait,  # noqa: UP007
                DriveDistance, RotateDegrees, SetPose]
COMPLETING_COMMANDS = (DriveDistance, RotateDegrees, SetPose)
"""Commands that run until they end (succeeded or failed); the script waits for each."""

PROFILES = ("closed_loop", "seed")


@dc.dataclass
class Motion:
    """How DriveDistance and RotateDegrees slow down, land and give up (`motion.py`)."""

    profile: str = "closed_loop"
    """`closed_loop`: speed from the measured distance/angle left, heading held while
    driving; `seed`: the book's (last 6 samples at 60 Hz, halve the speed when < 6 frames
    remain, stop when reached)."""
    stall_time: float = 1.0
    """s: a command that makes no progress for this long fails as `stalled`."""
    stall_distance: float = 0.005
    """m: progress a DriveDistance must make within `stall_time`."""
    stall_angle_deg: float = 0.5
    """deg: progress a RotateDegrees must make within `stall_time`."""


@dc.dataclass
class Robot:
    """One Corobot: where it starts, how it drives, its tyres and its script."""

    pose: Pose = dc.field(default_factory=Pose)
    drive: Drive = dc.field(default_factory=Drive)
    contact: WheelContact = dc.field(default_factory=WheelContact)
    visual: str = "meshes"
    """How the robot looks: `meshes` (the detailed model) or `boxes` (its collision shapes)."""
    commands: list[Command] = dc.field(default_factory=list)
    motion: Motion = dc.field(default_factory=Motion)
    velocity: list[float] = dc.field(default_factory=lambda: [0.0] * 6)
    """Initial chassis spatial velocity in the world [wx, wy, wz, vx, vy, vz] (rad/s, m/s)."""
    wheel_angles: list[float] = dc.field(default_factory=lambda: [0.0] * 4)
    """Initial axle angles (rad, `dimensions.WHEEL_NAMES` order): the encoders start here."""
    wheel_speeds: list[float] = dc.field(default_factory=lambda: [0.0] * 4)
    """Initial axle speeds (rad/s, same order); the drive's commanded axle speeds start at the
    front wheels' (a saved scene carries on without a jolt)."""
    camera: CameraConfig = dc.field(default_factory=default_camera_config)
    """The front camera, Drake's CameraConfig (SPEC defaults; `corobot_drake/sensors/camera.py`).
    `X_PB.base_frame` names a frame of this robot (`chassis`); `{rgb: false}`: no camera."""
    ir_sensors: dict[str, IrSensorConfig] = dc.field(default_factory=default_ir_sensors)
    """IR distance sensors by name (`corobot_drake/sensors/ir_sensor.py`); defaults `front` and
    `rear` at the SPEC positions; `{enabled: false}` removes one."""


def _default_plant_config() -> MultibodyPlantConfig:
    return MultibodyPlantConfig(
        time_step=0.010,
        discrete_contact_approximation="lagged",
        contact_model="hydroelastic_with_fallback",
    )


@dc.dataclass
class Scenario:
    """Everything needed to build and run one simulation."""

    random_seed: int = 0
    simulation_duration: float = math.inf
    """s; the CLI's --duration overrides it."""
    plant_config: MultibodyPlantConfig = dc.field(default_factory=_default_plant_config)
    simulator_config: SimulatorConfig = dc.field(default_factory=SimulatorConfig)
    world: World = dc.field(default_factory=World)
    robots: dict[str, Robot] = dc.field(default_factory=dict)


# --- loading with clear errors ----------------------------------------------------------


class ScenarioError(Exception):
    """A scenario that cannot be used; `str()` is one line naming the file, line and field."""

    def __init__(self, source: str, field: str, message: str, line: int | None = None):
        where = f"{source}:{line}" if line is not None else source
        super().__init__(f"{where}: {field or '(top level)'}: {message}")
        self.source, self.field, self.line = source, field, line


def _fields(cls) -> dict[str, object] | None:
    if dc.is_dataclass(cls):
        hints = typing.get_type_hints(cls)
        return {f.name: hints[f.name] for f in dc.fields(cls)}
    if hasattr(cls, "__fields__"):
        return {f.name: f.type for f in cls.__fields__}
    return None


def _is_union(tp) -> bool:
    return typing.get_origin(tp) in (Union, types.UnionType)


def _type_name(tp) -> str:
    return getattr(tp, "__name__", str(tp))


_YAML_SPECIAL_FLOATS = {".inf": math.inf, "+.inf": math.inf, "-.inf": -math.inf, ".nan": math.nan}


class _Checker:
    """Walks the composed YAML node tree beside the schema, naming the first problem."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, node, path, message):
        raise ScenarioError(self.source, path, message, node.start_mark.line + 1)

    def check(self, node, tp, path: str):
        origin = typing.get_origin(tp)
        args = typing.get_args(tp)
        if _is_union(tp):
            options = [a for a in args if a is not type(None)]
            if len(options) == 1:  # Optional[T]
                if isinstance(node, yaml.ScalarNode) and node.value in ("", "null", "~"):
                    return
                return self.check(node, options[0], path)
            tag = node.tag[1:] if node.tag.startswith("!") else None
            names = {_type_name(o): o for o in options}
            if tag is None:  # untagged means the first variant, as in the typed load
                return self.check(node, options[0], path)
            if tag not in names:
                self.fail(node, path, f"unknown tag !{tag}; expected one of "
                          + ", ".join(f"!{n}" for n in names))
            return self.check(node, names[tag], path)
        if tp in (float, int):
            if not isinstance(node, yaml.ScalarNode):
                self.fail(node, path, f"expected a number, got a {_kind(node)}")
            try:
                value = _YAML_SPECIAL_FLOATS.get(node.value.lower()) if tp is float else None
                if value is None:
                    value = float(node.value) if tp is float else int(node.value)
            except ValueError:
                self.fail(node, path, f"expected {'a number' if tp is float else 'an integer'}, "
                          f"got {node.value!r}")
            if tp is float and math.isnan(value):
                self.fail(node, path, "NaN is not allowed")
            return
        if tp is bool:
            if not isinstance(node, yaml.ScalarNode) or node.value.lower() not in (
                "true", "false", "yes", "no", "on", "off"
            ):
                self.fail(node, path, f"expected true or false, got {_describe(node)}")
            return
        if tp is str:
            if not isinstance(node, yaml.ScalarNode):
                self.fail(node, path, f"expected text, got a {_kind(node)}")
            return
        if origin in (list, typing.List):  # noqa: UP006
            if not isinstance(node, yaml.SequenceNode):
                self.fail(node, path, f"expected a list, got {_describe(node)}")
            for i, item in enumerate(node.value):
                self.check(item, args[0], f"{path}[{i}]")
            return
        if origin in (dict, typing.Dict):  # noqa: UP006
            if not isinstance(node, yaml.MappingNode):
                self.fail(node, path, f"expected a mapping of names, got {_describe(node)}")
            seen = set()
            for key, value in node.value:
                if key.value in seen:
                    self.fail(key, f"{path}.{key.value}", "duplicate name")
                seen.add(key.value)
                self.check(value, args[1], f"{path}.{key.value}")
            return
        fields = _fields(tp)
        if fields is None:
            return  # a Drake type with its own reader; the typed load checks it
        if isinstance(node, yaml.ScalarNode) and node.value in ("", "{}") and not fields:
            return
        if not isinstance(node, yaml.MappingNode):
            self.fail(node, path, f"expected a mapping for {_type_name(tp)}, got {_describe(node)}")
        seen = set()
        for key, value in node.value:
            name = key.value
            sub = f"{path}.{name}" if path else name
            if name in seen:
                self.fail(key, sub, "duplicate field")
            seen.add(name)
            if name not in fields:
                self.fail(key, sub, f"unknown field; {_type_name(tp)} has "
                          + ", ".join(fields))
            self.check(value, fields[name], sub)


def _kind(node) -> str:
    return {yaml.ScalarNode: "value", yaml.SequenceNode: "list", yaml.MappingNode: "mapping"}[
        type(node)]


def _describe(node) -> str:
    return repr(node.value) if isinstance(node, yaml.ScalarNode) else f"a {_kind(node)}"


class _TagTolerantLoader(yaml.SafeLoader):
    """Composes nodes with any `!Tag` (the typed load interprets them)."""


def _check_text(text: str, source: str) -> None:
    try:
        node = yaml.compose(text, Loader=_TagTolerantLoader)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        line = mark.line + 1 if mark else None
        raise ScenarioError(source, "", f"not valid YAML: {getattr(e, 'problem', e)}",
                            line) from None
    if node is None:
        return
    _Checker(source).check(node, Scenario, "")


_CONTACT_MODELS = ("hydroelastic", "point", "hydroelastic_with_fallback")
_APPROXIMATIONS = ("lagged", "similar", "sap", "tamsi")


def _validate(s: Scenario, source: str) -> None:
    """Checks of meaning that the schema's types cannot express."""
    pc = s.plant_config
    if not pc.time_step > 0:
        raise ScenarioError(source, "plant_config.time_step",
                            "must be > 0 (the robot's velocity servo needs the discrete plant)")
    if pc.contact_model not in _CONTACT_MODELS:
        raise ScenarioError(source, "plant_config.contact_model",
                            f"{pc.contact_model!r} is not one of {', '.join(_CONTACT_MODELS)}")
    if pc.discrete_contact_approximation not in _APPROXIMATIONS:
        raise ScenarioError(source, "plant_config.discrete_contact_approximation",
                            f"{pc.discrete_contact_approximation!r} is not one of "
                            + ", ".join(_APPROXIMATIONS))
    if pc.discrete_contact_approximation == "tamsi":
        raise ScenarioError(source, "plant_config.discrete_contact_approximation",
                            "tamsi ignores the wheels' velocity-servo gains (the robot would not "
                            "move); use lagged, similar or sap")
    for name, body in s.world.bodies.items():
        path = f"world.bodies.{name}"
        if not body.fixed and not body.mass > 0:
            raise ScenarioError(source, f"{path}.mass", "a free body needs a mass > 0")
        if len(body.velocity) != 6:
            raise ScenarioError(source, f"{path}.velocity", "needs 6 numbers [w, v]")
        if len(body.color) != 4:
            raise ScenarioError(source, f"{path}.color", "needs 4 numbers RGBA")
        if isinstance(body.shape, Box) and len(body.shape.size) != 3:
            raise ScenarioError(source, f"{path}.shape.size", "needs 3 numbers")
    if len(s.world.sky_color) != 3:
        raise ScenarioError(source, "world.sky_color", "needs 3 numbers RGB")
    for name, robot in s.robots.items():
        path = f"robots.{name}"
        if not name or "::" in name or "/" in name:
            raise ScenarioError(source, path, "a robot name must be non-empty, without :: or /")
        if name in s.world.bodies:
            raise ScenarioError(source, path, "a world body already has this name")
        if robot.visual not in VISUALS:
            raise ScenarioError(source, f"{path}.visual", f"{robot.visual!r} is not one of "
                                + ", ".join(VISUALS))
        d = robot.drive
        for field in ("motor_torque_scaling", "slew_rate", "max_axle_speed", "control_period"):
            if not getattr(d, field) > 0:
                raise ScenarioError(source, f"{path}.drive.{field}", "must be > 0")
        c = robot.contact
        for field in ("friction", "hydroelastic_modulus", "resolution_hint", "effort_limit",
                      "servo_damping"):
            if not getattr(c, field) > 0:
                raise ScenarioError(source, f"{path}.contact.{field}", "must be > 0")
        problem = check_camera_config(robot.camera)
        if problem is not None:
            field, message = problem
            raise ScenarioError(source, f"{path}.camera" + (f".{field}" if field else ""),
                                message)
        for sensor, ir in robot.ir_sensors.items():
            problem = check_ir_sensor_name(sensor)
            if problem is not None:
                raise ScenarioError(source, f"{path}.ir_sensors.{sensor}", problem)
            problem = check_ir_sensor_config(ir)
            if problem is not None:
                raise ScenarioError(source, f"{path}.ir_sensors.{sensor}.{problem[0]}",
                                    problem[1])
        m = robot.motion
        if m.profile not in PROFILES:
            raise ScenarioError(source, f"{path}.motion.profile",
                                f"{m.profile!r} is not one of " + ", ".join(PROFILES))
        for field in ("stall_time", "stall_distance", "stall_angle_deg"):
            if not getattr(m, field) > 0:
                raise ScenarioError(source, f"{path}.motion.{field}", "must be > 0")
        if len(robot.velocity) != 6:
            raise ScenarioError(source, f"{path}.velocity", "needs 6 numbers [w, v]")
        for field in ("wheel_angles", "wheel_speeds"):
            if len(getattr(robot, field)) != 4:
                raise ScenarioError(source, f"{path}.{field}", "needs 4 numbers")
        for i, cmd in enumerate(robot.commands):
            if isinstance(cmd, Wait) and not cmd.seconds >= 0:
                raise ScenarioError(source, f"{path}.commands[{i}].seconds", "must be >= 0")
            if isinstance(cmd, DriveDistance | RotateDegrees) and not 0 < cmd.power <= 1:
                raise ScenarioError(source, f"{path}.commands[{i}].power",
                                    f"must be in (0, 1], got {cmd.power:g}")


def load_scenario(filename: str | Path | None = None, *, data: str | None = None,
                  overrides: list[str] = (), defaults: Scenario | None = None) -> Scenario:
    """Reads a scenario file and/or YAML text, then each override merged on top.

    Raises ScenarioError (one line: file, line, field, problem) for anything wrong.
    """
    scenario = defaults or Scenario()
    layers = []
    if filename is not None:
        path = Path(filename)
        try:
            layers.append((str(path), path.read_text()))
        except OSError as e:
            raise ScenarioError(str(path), "", f"cannot read the file ({e.strerror})") from None
    if data is not None:
        layers.append(("<scenario text>", data))
    layers += [("--override", text) for text in overrides]
    for source, text in layers:
        _check_text(text, source)
        try:
            scenario = yaml_load_typed(schema=Scenario, data=text, defaults=scenario,
                                       retain_map_defaults=True)
        except Exception as e:  # the pre-check missed it: still one clear line
            raise ScenarioError(source, "", (str(e) or type(e).__name__).splitlines()[0]) from None
        _validate(scenario, source)
    return scenario


def save_scenario(scenario: Scenario, filename: str | Path) -> None:
    """Writes a scenario YAML that `load_scenario` reads back to an equal Scenario."""
    Path(filename).write_text(yaml_dump_typed(scenario, schema=Scenario))
