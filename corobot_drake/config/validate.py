"""The one validation pass over a scenario: everything is checked here, once, as it loads.

For each layer (a file, YAML text, an `--override`), `LayerChecks`:

1. takes the text only if it is UTF-8, at most 256 KiB, YAML nested at most 64 deep with at
   most 20000 values (so that any bad input ends within 2 s);
2. walks the YAML node tree beside the schema before the typed load (unknown fields, wrong
   types, unknown or misplaced tags, duplicate names, vectors of the wrong size), noting the
   line of every field;
3. after the typed load, checks every value against its bound (`limits.py`: declared
   beside the schema; a float without one must be finite), then what involves several fields
   (names, the camera, every pose, and the start poses against the ground, the world's bodies
   and each other: `config/placement.py`), on the merged scenario.

Either way a problem stops the load with one `ScenarioError` line, `FILE:LINE: field.path:
message` (the line of the field in this layer, or of its nearest enclosing field).
`build_station` and the systems trust what `load_scenario` returns and do not check again;
`check_scenario` (what `Simulation` runs on a scenario changed in Python) skips one unchanged
since it passed (`mark_checked`).
"""

import copy
import dataclasses as dc
import functools
import math
import re
import types
import typing
from pathlib import Path
from typing import Union

import numpy as np
import yaml
from pydrake.common import pretty_class_name
from pydrake.common.schema import Transform
from pydrake.common.yaml import yaml_dump_typed, yaml_load_typed
from pydrake.geometry import Rgba

from corobot_drake.config import placement
from corobot_drake.config import schema as sc
from corobot_drake.config.bounds import DRAKE_BOUNDS, rule_problem
from corobot_drake.config.directives import DirectiveError, check_directives
from corobot_drake.config.mesh_files import MeshFileError, check_mesh_file, scale_problem
from corobot_drake.config.sensors import FRONT_CAMERA
from corobot_drake.limits import (
    ANGLE,
    COLOR,
    DRAKE_INT,
    ELLIPSOID_MAX_ASPECT,
    FINITE,
    MESH_SCALE,
    POSITION,
    Range,
    bound_of,
)
from corobot_drake.names import unknown_robot_kind
from corobot_drake.resources import resolve_file
from corobot_drake.robots import ROBOTS, robot_defaults, robot_spec
from corobot_drake.sensors.registry import KINDS

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


MAX_DEPTH = 64
"""Deepest YAML nesting read (the schema's deepest field is ~8 levels; thousands overflowed
Python's stack)."""
MAX_VALUES = 20_000
"""Most YAML values one layer may hold, counting each use of an alias (`*name`) again (a world
of 500 bodies has ~10k). Drake's typed load takes ~35 us of CPU a value: 0.7 s at most."""

_Loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
"""libyaml's composer when PyYAML has it: 10x faster than PyYAML's own (1.7 s for 60k
numbers). Composing keeps any `!Tag`; the typed load interprets them."""


def _flow_too_deep(text: str) -> int | None:
    """The line where `[`/`{` brackets first nest deeper than MAX_DEPTH, else None. Checked
    before parsing: PyYAML's scanner takes time quadratic in flow depth (5000 deep: 2 s).
    Brackets in quotes or comments count too: a real scenario has far fewer than 64."""
    if text.count("[") + text.count("{") <= MAX_DEPTH:
        return None
    depth, line = 0, 1
    for m in re.finditer(r"[\[\]{}\n]", text):
        c = m.group()
        if c == "\n":
            line += 1
        elif c in "[{":
            depth += 1
            if depth > MAX_DEPTH:
                return line
        else:
            depth = max(depth - 1, 0)
    return None


def _check_size(source: str, root) -> None:
    """At most MAX_DEPTH levels and MAX_VALUES values below `root` (aliases may make the
    node tree a graph, even a cycle: each visit counts)."""
    stack, values = [(root, 1)], 0
    while stack:
        node, depth = stack.pop()
        values += 1
        if depth > MAX_DEPTH or values > MAX_VALUES:
            message = (f"nested deeper than {MAX_DEPTH} levels; a scenario's fields nest ~8 "
                       "deep" if depth > MAX_DEPTH else
                       f"more than {MAX_VALUES} values (each alias counted at every use)")
            raise sc.ScenarioError(source, "", message, node.start_mark.line + 1)
        if isinstance(node, yaml.SequenceNode):
            stack += [(item, depth + 1) for item in node.value]
        elif isinstance(node, yaml.MappingNode):
            stack += [(n, depth + 1) for pair in node.value for n in pair]


def _yaml_error(source: str, text: str, e: yaml.YAMLError) -> sc.ScenarioError:
    """The one line of a YAML syntax error, at its line."""
    if isinstance(e, yaml.reader.ReaderError):  # a character YAML refuses (a NUL, ...)
        character = chr(e.character) if isinstance(e.character, int) else e.character
        return sc.ScenarioError(source, "", f"not valid YAML: character {character!r} is not "
                                "allowed", text.count("\n", 0, e.position) + 1)
    mark = getattr(e, "problem_mark", None) or getattr(e, "context_mark", None)
    return sc.ScenarioError(source, "", f"not valid YAML: {getattr(e, 'problem', e)}",
                            mark.line + 1 if mark else None)


