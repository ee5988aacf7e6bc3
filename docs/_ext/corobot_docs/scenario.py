"""The scenario's schema as Markdown: one table per struct, from `config.scenario.Scenario` down,
then the robot file's (`robots.file.RobotFile`).

Read from the code at build time: the dataclasses' fields (types, defaults), their bounds
(`limits.bounded` metadata; `config.bounds.DRAKE_BOUNDS` for Drake's config structs) and the
rules that read another field (`config.bounds.DRAKE_RULES`), their attribute docstrings (the
string below each field, read with `ast`) and, for Drake's structs, the project's words
(`config.drake_docs.DRAKE_DOCS`; Drake's own docstrings speak of LCM and C++). Each sensor
kind's config comes in through `Robot`'s per-kind maps (`sensors.registry.KINDS`).

Every field has a description and a unit: a unit from its bound or its description's opening
(`kg; ...`, `1: ...`), else `1` for a number (its bound names no unit: dimensionless) and `—`
for anything else; a field without a description stops the build (`UndocumentedFieldsError`).
"""

from __future__ import annotations

import dataclasses as dc
import inspect
import math
import re
import textwrap
import types
import typing

from corobot_docs.markdown import cell, docs_below, table

UNITS = ("1", "m", "s", "kg", "Pa", "rad", "deg", "Hz", "N", "N m", "rad/s", "m/s", "rad/s^2",
         "m/s^2", "1/s", "s/m", "pixels", "ticks", "1, 1/m, 1/m^2")
"""Units a field's docstring may open with (`kg; ignored when fixed`, `1: ...` for a
dimensionless number) when its range has none."""

NO_UNIT = "—"
"""The unit cell of a field that is not a number (a name, a switch, a struct, a pose)."""


class UndocumentedFieldsError(ValueError):
    """Fields the reference would list without a description."""


KEYS = {"robots": "<robot>", "bodies": "<body>"}
"""The placeholder of a map's key in a field's path (a sensor's: `<name>`)."""


@dc.dataclass
class Section:
    cls: type
    paths: list[str]
    default: object
    """An instance whose values are this struct's defaults where it is used first."""


def page() -> str:
    from corobot_drake.config import scenario as sc
    from corobot_drake.robots.file import RobotFile
    from corobot_drake.sensors.registry import KINDS

    sections = _walk(sc.Scenario)
    out = [_intro(KINDS)]
    for s in sections.values():
        out.append(_section(s, sections))
    # The robot file's own structs; its sensors' configs are the scenario's, linked to.
    robot_file = {cls: s for cls, s in _walk(RobotFile).items() if cls not in sections}
    out.append(ROBOT_FILE_INTRO)
    for s in robot_file.values():
        out.append(_section(s, {**sections, **robot_file}, top="The robot file's top level."))
    missing = [f"{_title(s.cls)}.{name}" for s in [*sections.values(), *robot_file.values()]
               for name, _ in _struct_fields(s.cls) if not field_doc(s.cls, name)]
    if missing:
        raise UndocumentedFieldsError(
            "fields without a description (a docstring below the field, or "
            "config.drake_docs.DRAKE_DOCS for Drake's): " + ", ".join(missing))
    return "\n\n".join(out) + "\n"


ROBOT_FILE_INTRO = textwrap.dedent("""\
    ## The robot file

    A robot file (`robot:` in a scenario: a shipped robot's name or a file's path;
    `models/corobot/robot.yaml` is the Corobot's) is a YAML file read into
    `robots.file.RobotFile`: the robot's model, the link its pose places, its wheels, drive,
    tyres, casters and its own sensors (each kind's map, with the scenario's fields above).
    What it leaves out is measured from the model or scaled from the Corobot's; a value
    outside its range stops the loader with one line naming the robot file, the line and the
    field. The guide: [Add your own robot](../extending.md#add-your-own-robot).""")


