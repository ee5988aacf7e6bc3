"""Loads a scenario: `load_scenario` (and writes one back: `save_scenario`).

Each layer (a file, YAML text, an `--override`) runs through the one validation pass
(`config/validate.py`), so a bad file stops with one line naming the file, the line and the
field (`ScenarioError`); what `load_scenario` returns is trusted by everything that builds
from it. The schema is `config/schema.py`, re-exported here (`scenario.Robot`,
`scenario.ScenarioError`, ...): the loader imports the validation, which imports the schema,
and nothing imports back.
"""

from pathlib import Path

from pydrake.common.yaml import yaml_dump_typed

from corobot_drake.config.schema import *  # noqa: F403 (the schema, as `scenario.X`)
from corobot_drake.config.schema import Scenario, ScenarioError, read_text, resolve_paths
from corobot_drake.config.validate import load_layer, mark_checked
from corobot_drake.names import did_you_mean


def load_scenario(filename: str | Path | None = None, *, data: str | None = None,
                  overrides: list[str] = (), defaults: Scenario | None = None) -> Scenario:
    """Reads a scenario file and/or YAML text, then each override merged on top.

    Raises ScenarioError (one line: file, line, field, problem) for anything wrong.
    """
    scenario = defaults or Scenario()
    # (source, text, the directory its relative file references are relative to)
    layers = []
    if filename is not None:
        layers.append((str(filename), read_text(filename), Path(filename).parent))
    if data is not None:
        layers.append(("<scenario text>", data, Path.cwd()))
    layers += [("--override", text, Path.cwd()) for text in overrides]
    for i, (source, text, base) in enumerate(layers):
        before = list(scenario.robots)
        try:
            scenario, checks = load_layer(source, text, Scenario, scenario, base)
            resolve_paths(scenario, base)
            checks.validate(scenario, final=i == len(layers) - 1)  # what the types cannot say
        except ScenarioError as e:
            raise _new_robot_hint(e, before) from None
    if layers:  # the merged scenario passed every check: `Simulation` need not repeat them
        mark_checked(scenario)
    return scenario


def _new_robot_hint(error: ScenarioError, before: list[str]) -> ScenarioError:
    """`error`, saying "did you mean" when the robot its field names is new in this layer and
    close to one the layers below have: a misspelt name in an override adds a robot, which
    then fails as a robot (starts inside the one it meant, lacks a field)."""
    parts = error.field.split(".")
    if len(parts) < 2 or parts[0] != "robots" or parts[1] in before:
        return error
    hint = did_you_mean(parts[1], before)
    if not hint:
        return error
    return ScenarioError(error.source, error.field, f"{error.message}; {parts[1]!r} adds a "
                         f"robot{hint}", error.line)


def save_scenario(scenario: Scenario, filename: str | Path) -> None:
    """Writes a scenario YAML that `load_scenario` reads back to an equal Scenario."""
    Path(filename).write_text(yaml_dump_typed(scenario, schema=Scenario))