def _compose(source: str, text: str):
    """The YAML node tree of `text` (None when it holds no document); ScenarioError (with
    the line) when it is not YAML, nests too deep or holds too many values."""
    line = _flow_too_deep(text)
    if line is not None:
        raise sc.ScenarioError(source, "", f"nested deeper than {MAX_DEPTH} levels; a "
                               "scenario's fields nest ~8 deep", line)
    try:
        node = yaml.compose(text, Loader=_Loader)
    except yaml.YAMLError as e:
        raise _yaml_error(source, text, e) from None
    if node is not None:
        _check_size(source, node)
    return node


class _SchemaWalk:
    """Walks the composed YAML node tree beside the schema, naming the first problem and
    noting each field's line in `lines`."""

    def __init__(self, source: str, lines: dict[str, int]):
        self.source, self.lines = source, lines

    def fail(self, node, path, message):
        raise sc.ScenarioError(self.source, path, message, node.start_mark.line + 1)

    def check(self, node, tp, path: str, tag_read: bool = False):
        """`tag_read`: the node's `!Tag` chose `tp` from a union (elsewhere a tag is wrong)."""
        if _is_union(tp):
            return self._union(node, typing.get_args(tp), path)
        if node.tag.startswith("!") and not tag_read:
            self.fail(node, path, f"unexpected tag {node.tag}; a tag picks a variant only "
                      "where there are several (a shape, a command, a rotation)")
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
            if node.tag in _NOT_TEXT:  # the typed load would refuse it without a line
                self.fail(node, path, f"expected text, got {_plain(node)}; quote it for "
                          f"text: '{node.value}'")
            return
        origin, args = typing.get_origin(tp), typing.get_args(tp)
        if origin in (list, typing.List):  # noqa: UP006
            return self._list(node, args[0], path)
        if origin in (dict, typing.Dict):  # noqa: UP006
            return self._names(node, args[1], path)
        fields = _fields(tp)
        if tp is Rgba:
            self._rgba(node, path)
        elif fields is not None:
            self._struct(node, tp, fields, path)
        # else a Drake type with its own reader; the typed load checks it

    def _rgba(self, node, path):
        """Drake's `Rgba`: `{rgba: [r, g, b, a]}` (or 3 numbers), each in [0, 1] (Drake
        would refuse it without a line)."""
        if not isinstance(node, yaml.MappingNode):
            self.fail(node, path, f"expected a mapping {{rgba: [r, g, b, a]}}, got "
                      f"{_describe(node)}")
        for key, value in node.value:
            sub = f"{path}.{key.value}"
            if key.value != "rgba":
                self.fail(key, sub, "unknown field; Rgba has rgba")
            self.lines[sub] = key.start_mark.line + 1
            self._list(value, float, sub)
            if len(value.value) not in (3, 4):
                self.fail(value, sub, f"needs 3 or 4 numbers, got {len(value.value)}")
            for i, item in enumerate(value.value):
                problem = COLOR.problem(float(_YAML_SPECIAL_FLOATS.get(item.value.lower(),
                                                                        item.value)))
                if problem:
                    self.fail(item, f"{sub}[{i}]", problem)

    def _union(self, node, args, path):
        options = [a for a in args if a is not type(None)]
        if len(options) == 1:  # Optional[T]
            if isinstance(node, yaml.ScalarNode) and node.value in ("", "null", "~"):
                return
            return self.check(node, options[0], path)
        if type(None) in args and node.tag == "tag:yaml.org,2002:null":
            return  # one of the variants (a study's grid value, typed later by its field)
        if str in options and node.tag in _NOT_A_SCALAR:  # not one of bool, int, float, str
            self.fail(node, path, f"expected {_variants_text(options)}, got {_plain(node)}")
        tag = node.tag[1:] if node.tag.startswith("!") else None
        if tag is None:  # untagged: the first variant of the node's kind, as the typed load
            size = _vector_size(options)
            if size is not None:
                return self._list(node, float, path, size)
            variant = _untagged_variant(node, options)
            if variant is None:  # no variant is of the node's kind (a list for a number)
                self.fail(node, path, f"expected {_variants_text(options)}, got "
                          f"{_describe(node)}")
            return self.check(node, variant, path)
        names = {_tag_name(o): o for o in options
                 if o is not np.ndarray and not _type_name(o).startswith("_")}
        if tag not in names:
            self.fail(node, path, f"unknown tag !{tag}; expected one of "
                      + ", ".join(f"!{n}" for n in names))
        return self.check(node, names[tag], path, tag_read=True)

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
        if tp is int and DRAKE_INT.problem(value):  # the typed load would fail without a field
            self.fail(node, path, DRAKE_INT.problem(value))

    def _list(self, node, item_type, path, size: int | None = None):
        if not isinstance(node, yaml.SequenceNode):
            self.fail(node, path, f"expected a list, got {_describe(node)}")
        if size is not None and len(node.value) != size:
            self.fail(node, path, f"needs {size} numbers, got {len(node.value)}")
        for i, item in enumerate(node.value):
            self.lines[f"{path}[{i}]"] = item.start_mark.line + 1
            self.check(item, item_type, f"{path}[{i}]")

    def _key(self, key, path):
        # `{[1, 2]: x}` and `{? {a: 1}: x}` are YAML, and no field or name.
        if not isinstance(key, yaml.ScalarNode):
            self.fail(key, path, f"a key must be a name, got {_describe(key)}")

    def _names(self, node, value_type, path):
        if not isinstance(node, yaml.MappingNode):
            self.fail(node, path, f"expected a mapping of names, got {_describe(node)}")
        seen = set()
        for key, value in node.value:
            self._key(key, path)
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
            self._key(key, path)
            name = key.value
            sub = f"{path}.{name}" if path else name
            if name in seen:
                self.fail(key, sub, "duplicate field")
            seen.add(name)
            if (tp, name) in REPLACED_FIELDS:
                self.fail(key, sub, REPLACED_FIELDS[tp, name])
            if name not in fields:
                self.fail(key, sub, f"unknown field; {_type_name(tp)} has "
                          + ", ".join(fields))
            self.lines[sub] = key.start_mark.line + 1
            self.check(value, fields[name], sub)


