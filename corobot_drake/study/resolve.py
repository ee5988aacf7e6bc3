"""A study checked against its scenario as it loads, before any worker starts: the scenario
file, each of `overrides`, and every grid and random path, each failing at its line of the
study file.

A path is resolved once, on the scenario a run starts from (the file, the overrides, the
study's programs), to the field it names: the field must exist and hold one value (a number,
an integer, true or false, or text), not a structure. Each grid value (each `!Choice` value;
a `!Uniform`'s ends, a `!Normal`'s mean) must have the field's type and lie within its bound;
then the path's first value is put into a run's scenario as a worker would put it
(`runner.run_scenario`), so what only the whole scenario can say (a start pose inside a box)
fails here too. A value that fails only with other paths' values is that run's error row.
"""

from __future__ import annotations

import dataclasses as dc
import typing
from pathlib import Path

from corobot_drake.config.bounds import DRAKE_BOUNDS
from corobot_drake.config.scenario import ScenarioError, load_scenario, one_line
from corobot_drake.config.validate import LayerChecks
from corobot_drake.limits import Range, bound_of
from corobot_drake.names import did_you_mean
from corobot_drake.study.programs import PROGRAMS
from corobot_drake.study.spec import (
    Choice,
    Normal,
    Run,
    Study,
    Uniform,
    draw,
    path_kind,
    scenario_path,
    seeds,
)

TOP_LEVEL = {
    "random_seed": "each run's random_seed is its seed: list the seeds in `seeds` instead",
    "simulation_duration": "every run lasts the study's `duration`: set that (or split the "
                           "study to vary it)",
}
"""The scenario's top-level values a study sets itself, so a grid or random path may not."""
TYPE_NAMES = {float: "a number", int: "an integer", bool: "true or false", str: "text"}


def base_scenario(study: Study, study_file: str | Path, checks: LayerChecks):
    """The scenario file merged with each of `overrides`: what every run starts from (as
    `runner.study_scenario` reads it); a problem fails at the line of `scenario` or of the
    override."""
    try:
        scenario = load_scenario(scenario_path(study, study_file))
    except ScenarioError as e:
        checks.fail("scenario", str(e).replace(": (top level):", ":"))
    for i, text in enumerate(study.overrides):
        try:
            scenario = load_scenario(overrides=[text], defaults=scenario)
        except ScenarioError as e:
            checks.fail(f"overrides[{i}]", f"{e.field}: {e.message}")
    return scenario


def check_against_scenario(study: Study, study_file: str | Path, checks: LayerChecks) -> None:
    """Every grid and random path of `study` resolved against its scenario (module
    docstring); ScenarioError at the path's line for the first problem."""
    from corobot_drake.study.runner import run_scenario

    base = base_scenario(study, study_file, checks)
    _check_program_robots(study, base, checks)
    file = scenario_path(study, study_file)
    first = Run(0, seeds(study)[0], 0, ())
    start = run_scenario(study, file, first, base)  # the programs' scripts in place
    for section, paths in (("grid", study.grid), ("random", study.random)):
        for path, values in paths.items():
            where = f"{section}.{path}"
            root = study if path_kind(path) == "program" else start
            if path in TOP_LEVEL:
                checks.fail(where, f"a study sets {path} itself: {TOP_LEVEL[path]}")
            try:
                tp, bound = field_at(root, path)
            except ValueError as e:
                checks.fail(where, str(e))
            for suffix, value in _values(section, values, tp, where, checks):
                problem = value_problem(value, tp, bound)
                if problem:
                    checks.fail(where + suffix, problem)
            value = values[0] if section == "grid" else draw(values, first.seed, path)
            try:
                run_scenario(study, file, dc.replace(first, params=((path, value),)), base)
            except (ScenarioError, ValueError, TypeError) as e:
                text = f"{e.field}: {e.message}" if isinstance(e, ScenarioError) else one_line(e)
                checks.fail(where, f"with {value!r}: {text}")


def parameter_units(study: Study, study_file: str | Path) -> dict[str, str]:
    """Each grid and random path's unit (its field's bound's; "" for none, or a path that
    does not resolve), for the plots' axes. For a study `load_study` accepted."""
    from corobot_drake.study.runner import run_scenario

    start = run_scenario(study, scenario_path(study, study_file), Run(0, seeds(study)[0], 0, ()))
    units = {}
    for path in [*study.grid, *study.random]:
        try:
            _, bound = field_at(study if path_kind(path) == "program" else start, path)
        except ValueError:
            bound = None
        units[path] = getattr(bound, "unit", "") or ""
    return units