def _intro(kinds) -> str:
    sensors = ", ".join(f"`{k.field}` ({', '.join(k.defaults()) or 'none by default'})"
                        for k in kinds)
    return textwrap.dedent(f"""\
        A scenario is a YAML file read into `config.scenario.Scenario` (Drake's
        `yaml_load_typed`); every field below may be left out, taking its default. A value
        outside its range stops the loader with one line naming the file, the line and the
        field. The robot's sensors are maps by name, one per kind of sensor: {sensors}; a
        sensor the defaults lack starts as the defaults in its kind's table.

        Generated from the code at each build (`docs/_ext/corobot_docs/scenario.py`).""")


# --- the walk ---------------------------------------------------------------------------


def _struct_fields(cls) -> list[tuple[str, object]] | None:
    """(name, type) of a dataclass's or Drake config struct's fields; None for anything else."""
    if dc.is_dataclass(cls):
        hints = typing.get_type_hints(cls)
        return [(f.name, hints[f.name]) for f in dc.fields(cls)]
    if isinstance(cls, type) and hasattr(cls, "__fields__"):
        return [(f.name, f.type) for f in cls.__fields__]
    return None


def _expanded(cls) -> bool:
    """Whether `cls` gets a table: the project's dataclasses and the Drake structs the
    scenario bounds (others, such as Transform, are Drake's, referred to by name)."""
    from corobot_drake.config.bounds import DRAKE_BOUNDS

    return dc.is_dataclass(cls) or cls in DRAKE_BOUNDS


def _walk(root) -> dict[type, Section]:
    sections: dict[type, Section] = {}

    def visit(cls, path, default):
        if cls in sections:
            sections[cls].paths.append(path)
            return
        sections[cls] = Section(cls, [path], default)
        for name, tp in _struct_fields(cls):
            value = getattr(default, name, None)
            for inner, inner_path, inner_default in _inner_structs(tp, f"{path}.{name}", value):
                visit(inner, inner_path, inner_default)

    visit(root, "", root())
    return sections


def _inner_structs(tp, path, value):
    """(struct type, its path, its default instance) of the expandable structs in `tp`."""
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin is dict:
        key = KEYS.get(path.rsplit(".", 1)[-1], "<name>")
        yield from _inner_structs(args[1], f"{path}.{key}", _dict_default(path, args[1]))
    elif origin is list:
        yield from _inner_structs(args[0], f"{path}[]", None)
    elif origin in (typing.Union, types.UnionType):
        for a in args:
            yield from _inner_structs(a, f"{path} !{a.__name__}", value
                                      if isinstance(value, a) else None)
    elif _struct_fields(tp) is not None and _expanded(tp):
        yield tp, path, value if isinstance(value, tp) else tp()


def _dict_default(path: str, tp):
    """The config a new entry of a map starts as (a sensor kind's `new_sensor`)."""
    from corobot_drake.sensors.registry import KINDS

    for k in KINDS:
        if path.endswith(f".{k.field}") and k.config_type is tp:
            return k.new_sensor("name")
    return tp() if _struct_fields(tp) is not None else None


# --- one table --------------------------------------------------------------------------


def _section(s: Section, sections, top: str = "The file's top level.") -> str:
    where = ", ".join(f"`{p.lstrip('.')}`" for p in s.paths[:4])
    where = f"At {where}." if where != "``" else top
    if s.cls.__module__.startswith("pydrake"):
        where += (f" Drake's [`{s.cls.__module__}.{s.cls.__qualname__}`]"
                  f"({_drake_url(s.cls)}).")
    doc = _class_doc(s.cls)
    head = [f"## {_title(s.cls)}", "", where + (f" {doc}" if doc else "")]
    rows = [_row(s, name, tp, sections) for name, tp in _struct_fields(s.cls)]
    return "\n".join(head) + "\n\n" + table(
        ("field", "type", "default", "unit", "allowed", "what"), rows)