REPLACED_FIELDS = {
    (sc.Robot, "camera"): "replaced by `cameras`, a map of cameras by name: write "
                          f"`cameras: {{{FRONT_CAMERA}: {{...}}}}` ({FRONT_CAMERA}: the "
                          "Corobot's own camera)",
}
"""{(schema type, field a scenario may still carry): the one line saying what to write now}."""


RIGID_ON_GROUND = ("touches the rigid ground at a single point (Drake's point contact) and "
                   "sinks through it when pushed; only a rigid sphere rests on its one point")
"""Why a free body may not be rigid unless it is a sphere: a 0.2 m box pushed by the robot at
power 0.5, and the 100 kg giant box rammed at full power, sank through the ground at the 10
and 20 ms steps (`tests/simulation/test_models.py` pushes one; the compliant ones stay on it)."""


MAX_SINK = 0.1
"""The deepest a free compliant body may sink into the ground at rest, as a share of its
thickness: a 2 kg, 0.2 m box sank 7 mm at 1e4 Pa (estimated 4.9), one of 20 kg went through
the ground (estimated 49 mm)."""


# --- 2. what the types cannot say -----------------------------------------------------------


def _node_kind(tp):
    """The YAML node a value of type `tp` is written as."""
    origin = typing.get_origin(tp)
    if origin in (list, typing.List):  # noqa: UP006
        return yaml.SequenceNode
    if origin in (dict, typing.Dict) or _fields(tp) is not None:  # noqa: UP006
        return yaml.MappingNode
    return yaml.ScalarNode


_SCALAR_TEXT = {bool: "true or false", int: "an integer", float: "a number", str: "text"}


def _variants_text(options) -> str:
    """The variants of a union in words: `true or false, an integer, a number or text`."""
    words = list(dict.fromkeys(_SCALAR_TEXT.get(o) or {
        yaml.SequenceNode: "a list", yaml.MappingNode: "a mapping"}.get(_node_kind(o),
                                                                      _type_name(o))
        for o in options))
    return ", ".join(words[:-1]) + " or " + words[-1] if len(words) > 1 else words[0]


def _untagged_variant(node, options):
    """The variant an untagged node loads as: the first list type for a list, the first
    mapping type for a mapping, the first scalar type that reads a scalar. When no variant is
    of the node's kind: the first of a union of structures (its error names it), else None
    (a union of scalars given a list: the error names them all)."""
    same_kind = [o for o in options if _node_kind(o) is type(node)]
    if not same_kind:
        return options[0] if {_node_kind(o) for o in options} == {yaml.MappingNode} else None
    if isinstance(node, yaml.ScalarNode):
        for option in same_kind:
            if _reads(option, node.value):
                return option
    return same_kind[0]


_NOT_TEXT = {"tag:yaml.org,2002:null": "null", "tag:yaml.org,2002:bool": "true or false",
             "tag:yaml.org,2002:int": "a number", "tag:yaml.org,2002:float": "a number",
             "tag:yaml.org,2002:timestamp": "a date"}
"""The tags YAML gives a plain (unquoted) scalar that does not load as text: what the typed
load makes of it, in words."""


def _plain(node) -> str:
    """A plain scalar that does not load as text, in words: `null`, `a date ('2026-01-01')`."""
    word = _NOT_TEXT[node.tag]
    return word if node.value == word else f"{word} ({node.value!r})"


