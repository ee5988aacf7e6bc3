"""The one validation pass over a scenario: everything is checked here, once, as it loads.

For each layer (a file, YAML text, an `--override`), `LayerChecks`:

1. walks the YAML node tree beside the schema before the typed load (unknown fields, wrong
   types, unknown tags, duplicate names, vectors of the wrong size), noting the line of
   every field;
2. after the typed load, checks what the types cannot say (ranges, names, the sensors and
   camera, every pose), on the merged scenario.

Either way a problem stops the load with one `ScenarioError` line, `FILE:LINE: field.path:
message` (the line of the field in this layer, or of its nearest enclosing field).
`build_station` and the systems trust what `load_scenario` returns and do not check again.
"""

import dataclasses as dc
import math
import re
import types
import typing
from pathlib import Path
from typing import Union

import numpy as np
import yaml
from pydrake.common import pretty_class_name
from pydrake.common.yaml import yaml_load_typed
from pydrake.geometry import RenderEngineGlParams, RenderEngineVtkParams
from pydrake.multibody.parsing import ModelDirectives, ProcessModelDirectives
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import SpatialInertia

from corobot_drake.config import scenario as sc
from corobot_drake.config.sensors import RENDERERS, IrSensorConfig
from corobot_drake.model.sdf import LINKS, VISUALS
from corobot_drake.resources import make_parser, resolve_file
from corobot_drake.sensors.ir_models import MODELS as IR_MODELS

# --- 1. the YAML against the schema --------------------------------------------------------


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


def _tag_name(tp) -> str:
    """The YAML tag that selects `tp` in a union, as Drake's typed load reads it (a template
    instance by its base name: `!UniformVector`)."""
    return pretty_class_name(tp).split("[", 1)[0]


def _vector_size(options) -> int | None:
    """The size of one of Drake's schema vectors (`translation`, `deg`: a union of a numpy
    array and `DeterministicVector𝓣3𝓤`, ...), else None."""
    if options[0] is not np.ndarray:
        return None
    for o in options[1:]:
        m = re.search(r"Vector𝓣(\d+)𝓤", _type_name(o))
        if m:
            return int(m.group(1))
    return None


_YAML_SPECIAL_FLOATS = {".inf": math.inf, "+.inf": math.inf, "-.inf": -math.inf, ".nan": math.nan}


def _kind(node) -> str:
    return {yaml.ScalarNode: "value", yaml.SequenceNode: "list", yaml.MappingNode: "mapping"}[
        type(node)]


def _describe(node) -> str:
    return repr(node.value) if isinstance(node, yaml.ScalarNode) else f"a {_kind(node)}"


class _TagTolerantLoader(yaml.SafeLoader):
    """Composes nodes with any `!Tag` (the typed load interprets them)."""