def _check_program_robots(study: Study, base, checks: LayerChecks) -> None:
    """Each program's `robot` (its grid and `!Choice` values too) names a robot of the
    scenario a run starts from; else fails at that value's line."""
    for name in PROGRAMS:
        program = getattr(study, name)
        if program is None:
            continue
        path = f"{name}.robot"
        named = [(path, program.robot)]
        named += [(f"grid.{path}[{i}]", v) for i, v in enumerate(study.grid.get(path, []))]
        if isinstance(study.random.get(path), Choice):
            named += [(f"random.{path}.values[{i}]", v)
                      for i, v in enumerate(study.random[path].values)]
        for where, robot in named:
            if problem := value_problem(robot, str, None):
                checks.fail(where, problem)
            if robot not in base.robots:  # at the program's line when `robot` is its default
                checks.fail(where, f"the scenario has no robot {robot!r}"
                            f"{did_you_mean(robot, base.robots)}; it has: "
                            + (", ".join(base.robots) or "none"))


def _values(section: str, values, tp, where: str, checks: LayerChecks):
    """(where in the study file, value) of what a grid list or a distribution puts into a
    field of type `tp`."""
    if section == "grid":
        return [(f"[{i}]", v) for i, v in enumerate(values)]
    if isinstance(values, Choice):
        return [(f".values[{i}]", v) for i, v in enumerate(values.values)]
    if tp is not float:
        checks.fail(where, f"a !{type(values).__name__} draws a number, and the field takes "
                    f"{TYPE_NAMES[tp]}: use a !Choice of values")
    if isinstance(values, Uniform):
        return [(".min", values.min), (".max", values.max)]
    assert isinstance(values, Normal)
    return [(".mean", values.mean)]


def field_at(root, path: str) -> tuple[type, object]:
    """(type, bound) of the single value at the dotted `path` of a loaded scenario or study
    (dataclass fields, Drake struct fields, mapping keys, list indices); ValueError naming
    the first key that does not resolve, or a field that is not a single value."""
    node, tp, bound = root, type(root), None
    keys = path.split(".")
    for depth, key in enumerate(keys):
        node, tp, bound = _child(node, key, ".".join(keys[:depth]) or "the scenario", bound)
    tp = _single(tp, node)
    if tp is None:
        raise ValueError(f"{path} is {_a(node)}, not a single value: vary one of its fields")
    return tp, bound


def _child(node, key: str, parent: str, bound):
    """(value, declared type, bound) of `node`'s `key` (`node` is at `parent`; `bound`, its
    own, is its items' when it is a list)."""
    if node is None:
        raise ValueError(f"{parent} is not set (an optional field): nothing to vary in it")
    if isinstance(node, list):
        if not (key.isdigit() and int(key) < len(node)):
            raise ValueError(f"{parent}: the list has {len(node)} items (index from 0), no "
                             f"{key!r}")
        item = node[int(key)]
        return item, type(item), bound[int(key)] if isinstance(bound, tuple) else bound
    if isinstance(node, dict):
        if key not in node:
            raise ValueError(f"{parent} has no {key!r}{did_you_mean(key, node)}; it has: "
                             + (", ".join(map(str, node)) or "nothing"))
        return node[key], type(node[key]), None
    if dc.is_dataclass(node):
        fields = {f.name: f for f in dc.fields(node)}
        if key not in fields:
            raise ValueError(f"{parent} ({type(node).__name__}) has no field {key!r}"
                             f"{did_you_mean(key, fields)}; fields: {', '.join(fields)}")
        hints = typing.get_type_hints(type(node))
        return getattr(node, key), hints[key], bound_of(fields[key])
    names = {f.name: f.type for f in getattr(type(node), "__fields__", ())}
    if not names:
        raise ValueError(f"{parent} is {_a(node)}: a study reaches only fields, mapping keys "
                         "and list items")
    if key not in names:
        raise ValueError(f"{parent} ({type(node).__name__}) has no field {key!r}"
                         f"{did_you_mean(key, names)}; fields: " + ", ".join(names))
    return getattr(node, key), names[key], DRAKE_BOUNDS.get(type(node), {}).get(key)


def _single(tp, value):
    """The scalar type a field of declared type `tp` holding `value` takes, or None."""
    options = [a for a in typing.get_args(tp) if a is not type(None)] or [tp]
    scalars = [o for o in options if o in TYPE_NAMES]
    if len(scalars) == 1 and len(options) == 1:
        return scalars[0]
    return type(value) if type(value) in TYPE_NAMES and len(options) == 1 else None


def _a(value) -> str:
    """`a list`, `a mapping`, `a Transform`, ..."""
    name = type(value).__name__
    return {"list": "a list", "dict": "a mapping", "ndarray": "an array"}.get(name, f"a {name}")


def value_problem(value, tp: type, bound) -> str | None:
    """What is wrong with `value` for a field of scalar type `tp` and `bound`, or None (an
    integer fits a float field)."""
    fits = (isinstance(value, bool) if tp is bool else
            not isinstance(value, bool) and isinstance(value, int | float if tp is float
                                                       else tp))
    if not fits:
        return f"expected {TYPE_NAMES[tp]}, got {'null' if value is None else repr(value)}"
    if isinstance(bound, Range) and tp in (int, float):
        return bound.problem(value)
    if bound is not None and tp is str and hasattr(bound, "problem"):
        return bound.problem(value)
    return None