_NOT_A_SCALAR = ("tag:yaml.org,2002:null", "tag:yaml.org,2002:timestamp")


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
        if len(text) > sc.MAX_FILE_BYTES:  # an --override or YAML text, as large as a file
            raise sc.ScenarioError(source, "", f"larger than {sc.MAX_FILE_BYTES >> 10} KiB, "
                                   "the most a scenario may be")
        try:  # argv's undecodable bytes come as surrogates: check them as bytes
            data = text.encode("utf-8", "surrogateescape")
        except UnicodeEncodeError:
            data = text.encode("utf-8", "surrogatepass")
        sc.decode(source, data)
        node = _compose(source, text)
        if node is None:
            raise sc.ScenarioError(source, "", f"empty (no YAML document); expected a mapping "
                                   f"of {_type_name(schema)} fields", 1)
        self.robots_node = _field_node(node, "robots") if schema is sc.Scenario else None
        """The layer's `robots:` mapping node (None without one), for `_with_new_sensors`."""
        self.lines: dict[str, int] = {"": node.start_mark.line + 1}
        """Field path (`robots.corobot.drive.slew_rate`) -> its line in this layer ("": the
        document's first)."""
        _SchemaWalk(source, self.lines).check(node, schema, "")

    @classmethod
    def of_object(cls, source: str) -> "LayerChecks":
        """The checks of a scenario built in Python (no text: errors name no line)."""
        checks = cls.__new__(cls)
        checks.source, checks.lines, checks.robots_node = source, {}, None
        return checks

    def has(self, path: str) -> bool:
        """Whether this layer writes the field `path`."""
        return path in self.lines

    def fail(self, path: str, message: str):
        """Raises the ScenarioError at the line of `path`, or of the nearest enclosing field
        this layer has (at worst, the layer's first line)."""
        where = path
        while where and where not in self.lines:
            parent = re.sub(r"(\.[^.\[]*|\[\d+\])$", "", where)
            where = parent if parent != where else ""  # a top-level field: the layer's line
        raise sc.ScenarioError(self.source, path, message, self.lines.get(where))

    def validate(self, s, final: bool = True) -> None:
        """Every value against its bound (`limits.py`), then, for a Scenario, the
        checks of meaning that involve several fields; `final`: also those that a later layer
        may still settle (the plant's step against the integrator: one override may switch
        the plant and the next the integrator)."""
        self._bounds(s, "")
        if isinstance(s, sc.Scenario):
            self._scenario(s)
            if final:
                self._integrator(s)

    # -- every value against its bound ------------------------------------------------------

    def _bounds(self, obj, path: str) -> None:
        """Walks a loaded value: the fields of dataclasses (bounds in their metadata) and of
        Drake's config structs (bounds in `DRAKE_BOUNDS`), mappings and lists."""
        if isinstance(obj, dict):
            for key, value in obj.items():
                self._value(value, f"{path}.{key}", None)
        elif dc.is_dataclass(obj):
            hints = _hints(type(obj))
            for f in dc.fields(obj):
                value = getattr(obj, f.name)
                if not _has_type(value, hints[f.name]):  # a scenario built in Python
                    self.fail(_join(path, f.name), f"expected {_type_text(hints[f.name])}, got "
                              f"{value!r:.60}")
                self._value(value, _join(path, f.name), bound_of(f), f.metadata.get("size"))
        elif hasattr(type(obj), "__fields__") and not isinstance(obj, Transform):
            table = DRAKE_BOUNDS.get(type(obj), {})
            for f in type(obj).__fields__:
                self._value(getattr(obj, f.name), _join(path, f.name), table.get(f.name))

    def _value(self, value, path: str, bound, size: int | None = None) -> None:
        if isinstance(value, list):
            if size is not None and len(value) != size:
                self.fail(path, f"needs {size} numbers, got {len(value)}")
            for i, item in enumerate(value):
                # One bound per element: an element past them is finite (the field's own
                # check says how many it takes).
                self._value(item, f"{path}[{i}]", (bound[i] if i < len(bound) else None)
                            if isinstance(bound, tuple) else bound)
        elif isinstance(value, bool) or value is None:
            return
        elif isinstance(bound, Range) and not isinstance(value, int | float | np.number):
            self.fail(path, f"expected a number, got {value!r}")  # a scenario built in Python
        elif isinstance(value, int | float | np.number):
            bound = bound or (DRAKE_INT if isinstance(value, int | np.integer) else FINITE)
            problem = bound.problem(value)
            if problem:
                self.fail(path, problem)
        elif isinstance(value, str):
            problem = bound.problem(value) if bound else None
            if problem:
                self.fail(path, problem)
        elif isinstance(value, np.ndarray):  # a vector of Drake's struct (a light's position)
            for i, item in enumerate(value.ravel().tolist()):
                self._value(item, f"{path}[{i}]", bound)
        elif isinstance(value, Rgba):
            for channel in "rgba":
                problem = COLOR.problem(getattr(value, channel)())
                if problem:
                    self.fail(f"{path}.{channel}", problem)
        elif not isinstance(value, Transform):  # poses: checked as poses below
            self._bounds(value, path)

    # -- what involves several fields -------------------------------------------------------

    def _scenario(self, s: sc.Scenario) -> None:
        for name, body in s.world.bodies.items():
            self._world_pose(f"world.bodies.{name}.pose", body.pose)
            shape = body.shape
            if isinstance(shape, sc.Mesh):
                self._mesh(f"world.bodies.{name}.shape", shape, body)
            self._free_rigid_body(f"world.bodies.{name}", body)
            self._sink(f"world.bodies.{name}", body)
            if isinstance(shape, sc.Ellipsoid) and body.hydroelastic_modulus > 0:
                axes = (shape.a, shape.b, shape.c)
                if max(axes) > ELLIPSOID_MAX_ASPECT * min(axes):
                    self.fail(f"world.bodies.{name}.shape", f"a compliant ellipsoid's largest "
                              f"semi-axis may be at most {ELLIPSOID_MAX_ASPECT:g} times its "
                              f"smallest (its mesh grows fast); got {max(axes) / min(axes):.3g}"
                              "; or make it rigid (hydroelastic_modulus: 0)")
        models = self._directives(s)
        if not np.linalg.norm(s.world.sun.direction) >= 1e-6:  # it is normalized
            self.fail("world.sun.direction", "must not be zero (the way the light travels): "
                      "a length of at least 1e-6")
        for name, robot in s.robots.items():
            self._robot(name, robot, s)
        self._placement(s, models)

    def _integrator(self, s: sc.Scenario) -> None:
        """A continuous plant (`time_step: 0`) with CENIC, stepped at most `TIME_STEP`; a
        discrete one (SAP) with any other scheme (Drake's CENIC refuses a discrete plant)."""
        cenic = s.simulator_config.integration_scheme == sc.CENIC
        if s.plant_config.time_step == 0 and not cenic:
            self.fail("simulator_config.integration_scheme", "a continuous plant "
                      "(plant_config.time_step: 0) needs cenic; got "
                      f"{s.simulator_config.integration_scheme}")
        if s.plant_config.time_step > 0 and cenic:
            self.fail("plant_config.time_step", "cenic needs a continuous plant (0); got "
                      f"{s.plant_config.time_step:g} (a discrete plant steps with SAP: set "
                      "simulator_config.integration_scheme: runge_kutta3)")
        broken = rule_problem(s.simulator_config)  # cenic's step (`DRAKE_RULES`)
        if broken:
            self.fail(f"simulator_config.{broken[0]}", broken[1])
        if not cenic and _dumped(s.cenic_solver) != _dumped(sc.Scenario().cenic_solver):
            self.fail("cenic_solver", "sets the solver of cenic's steps; the plant steps with "
                      f"{s.simulator_config.integration_scheme} (set it only with "
                      "integration_scheme: cenic)")

    def _mesh(self, path: str, mesh: sc.Mesh, body: sc.WorldBody) -> None:
        try:
            filename = resolve_file(mesh.filename)
        except RuntimeError as e:
            self.fail(f"{path}.filename", sc.one_line(e).removeprefix("error: "))
        try:
            info = check_mesh_file(filename, sc.MESH_EXTENSIONS)
        except MeshFileError as e:
            self.fail(f"{path}.filename", f"{filename}: {e}")
        problem = scale_problem(info, mesh.scale, MESH_SCALE)
        if problem:
            self.fail(f"{path}.scale", problem)
        if mesh.collision not in sc.MESH_COLLISIONS:
            self.fail(f"{path}.collision", f"{mesh.collision!r} is not one of "
                      + ", ".join(sc.MESH_COLLISIONS))
        if mesh.collision == "mesh" and not filename.lower().endswith(".obj"):
            self.fail(f"{path}.collision", "a surface mesh touches as Drake's rigid "
                      "hydroelastic mesh, which is read from an OBJ file: use an .obj, or "
                      "convex_hull")
        if mesh.collision == "mesh" and not body.fixed:
            self.fail(f"{path}.collision", "a surface mesh touches rigidly, and a free rigid "
                      f"body {RIGID_ON_GROUND}: make the body fixed, or use convex_hull "
                      "(compliant)")
        if mesh.collision == "mesh" and body.hydroelastic_modulus > 0:
            self.fail(f"{path}.collision", "a surface mesh touches rigidly: set the body's "
                      "hydroelastic_modulus to 0, or use convex_hull (compliant)")

    def _sink(self, path: str, body: sc.WorldBody) -> None:
        """A free compliant body must not sink into the ground under its own weight by more
        than MAX_SINK of its thickness (`placement.static_sink`)."""
        if body.fixed or body.hydroelastic_modulus == 0:
            return
        sink, thickness, least_modulus = placement.static_sink(body, MAX_SINK)
        if sink > MAX_SINK * thickness:
            self.fail(f"{path}.hydroelastic_modulus", f"too soft for its mass: it would sink "
                      f"~{sink * 1000:.0f} mm into the ground (at most {MAX_SINK:.0%} of its "
                      f"{thickness * 1000:.0f} mm); at least {least_modulus:.2g} Pa, or less mass")

    def _free_rigid_body(self, path: str, body: sc.WorldBody) -> None:
        """A free body in point contact (`hydroelastic_modulus: 0`) only if it is a sphere:
        Drake's point contact touches the rigid ground at one point per pair, which holds a
        ball but not a face."""
        if body.fixed or body.hydroelastic_modulus > 0 or isinstance(body.shape, sc.Sphere):
            return
        if isinstance(body.shape, sc.Mesh) and body.shape.collision == "mesh":
            return  # refused with its collision field
        self.fail(f"{path}.hydroelastic_modulus", f"a free rigid {type(body.shape).__name__} "
                  f"{RIGID_ON_GROUND}: give it a modulus (compliant; the default "
                  f"{sc.WorldBody.hydroelastic_modulus:g} Pa), or make it fixed")

    def _directives(self, s: sc.Scenario) -> list:
        """Names that clash with the scenario's, then the files and what Drake makes of them
        (`config/directives.py`); returns the models' collision shapes, for the placement."""
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
            return []
        try:
            return check_directives(s.directives, s.world.bodies, RIGID_ON_GROUND)
        except DirectiveError as e:
            self.fail(e.path, str(e))

    def _robot(self, name: str, robot: sc.Robot, s: sc.Scenario) -> None:
        path = f"robots.{name}"
        if not ROBOT_NAME.fullmatch(name) or name in (".", ".."):
            # It is a URL path segment (/robots/<name>/...) and names the robot's systems.
            self.fail(path, "a robot name must be letters, digits, '_', '-', '.' or '~' (it is "
                      f"a URL path segment, /robots/<name>), not '.' or '..'; got {name!r}")
        if name in s.world.bodies:
            self.fail(path, "a world body already has this name")
        self._world_pose(f"{path}.pose", robot.pose)
        self._robot_kind(path, robot)
        for kind in KINDS:
            for sensor, config in getattr(robot, kind.field).items():
                self._sensor(f"{path}.{kind.field}.{sensor}", kind, sensor, config, robot, s)
        self._resume_fields(path, robot)

    def _robot_kind(self, path: str, robot: sc.Robot) -> None:
        """The robot file its `robot:` names, loaded (its own problems name its own lines),
        and the drive's effective radius and track near the robot's own."""
        if robot.robot not in ROBOTS and not Path(robot.robot).is_file():
            self.fail(f"{path}.robot", unknown_robot_kind(robot.robot, ROBOTS))
        spec = robot_spec(robot.robot)
        d = robot.drive
        if not 0.5 * spec.wheel_radius <= d.effective_wheel_radius <= 1.5 * spec.wheel_radius:
            self.fail(f"{path}.drive.effective_wheel_radius", f"must be within 50% of the "
                      f"wheels' radius {spec.wheel_radius:.6g} m; got {d.effective_wheel_radius:g}")
        if not 0.5 * spec.track <= d.effective_track_width <= 4.0 * spec.track:
            self.fail(f"{path}.drive.effective_track_width", f"must be from 0.5 to 4 times the "
                      f"wheels' track {spec.track:.6g} m (a skid steer's is wider); got "
                      f"{d.effective_track_width:g}")

    def _resume_fields(self, path: str, robot: sc.Robot) -> None:
        """The fields a saved scene writes to resume a drive: sizes that a bound cannot state
        (empty, or a full vector)."""
        if len(robot.axle_speed_command) not in (0, 2):
            self.fail(f"{path}.axle_speed_command", "needs [] or 2 numbers [left, right]")
        n = len(robot_spec(robot.robot).wheels)
        for field in ("wheel_angles", "wheel_speeds"):
            if len(getattr(robot, field)) != n:
                self.fail(f"{path}.{field}", f"needs {n} numbers (one per wheel), got "
                          f"{len(getattr(robot, field))}")
        if len(robot.wheel_hold_angles) not in (0, n):
            self.fail(f"{path}.wheel_hold_angles", f"needs [] or {n} angles (rad)")
        if len(robot.odometry) not in (0, 3, 5):
            self.fail(f"{path}.odometry", "needs [], [x, y, yaw] or [x, y, yaw, left ticks, "
                      "right ticks]")
        window = max(1, round(sc.SEED_WINDOW / robot.drive.control_period))
        for i, cmd in enumerate(robot.commands):
            if not isinstance(cmd, sc.DriveDistance | sc.RotateDegrees):
                continue
            if len(cmd.start) not in (0, 3):
                self.fail(f"{path}.commands[{i}].start",
                          f"expected [] or [x, y, yaw_deg], got {len(cmd.start)} numbers")
            if cmd.recent_progress and not cmd.start:
                self.fail(f"{path}.commands[{i}].recent_progress",
                          "needs `start` (the progress counts from it)")
            if len(cmd.recent_progress) > window:
                self.fail(f"{path}.commands[{i}].recent_progress",
                          f"at most {window} values (one per control update in the seed "
                          f"profile's last {sc.SEED_WINDOW:g} s); got {len(cmd.recent_progress)}")

    def _placement(self, s: sc.Scenario, models: list) -> None:
        """Robots on or above the ground, clear of the world's bodies and of each other; free
        bodies not in the ground (`config/placement.py`)."""
        for problem in placement.problems(s, models):
            # Blame the pose this layer wrote: the robot's, else the other body's.
            paths = [p for p in problem.paths if self.has(p)] or list(problem.paths)
            self.fail(paths[0], problem.message)

    # -- poses (Drake's schema Transform, `config/poses.py`) --------------------------------

    def _transform(self, path: str, X) -> None:
        """A fixed, finite pose within the world's bounds."""
        if not X.IsDeterministic():
            self.fail(path, "must be a fixed pose (no random distributions)")
        rotation = X.rotation.value
        for name, bound in (("deg", ANGLE), ("angle_deg", ANGLE), ("axis", FINITE)):
            values = np.atleast_1d(np.asarray(getattr(rotation, name, []), dtype=float))
            for i, v in enumerate(values):
                problem = bound.problem(float(v))
                if problem:
                    self.fail(f"{path}.rotation.{name}" + (f"[{i}]" if len(values) > 1 else ""),
                              problem)
        try:
            value = X.GetDeterministicValue()
        except Exception as e:  # Drake's own check (e.g. an AngleAxis with a zero axis)
            self.fail(path, sc.one_line(e))
        for i, v in enumerate(value.translation()):
            problem = POSITION.problem(float(v))
            if problem:
                self.fail(f"{path}.translation[{i}]", problem)
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

    def _mount(self, path: str, X_PB, robot: sc.Robot, s: sc.Scenario) -> None:
        """A sensor's X_PB: its base_frame a link of its `robot`, a scoped `model::link` of
        the scenario, or empty (the world)."""
        frame = X_PB.base_frame or ""
        model, _, link = frame.rpartition("::")
        links = robot_spec(robot.robot).links  # (a robot's name may hold dots: not from path)
        if not (frame in ("", "world") or (not model and link in links)
                or (model in s.robots and link in robot_spec(s.robots[model].robot).links)
                or (model in s.world.bodies and link == model)):
            self.fail(f"{path}.base_frame",
                      f"{frame!r} is not a link of the robot ({', '.join(links)}), a scoped "
                      "model::link of this scenario, or empty (the world)")
        self._transform(path, X_PB)

    # -- sensors ----------------------------------------------------------------------------

    def _sensor(self, path: str, kind, name: str, config, robot: sc.Robot,
                s: sc.Scenario) -> None:
        """A sensor of any kind (`registry.KINDS`) of `robot`: its name, its mount (every
        config has an `X_PB` on a link of its robot), then, unless it is turned off, its
        kind's own checks (`SensorKind.check`)."""
        if not SENSOR_NAME.fullmatch(name):
            # It appears in port names, Meshcat paths, topics and URLs
            # (/robots/<robot>/<sensor>).
            self.fail(path, "a sensor name must be letters, digits, '_', '-' or '~'; got "
                      f"{name!r}")
        self._mount(f"{path}.X_PB", config.X_PB, robot, s)
        if not kind.enabled(config):
            return
        broken = rule_problem(config)  # a Drake struct's rules (`DRAKE_RULES`: the camera's)
        if broken:
            self.fail(f"{path}.{broken[0]}", broken[1])
        for field, problem in kind.check(config):
            self.fail(f"{path}.{field}" if field else path, problem)