class _SchemaWalk:
    """Walks the composed YAML node tree beside the schema, naming the first problem and
    noting each field's line in `lines`."""

    def __init__(self, source: str, lines: dict[str, int]):
        self.source, self.lines = source, lines

    def fail(self, node, path, message):
        raise sc.ScenarioError(self.source, path, message, node.start_mark.line + 1)

    def check(self, node, tp, path: str):
        if _is_union(tp):
            return self._union(node, typing.get_args(tp), path)
        if tp in (float, int):
            return self._number(node, tp, path)
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
        origin, args = typing.get_origin(tp), typing.get_args(tp)
        if origin in (list, typing.List):  # noqa: UP006
            return self._list(node, args[0], path)
        if origin in (dict, typing.Dict):  # noqa: UP006
            return self._names(node, args[1], path)
        fields = _fields(tp)
        if fields is not None:
            self._struct(node, tp, fields, path)
        # else a Drake type with its own reader; the typed load checks it

    def _union(self, node, args, path):
        options = [a for a in args if a is not type(None)]
        if len(options) == 1:  # Optional[T]
            if isinstance(node, yaml.ScalarNode) and node.value in ("", "null", "~"):
                return
            return self.check(node, options[0], path)
        tag = node.tag[1:] if node.tag.startswith("!") else None
        if tag is None:  # untagged: the first variant of the node's kind, as the typed load
            size = _vector_size(options)
            if size is not None:
                return self._list(node, float, path, size)
            return self.check(node, _untagged_variant(node, options), path)
        names = {_tag_name(o): o for o in options
                 if o is not np.ndarray and not _type_name(o).startswith("_")}
        if tag not in names:
            self.fail(node, path, f"unknown tag !{tag}; expected one of "
                      + ", ".join(f"!{n}" for n in names))
        return self.check(node, names[tag], path)

    def _number(self, node, tp, path):
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

    def _list(self, node, item_type, path, size: int | None = None):
        if not isinstance(node, yaml.SequenceNode):
            self.fail(node, path, f"expected a list, got {_describe(node)}")
        if size is not None and len(node.value) != size:
            self.fail(node, path, f"needs {size} numbers, got {len(node.value)}")
        for i, item in enumerate(node.value):
            self.lines[f"{path}[{i}]"] = item.start_mark.line + 1
            self.check(item, item_type, f"{path}[{i}]")

    def _names(self, node, value_type, path):
        if not isinstance(node, yaml.MappingNode):
            self.fail(node, path, f"expected a mapping of names, got {_describe(node)}")
        seen = set()
        for key, value in node.value:
            sub = f"{path}.{key.value}"
            if key.value in seen:
                self.fail(key, sub, "duplicate name")
            seen.add(key.value)
            self.lines[sub] = key.start_mark.line + 1
            self.check(value, value_type, sub)

    def _struct(self, node, tp, fields, path):
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
            self.lines[sub] = key.start_mark.line + 1
            self.check(value, fields[name], sub)


# --- 2. what the types cannot say -----------------------------------------------------------

_CONTACT_MODELS = ("hydroelastic", "point", "hydroelastic_with_fallback")
_APPROXIMATIONS = ("lagged", "similar", "sap", "tamsi")


def _untagged_variant(node, options):
    """The variant an untagged node loads as: the first list type for a list, the first
    mapping type for a mapping, the first scalar type that reads a scalar."""
    def kind(tp):
        origin = typing.get_origin(tp)
        if origin in (list, typing.List):  # noqa: UP006
            return yaml.SequenceNode
        if origin in (dict, typing.Dict) or _fields(tp) is not None:  # noqa: UP006
            return yaml.MappingNode
        return yaml.ScalarNode

    same_kind = [o for o in options if kind(o) is type(node)] or options
    if isinstance(node, yaml.ScalarNode):
        for option in same_kind:
            if _reads(option, node.value):
                return option
    return same_kind[0]


def _reads(tp, text: str) -> bool:
    if tp is str:
        return True
    if tp is bool:
        return text.lower() in ("true", "false", "yes", "no", "on", "off")
    try:
        tp(text)
    except (TypeError, ValueError):
        return tp is float and text.lower() in _YAML_SPECIAL_FLOATS
    return tp in (int, float)