def _title(cls) -> str:
    return cls.__qualname__ if cls.__module__.startswith("pydrake") else cls.__name__


def _class_doc(cls) -> str:
    if cls.__module__.startswith("pydrake"):
        return cell(_drake_docs(cls).get("", ""))
    doc = inspect.getdoc(cls) or ""
    if doc.startswith(cls.__name__ + "("):  # a dataclass's generated signature
        return ""
    return cell(doc.split("\n\n")[0])


def _row(s: Section, name: str, tp, sections) -> list[str]:
    bound, size = _bound(s.cls, name)
    doc = field_doc(s.cls, name)
    return [f"`{name}`", _type_text(tp, sections), _default_text(getattr(s.default, name, None)),
            _unit(bound, doc, tp), _allowed(bound, size, tp, _rule(s.cls, name)),
            cell(_without_one(doc))]


def _without_one(doc: str) -> str:
    """The description without its opening `1: ` (the mark of a number without a unit)."""
    return doc[3:4].upper() + doc[4:] if re.match(r"1[:;] ", doc) else doc


def _rule(cls, name: str):
    from corobot_drake.config.bounds import DRAKE_RULES

    return DRAKE_RULES.get(cls, {}).get(name)


def _bound(cls, name):
    from corobot_drake.config.bounds import DRAKE_BOUNDS

    if dc.is_dataclass(cls):
        f = {f.name: f for f in dc.fields(cls)}[name]
        return f.metadata.get("bound"), f.metadata.get("size")
    return DRAKE_BOUNDS.get(cls, {}).get(name), None


def _unit(bound, doc: str, tp) -> str:
    """The bound's unit, else the description's opening one (`UNITS`), else `1` for a number
    and `NO_UNIT` for anything else (a field that is not read has none)."""
    from corobot_drake.config.drake_docs import NOT_READ

    bounds = bound if isinstance(bound, tuple) else (bound,)
    units = [getattr(b, "unit", "") for b in bounds if getattr(b, "unit", "")]
    if units:
        return ", ".join(dict.fromkeys(units))
    m = re.match(r"(.+?)[:;] ", doc)
    if m and m.group(1) in UNITS:
        return m.group(1)
    return "1" if _numeric(tp) and not doc.startswith(NOT_READ) else NO_UNIT


def _numeric(tp) -> bool:
    """Whether `tp` holds numbers: an int or a float (or None), a list or an array of them."""
    import numpy as np

    tp = _scalar(tp)
    if typing.get_origin(tp) is list:
        tp = typing.get_args(tp)[0]
    return tp in (int, float, np.ndarray)


def _allowed(bound, size, tp, rule=None) -> str:
    from corobot_drake.limits import DRAKE_INT, FINITE, OneOf, Range

    def one(b):
        if isinstance(b, Range):
            return b.text()
        if isinstance(b, OneOf):
            return "one of " + ", ".join(f"`{n}`" for n in b.names) + (
                f" ({b.why})" if b.why else "")
        return ""

    if isinstance(bound, tuple):
        text = "; ".join(f"{_indices(first, last)} {one(b)}"
                         for first, last, b in _runs(bound))
    elif bound is not None:
        text = one(bound) + (" each" if typing.get_origin(tp) is list else "")
    elif _scalar(tp) is float:
        text = FINITE.text()
    elif _scalar(tp) is int:
        text = DRAKE_INT.text()
    else:
        text = ""
    if size is not None:
        text = f"{size} numbers" + (f", {text}" if text else "")
    if rule is not None:  # a rule that reads another field (`config.bounds.DRAKE_RULES`)
        text = f"{text}; {rule.text()}" if text else rule.text()
    return cell(text)


def _runs(bounds: tuple):
    """(first index, last index, bound) of each run of equal bounds of a list's elements."""
    runs = []
    for i, b in enumerate(bounds):
        if runs and runs[-1][2] == b:
            runs[-1][1] = i
        else:
            runs.append([i, i, b])
    return runs