@functools.cache
def _hints(cls) -> dict:
    return typing.get_type_hints(cls)


def _has_type(value, tp) -> bool:
    """Whether `value` is of the schema type `tp`, as far as the walk relies on it (Drake's
    own types are checked by their own fields)."""
    if _is_union(tp):
        return any(_has_type(value, t) for t in typing.get_args(tp))
    if tp is type(None):
        return value is None
    if tp is float:
        return isinstance(value, int | float | np.number) and not isinstance(value, bool)
    if tp is int:
        return isinstance(value, int | np.integer) and not isinstance(value, bool)
    if tp is bool:
        return isinstance(value, bool | np.bool_)
    origin = typing.get_origin(tp)
    if origin is not None:
        return isinstance(value, origin)
    return isinstance(value, tp) if isinstance(tp, type) else True


def _type_text(tp) -> str:
    if _is_union(tp):
        return " or ".join(_type_text(t) for t in typing.get_args(tp))
    origin = typing.get_origin(tp)
    return "None" if tp is type(None) else _type_name(origin or tp)


def _dumped(struct) -> str:
    """A Drake config struct as YAML (they have no value equality)."""
    return yaml_dump_typed(struct)


def _join(path: str, name: str) -> str:
    return f"{path}.{name}" if path else name


ROBOT_NAME = re.compile(r"[A-Za-z0-9_.~-]+")
"""A robot's name: RFC 3986's unreserved characters, so that it is a URL path segment as it
is (the services' URLs, /robots/<name>)."""
SENSOR_NAME = re.compile(r"[A-Za-z0-9_~-]+")
"""A sensor's name: as a robot's, without '.' (it joins port names: `<robot>.<sensor>`)."""