class LayerChecks:
    """The checks of one layer of a scenario (`source` names it in errors): the YAML `text`
    against the schema on construction, then `validate` on the scenario merged with it."""

    def __init__(self, source: str, text: str, schema=sc.Scenario):
        self.source = source
        self.lines: dict[str, int] = {}
        """Field path (`robots.corobot.drive.slew_rate`) -> its line in this layer."""
        try:
            node = yaml.compose(text, Loader=_TagTolerantLoader)
        except yaml.YAMLError as e:
            mark = getattr(e, "problem_mark", None)
            line = mark.line + 1 if mark else None
            raise sc.ScenarioError(source, "", f"not valid YAML: {getattr(e, 'problem', e)}",
                                   line) from None
        if node is not None:
            _SchemaWalk(source, self.lines).check(node, schema, "")

    def fail(self, path: str, message: str):
        """Raises the ScenarioError at the line of `path`, or of the nearest enclosing field
        this layer has."""
        where = path
        while where and where not in self.lines:
            where = re.sub(r"(\.[^.\[]*|\[\d+\])$", "", where)
        raise sc.ScenarioError(self.source, path, message, self.lines.get(where))

    def validate(self, s: sc.Scenario) -> None:
        """Checks of meaning that the schema's types cannot express."""
        self._plant_config(s.plant_config)
        for name, body in s.world.bodies.items():
            self._world_body(f"world.bodies.{name}", body)
        self._directives(s)
        if len(s.world.sky_color) != 3:
            self.fail("world.sky_color", "needs 3 numbers RGB")
        for name, robot in s.robots.items():
            self._robot(name, robot, s)

    def _plant_config(self, pc) -> None:
        if not pc.time_step > 0:
            self.fail("plant_config.time_step",
                      "must be > 0 (the robot's velocity servo needs the discrete plant)")
        if pc.contact_model not in _CONTACT_MODELS:
            self.fail("plant_config.contact_model",
                      f"{pc.contact_model!r} is not one of {', '.join(_CONTACT_MODELS)}")
        approximation = pc.discrete_contact_approximation
        if approximation not in _APPROXIMATIONS:
            self.fail("plant_config.discrete_contact_approximation",
                      f"{approximation!r} is not one of " + ", ".join(_APPROXIMATIONS))
        if approximation == "tamsi":
            self.fail("plant_config.discrete_contact_approximation",
                      "tamsi ignores the wheels' velocity-servo gains (the robot would not "
                      "move); use lagged, similar or sap")

    def _world_body(self, path: str, body: sc.WorldBody) -> None:
        if not body.fixed and not body.mass > 0:
            self.fail(f"{path}.mass", "a free body needs a mass > 0")
        if len(body.velocity) != 6:
            self.fail(f"{path}.velocity", "needs 6 numbers [w, v]")
        if len(body.color) != 4:
            self.fail(f"{path}.color", "needs 4 numbers RGBA")
        if isinstance(body.shape, sc.Box) and len(body.shape.size) != 3:
            self.fail(f"{path}.shape.size", "needs 3 numbers")
        if isinstance(body.shape, sc.Mesh):
            self._mesh(f"{path}.shape", body.shape, body)
        self._world_pose(f"{path}.pose", body.pose)

    def _mesh(self, path: str, mesh: sc.Mesh, body: sc.WorldBody) -> None:
        try:
            filename = resolve_file(mesh.filename)
        except RuntimeError as e:
            self.fail(f"{path}.filename", sc.one_line(e).removeprefix("error: "))
        if Path(filename).suffix.lower() not in sc.MESH_EXTENSIONS:
            self.fail(f"{path}.filename", f"{mesh.filename!r}: a mesh file is one of "
                      + ", ".join(sc.MESH_EXTENSIONS))
        if not Path(filename).is_file():
            self.fail(f"{path}.filename", f"no such file {filename!r}")
        if filename.lower().endswith(".obj") and not _has_normals(filename):
            self.fail(f"{path}.filename", f"{filename!r} has no vertex normals (vn): the "
                      "cameras' renderer needs them")
        if not (mesh.scale > 0 and math.isfinite(mesh.scale)):
            self.fail(f"{path}.scale", "must be > 0")
        if mesh.collision not in sc.MESH_COLLISIONS:
            self.fail(f"{path}.collision", f"{mesh.collision!r} is not one of "
                      + ", ".join(sc.MESH_COLLISIONS))
        if mesh.collision == "mesh" and body.hydroelastic_modulus > 0:
            self.fail(f"{path}.collision", "a surface mesh touches rigidly: set the body's "
                      "hydroelastic_modulus to 0, or use convex_hull (compliant)")

    def _directives(self, s: sc.Scenario) -> None:
        """Names that clash with the scenario's, then Drake's own processing of the
        directives into a scratch plant (files, formats, frame names), its first line."""
        for i, directive in enumerate(s.directives):
            model = directive.add_model
            if model is None:
                continue
            path = f"directives[{i}].add_model"
            if not model.file:
                self.fail(f"{path}.file", "needs the model's URI: package://... or file://...")
            if model.name in s.robots or model.name in s.world.bodies:
                self.fail(f"{path}.name", f"{model.name!r} already names a robot or a world "
                          "body")
        if not s.directives:
            return
        plant = MultibodyPlant(0.0)
        for name in s.world.bodies:  # what a directive may weld to
            plant.AddRigidBody(name, plant.AddModelInstance(name), SpatialInertia.Zero())
        try:  # all at once: a weld refers to the models added before it
            ProcessModelDirectives(ModelDirectives(directives=s.directives), plant,
                                   make_parser(plant))
        except Exception as e:  # Drake's message (it names the file or frame), one line
            self.fail("directives", sc.one_line(e).removeprefix("error: "))

    def _robot(self, name: str, robot: sc.Robot, s: sc.Scenario) -> None:
        path = f"robots.{name}"
        if not name or "::" in name or "/" in name:
            self.fail(path, "a robot name must be non-empty, without :: or /")
        if name in s.world.bodies:
            self.fail(path, "a world body already has this name")
        if robot.visual not in VISUALS:
            self.fail(f"{path}.visual", f"{robot.visual!r} is not one of " + ", ".join(VISUALS))
        self._world_pose(f"{path}.pose", robot.pose)
        self._all_positive(f"{path}.drive", robot.drive, (
            "motor_torque_scaling", "slew_rate", "max_axle_speed", "control_period"))
        self._all_positive(f"{path}.contact", robot.contact, (
            "friction", "hydroelastic_modulus", "resolution_hint", "effort_limit",
            "servo_damping"))
        self._camera(f"{path}.camera", robot.camera, s)
        for sensor, ir in robot.ir_sensors.items():
            self._ir_sensor(f"{path}.ir_sensors.{sensor}", sensor, ir, s)
        m = robot.motion
        if m.profile not in sc.PROFILES:
            self.fail(f"{path}.motion.profile",
                      f"{m.profile!r} is not one of " + ", ".join(sc.PROFILES))
        self._all_positive(f"{path}.motion", m, ("stall_time", "stall_distance",
                                                  "stall_angle_deg"))
        if len(robot.velocity) != 6:
            self.fail(f"{path}.velocity", "needs 6 numbers [w, v]")
        for field in ("wheel_angles", "wheel_speeds"):
            if len(getattr(robot, field)) != 4:
                self.fail(f"{path}.{field}", "needs 4 numbers")
        if len(robot.axle_speed_command) not in (0, 2):
            self.fail(f"{path}.axle_speed_command", "needs [] or 2 numbers [left, right]")
        for i, cmd in enumerate(robot.commands):
            if isinstance(cmd, sc.Wait) and not cmd.seconds >= 0:
                self.fail(f"{path}.commands[{i}].seconds", "must be >= 0")
            if isinstance(cmd, sc.DriveDistance | sc.RotateDegrees) and not 0 < cmd.power <= 1:
                self.fail(f"{path}.commands[{i}].power", f"must be in (0, 1], got {cmd.power:g}")
            if isinstance(cmd, sc.DriveDistance | sc.RotateDegrees) and len(cmd.start) not in (
                    0, 3):
                self.fail(f"{path}.commands[{i}].start",
                          f"expected [] or [x, y, yaw_deg], got {len(cmd.start)} numbers")

    def _all_positive(self, path: str, config, fields) -> None:
        for field in fields:
            if not getattr(config, field) > 0:
                self.fail(f"{path}.{field}", "must be > 0")

    # -- poses (Drake's schema Transform, `config/poses.py`) --------------------------------

    def _transform(self, path: str, X) -> None:
        """A fixed, finite pose."""
        if not X.IsDeterministic():
            self.fail(path, "must be a fixed pose (no random distributions)")
        try:
            value = X.GetDeterministicValue()
        except Exception as e:  # Drake's own check (e.g. an AngleAxis with a zero axis)
            self.fail(path, str(e).splitlines()[0])
        if not np.all(np.isfinite(value.translation())):
            self.fail(f"{path}.translation", "must be finite")
        R = value.rotation().matrix()
        if not (np.all(np.isfinite(R)) and np.allclose(R @ R.T, np.eye(3), atol=1e-9)):
            self.fail(f"{path}.rotation", "must be a finite rotation (an AngleAxis needs a "
                      "non-zero axis)")

    def _world_pose(self, path: str, X) -> None:
        """A pose in the world: no base_frame."""
        if X.base_frame not in (None, "", "world"):
            self.fail(f"{path}.base_frame",
                      f"a pose in the world has no base_frame (got {X.base_frame!r})")
        self._transform(path, X)

    def _mount(self, path: str, X_PB, s: sc.Scenario) -> None:
        """A sensor's X_PB: its base_frame a link of its robot, a scoped `model::link` of the
        scenario, or empty (the world)."""
        frame = X_PB.base_frame or ""
        model, _, link = frame.rpartition("::")
        if not (frame in ("", "world") or (not model and link in LINKS)
                or (model in s.robots and link in LINKS)
                or (model in s.world.bodies and link == model)):
            self.fail(f"{path}.base_frame",
                      f"{frame!r} is not a link of the robot ({', '.join(LINKS)}), a scoped "
                      "model::link of this scenario, or empty (the world)")
        self._transform(path, X_PB)

    # -- sensors ----------------------------------------------------------------------------

    def _camera(self, path: str, config, s: sc.Scenario) -> None:
        """A camera this project can build (nothing to check without one)."""
        if not config.rgb:
            return
        if config.depth or config.label:
            self.fail(f"{path}.{'depth' if config.depth else 'label'}",
                      "only the colour image is simulated; set it false")
        if not (config.fps > 0 and np.isfinite(config.fps)):
            self.fail(f"{path}.fps", "must be a positive number")
        if not 0 <= config.output_delay < 1.0 / config.fps:
            self.fail(f"{path}.output_delay", f"must be >= 0 and less than one frame "
                      f"(1/fps = {1.0 / config.fps:.4g} s)")
        if not config.capture_offset >= 0:
            self.fail(f"{path}.capture_offset", "must be >= 0")
        rc = config.renderer_class
        if not (isinstance(rc, RenderEngineVtkParams | RenderEngineGlParams) or rc in RENDERERS):
            self.fail(f"{path}.renderer_class", "must be RenderEngineGl, RenderEngineVtk or "
                      "empty (the faster one available)")
        self._mount(f"{path}.X_PB", config.X_PB, s)
        try:
            config.MakeCameras()
        except Exception as e:  # Drake's own validation: one line
            self.fail(path, str(e).splitlines()[0])

    def _ir_sensor(self, path: str, name: str, c: IrSensorConfig, s: sc.Scenario) -> None:
        if not name or any(ch in name for ch in "./: "):
            # It appears in port names and Meshcat paths.
            self.fail(path, "a sensor name must be non-empty, without '.', '/', ':' or spaces")
        if c.samples < 2:
            self.fail(f"{path}.samples", f"must be an integer of at least 2 (rays per fan of "
                      f"the IR cross of rays: one horizontal and one vertical fan); got "
                      f"{c.samples!r}")
        self._mount(f"{path}.X_PB", c.X_PB, s)
        if not 0.0 <= c.dispersion_cone_angle < 180.0:
            self.fail(f"{path}.dispersion_cone_angle",
                      f"must be in [0, 180) degrees; got {c.dispersion_cone_angle}")
        if not 0.0 < c.maximum_range < math.inf:
            self.fail(f"{path}.maximum_range", f"must be > 0 m and finite; got {c.maximum_range}")
        if not 0.0 < c.scan_rate_hz < math.inf:
            self.fail(f"{path}.scan_rate_hz", f"must be > 0 and finite; got {c.scan_rate_hz}")
        if c.model not in IR_MODELS:
            self.fail(f"{path}.model", f"{c.model!r} is not one of {', '.join(IR_MODELS)}")
        if not 0.0 <= c.change_threshold < math.inf:
            self.fail(f"{path}.change_threshold",
                      f"must be >= 0 m and finite; got {c.change_threshold}")
        if not c.noise_std >= 0.0:
            self.fail(f"{path}.noise_std", f"must be >= 0 V; got {c.noise_std}")


def _has_normals(obj_filename: str) -> bool:
    with open(obj_filename, errors="replace") as f:
        return any(line.startswith("vn ") for line in f)


def load_layer(source: str, text: str, schema, defaults=None):
    """One YAML layer checked against `schema` (errors with file and line), then loaded over
    `defaults` (a schema instance; None: the schema's defaults). Returns the value and the
    layer's `LayerChecks`, whose `fail` names a field's line for the checks of meaning."""
    checks = LayerChecks(source, text, schema)
    try:
        value = yaml_load_typed(schema=schema, data=text, defaults=defaults,
                                retain_map_defaults=True)
    except Exception as e:  # the pre-check missed it: still one clear line
        raise sc.ScenarioError(source, "", sc.one_line(e)) from None
    return value, checks