def _indices(first: int, last: int) -> str:
    return f"[{first}]" if first == last else f"[{first}-{last}]"


def _scalar(tp):
    args = [a for a in typing.get_args(tp) if a is not type(None)]
    return args[0] if typing.get_origin(tp) in (typing.Union, types.UnionType) \
        and len(args) == 1 else tp


def _type_text(tp, sections) -> str:
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin is dict:
        return f"map of {_type_text(args[1], sections)}"
    if origin is list:
        return f"list of {_type_text(args[0], sections)}"
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_type_text(a, sections) for a in args)
    if tp is type(None):
        return "null"
    if tp in sections:
        return f"[{tp.__name__}](#{_slug(_title(tp))})"
    if getattr(tp, "__module__", "").startswith("pydrake"):
        return f"[`{tp.__qualname__}`]({_drake_url(tp)})"
    return f"`{getattr(tp, '__name__', str(tp))}`"


def _drake_url(tp) -> str:
    """Drake's documentation of one of its Python classes."""
    return (f"https://drake.mit.edu/pydrake/{tp.__module__}.html"
            f"#{tp.__module__}.{tp.__qualname__}")


def _slug(title: str) -> str:
    """The heading's anchor as MyST makes it (GitHub's slugs)."""
    slug = re.sub(r"[^\w\- ]", "", title.strip().lower().replace("`", ""))
    return slug.replace(" ", "-")


def _default_text(value) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return f"`{str(value).lower()}`"
    if isinstance(value, float):
        return "`.inf`" if value == math.inf else f"`{value:g}`"
    if isinstance(value, int | str):
        return f"`{value}`" if value != "" else '`""`'
    if isinstance(value, dict):
        return cell(", ".join(f"`{k}`" for k in value)) or "none"
    if isinstance(value, list):
        return f"`{[round(v, 6) if isinstance(v, float) else v for v in value]}`" \
            if all(isinstance(v, int | float) for v in value) else ("none" if not value else
                                                                    "(see the type)")
    return "(see the type)"


# --- docstrings -------------------------------------------------------------------------


def field_doc(cls, name: str) -> str:
    """A field's description: its docstring (a dataclass's), a command argument's, a sensor
    map's, or the project's words for a field of Drake's (`DRAKE_DOCS`); "" when it has none.
    The Python reference's autodoc reads it too (`docstrings.process`)."""
    if not dc.is_dataclass(cls):
        return _drake_docs(cls).get(name, "")
    return docs_below(cls).get(name, "") or _command_arg_doc(cls, name) \
        or _sensor_map_doc(cls, name)


def _drake_docs(cls) -> dict[str, str]:
    from corobot_drake.config.drake_docs import DRAKE_DOCS

    return DRAKE_DOCS.get(cls, {})


def _sensor_map_doc(cls, name: str) -> str:
    """What a robot's (or a robot file's) map of a kind of sensor is
    (`sensors.registry.KINDS`)."""
    from corobot_drake.sensors.registry import KINDS

    kind = next((k for k in KINDS if k.field == name), None)
    if kind is None or cls.__name__ not in ("Robot", "RobotFile"):
        return ""
    doc = f"The robot's sensors of this kind, by name (`{name}: {{<name>: {{...}}}}`)"
    if cls.__name__ == "RobotFile":
        return doc + "; none by default, and a field a sensor leaves out takes its config " \
            "type's own default."
    if kind.defaults():
        off = ", ".join(f"{k}: {str(v).lower()}" for k, v in (kind.off or {}).items())
        doc += f"; a default one is removed by `{{{off}}}`" if off else ""
    return doc + "."


def _command_arg_doc(cls, name: str) -> str:
    from corobot_drake.commands import COMMANDS

    spec = COMMANDS.get(cls.__name__)
    if spec is None or spec.dataclass is not cls:
        return ""
    return next((a.doc for a in spec.args if a.name == name), "")