PYTHON_SOURCE = "<Python scenario>"
"""What an error names for a scenario built in Python (not loaded from a file)."""


def check_scenario(scenario: sc.Scenario, source: str = PYTHON_SOURCE) -> None:
    """The checks `load_scenario` runs after its typed load (bounds, names, poses, placement),
    on a scenario built or changed in Python; ScenarioError (one line, no line number).
    A scenario unchanged since it passed them (`load_scenario`'s, or here) is not checked
    again (`mark_checked`)."""
    if not isinstance(scenario, sc.Scenario):
        raise sc.ScenarioError(source, "", f"expected a Scenario, got {type(scenario).__name__}")
    content = _content(scenario)
    if content is not None and getattr(scenario, _CHECKED, None) == content:
        return
    try:
        LayerChecks.of_object(source).validate(scenario)
    except sc.ScenarioError:
        raise
    except Exception as e:  # a field of the wrong type where the walk expected another
        raise sc.ScenarioError(source, "", f"not a valid Scenario ({sc.one_line(e)})") from None
    setattr(scenario, _CHECKED, content)


# --- checked once ----------------------------------------------------------------------------

_CHECKED = "_checked_content"
"""The attribute of a Scenario that passed the checks: its `_content` then. Any change since
(a field set, a list or array changed in place) gives another content, and the checks again."""


def mark_checked(scenario: sc.Scenario) -> None:
    """Notes that `scenario`, as it is now, passed the checks (`load_scenario` marks what it
    returns), so that `check_scenario` (`Simulation`) does not repeat them until it changes."""
    setattr(scenario, _CHECKED, _content(scenario))


class _OpaqueValueError(Exception):
    """A value whose content `_content` cannot see: such a scenario is always checked."""


def _content(scenario: sc.Scenario):
    """Every value of the scenario as nested tuples of immutable values (arrays as bytes),
    equal for two states exactly when no field differs; None when a part is of a type it does
    not know (then there is no marker and the checks always run)."""
    try:
        return _value_content(scenario)
    except _OpaqueValueError:
        return None


def _value_content(value):
    if value is None or isinstance(value, bool | int | float | str | np.number):
        return (type(value), value)  # the type too: 1 and 1.0 and True differ to the checks
    if isinstance(value, list | tuple):
        return (type(value), *map(_value_content, value))
    if isinstance(value, dict):
        return (dict, *((key, _value_content(v)) for key, v in value.items()))
    if isinstance(value, np.ndarray):
        return (np.ndarray, value.dtype.str, value.shape, value.tobytes())
    if isinstance(value, Rgba):
        return (Rgba, value.r(), value.g(), value.b(), value.a())
    if dc.is_dataclass(value):
        names = [f.name for f in dc.fields(value)]
    elif hasattr(type(value), "__fields__"):  # Drake's structs: Transform, CameraConfig, ...
        names = [f.name for f in type(value).__fields__]
    else:
        raise _OpaqueValueError
    return (type(value), *(_value_content(getattr(value, name)) for name in names))


def load_layer(source: str, text: str, schema, defaults=None, base: Path | None = None):
    """One YAML layer checked against `schema` (errors with file and line), then loaded over
    `defaults` (a schema instance; None: the schema's defaults). Returns the value and the
    layer's `LayerChecks`, whose `fail` names a field's line for the checks of meaning.
    `base`: the directory a scenario layer's relative robot files are relative to."""
    checks = LayerChecks(source, text, schema)
    if schema is sc.Scenario:
        before = list((defaults or sc.Scenario()).robots)
        defaults = _with_new_robots(checks, defaults or sc.Scenario(), base or Path.cwd())
        defaults = _with_new_sensors(checks.robots_node, defaults)
    try:
        value = yaml_load_typed(schema=schema, data=text, defaults=defaults,
                                retain_map_defaults=True)
    except yaml.YAMLError as e:  # PyYAML's reader (Drake's) is stricter than libyaml's
        raise _yaml_error(source, text, e) from None
    except Exception as e:  # the pre-check missed it: still one clear line
        raise sc.ScenarioError(source, "", sc.one_line(e)) from None
    if schema is sc.Scenario:
        _keep_robot_order(value, before, checks.robots_node)
    return value, checks


def _keep_robot_order(scenario: sc.Scenario, before: list[str], robots_node) -> None:
    """Puts `scenario.robots` in the scenario's order: the layers below's robots as they
    were, then the ones this layer adds as it lists them. The typed load puts the defaults'
    entries first, and `_with_new_robots` makes a robot with a `robot:` a default, so the
    Corobot listed first would otherwise come after a Burger listed second (the first robot
    is the one the teleop and the dashboard open on)."""
    listed = [key.value for key, _ in getattr(robots_node, "value", ())]
    order = before + [name for name in listed if name not in before]
    order += [name for name in scenario.robots if name not in order]
    scenario.robots = {name: scenario.robots[name] for name in order
                       if name in scenario.robots}


def _field_node(node, name: str):
    """The value node of field `name` in a mapping node (None if it has none)."""
    return next((v for k, v in node.value if k.value == name), None) if isinstance(
        node, yaml.MappingNode) else None


def _with_new_robots(checks: LayerChecks, defaults: sc.Scenario, base: Path) -> sc.Scenario:
    """`defaults`, or a copy of it holding each robot this layer adds with a `robot:` of its
    own as that robot starts (`robots.robot_defaults`: its robot file's drive, tyres and
    sensors), so that the layer's fields apply over the robot's own defaults; a robot file
    that is wrong stops the load with its own one line."""
    new = []
    for key, fields in getattr(checks.robots_node, "value", ()):
        node = _field_node(fields, "robot")
        if not isinstance(node, yaml.ScalarNode):
            continue
        value = node.value if node.value in ROBOTS else sc.resolve_path(node.value, base)
        if key.value in defaults.robots:
            if value != defaults.robots[key.value].robot:
                checks.fail(f"robots.{key.value}.robot", "a robot's kind is set where it is "
                            "added (a later layer cannot change it)")
            continue
        if value not in ROBOTS and not Path(value).is_file():
            checks.fail(f"robots.{key.value}.robot", unknown_robot_kind(node.value, ROBOTS))
        new.append((key.value, value))
    if not new:
        return defaults
    defaults = copy.deepcopy(defaults)
    for name, value in new:
        defaults.robots[name] = robot_defaults(value)
    return defaults


def _with_new_sensors(robots_node, defaults: sc.Scenario) -> sc.Scenario:
    """`defaults`, or a copy of it holding each sensor this layer names that it lacks as its
    kind's `new_sensor` (a new camera is the Corobot's camera before the layer's fields apply;
    Drake's typed load would start it from its type's defaults)."""
    new = [(robot.value, kind, key.value)
           for robot, fields in getattr(robots_node, "value", ())
           for kind in KINDS
           for key, _ in getattr(_field_node(fields, kind.field), "value", ())
           if key.value not in getattr(defaults.robots.get(robot.value, sc.Robot()),
                                       kind.field)]
    if not new:
        return defaults
    defaults = copy.deepcopy(defaults)
    for robot, kind, sensor in new:
        entry = defaults.robots.setdefault(robot, sc.Robot())
        config = kind.new_sensor(sensor)
        base = robot_spec(entry.robot).base
        if config.X_PB.base_frame == "chassis" and base != "chassis":
            config.X_PB.base_frame = base  # the Corobot's mount, on this robot's base link
        getattr(entry, kind.field)[sensor] = config
    return defaults
