"""The scenario and robot-file reference (docs/_ext/corobot_docs/scenario.py, made without a
Sphinx build): every field described, with a unit; the rules that read another field shown as
the loader enforces them; Drake's fields in the project's words, those nothing reads marked.
"""

import re

import pytest

from conftest import REPO


@pytest.fixture(scope="module")
def scenario_page():
    import sys

    sys.path.insert(0, str(REPO / "docs" / "_ext"))
    from corobot_docs import scenario

    return scenario


@pytest.fixture(scope="module")
def tables(scenario_page) -> dict[str, dict[str, dict[str, str]]]:
    """{section title: {field: {column: cell}}} of the generated page."""
    out, title, header = {}, None, None
    for line in scenario_page.page().splitlines():
        if line.startswith("## "):
            title, header = line[3:].strip(), None
        elif line.startswith("| "):
            cells = [c.strip() for c in re.split(r"(?<!\\)\|", line)[1:-1]]
            if header is None:
                header = cells
            elif cells[0].startswith("`"):
                row = dict(zip(header, cells, strict=True))
                out.setdefault(title, {})[cells[0].strip("`")] = row
    return out


def test_every_field_has_a_description_and_a_unit(tables):
    rows = [(t, f, row) for t, fields in tables.items() for f, row in fields.items()]
    assert len(rows) > 200
    assert [(t, f) for t, f, row in rows if not row["what"]] == []
    assert [(t, f) for t, f, row in rows if not row["unit"]] == []
    # A dimensionless number is marked `1`, a name or a switch `—`.
    assert tables["Ground"]["friction"]["unit"] == "1"
    assert tables["RobotDrive"]["encoder_ticks_per_revolution"]["unit"] == "1"
    assert tables["Robot"]["visual"]["unit"] == "—"
    assert tables["Tyres"]["hydroelastic_modulus"]["unit"] == "Pa"


def test_a_field_without_a_description_stops_the_page(scenario_page, monkeypatch):
    from pydrake.systems.sensors import CameraConfig

    from corobot_drake.config.drake_docs import DRAKE_DOCS

    docs = dict(DRAKE_DOCS[CameraConfig])
    del docs["lcm_bus"]
    monkeypatch.setitem(DRAKE_DOCS, CameraConfig, docs)
    with pytest.raises(scenario_page.UndocumentedFieldsError, match=r"CameraConfig\.lcm_bus"):
        scenario_page.page()


BREAKS = {
    ("SimulatorConfig", "max_step_size"): "{simulator_config: {max_step_size: 0.05}}",
    ("CameraConfig", "depth"): "{robots: {r: {cameras: {front: {depth: true}}}}}",
    ("CameraConfig", "label"): "{robots: {r: {cameras: {front: {label: true}}}}}",
    ("CameraConfig", "output_delay"): "{robots: {r: {cameras: {front: {fps: 30, "
                                      "output_delay: 0.5}}}}}",
}
"""An override that breaks each rule (`config.bounds.DRAKE_RULES`), each value inside the
field's own bound."""


def test_each_rule_is_shown_and_the_loader_enforces_it(tables):
    from corobot_drake.config.bounds import DRAKE_RULES
    from corobot_drake.config.scenario import ScenarioError, load_scenario

    rules = {(cls.__qualname__, name): rule for cls, fields in DRAKE_RULES.items()
             for name, rule in fields.items()}
    assert set(rules) == set(BREAKS)
    for (title, name), rule in rules.items():
        assert rule.text() in tables[title][name]["allowed"], (title, name)
        with pytest.raises(ScenarioError) as refused:
            load_scenario(overrides=[BREAKS[title, name]])
        assert refused.value.field.rsplit(".", 1)[-1] == name, refused.value
    shown = {(t, f): tables[t][f]["allowed"] for t, f in BREAKS}
    assert "with integration_scheme `cenic`: in [0.0001, 0.02] s" in \
        shown["SimulatorConfig", "max_step_size"]
    assert "less than one frame (1/fps)" in shown["CameraConfig", "output_delay"]
    assert shown["CameraConfig", "depth"].startswith("`false` only")
    # The rule holds only where it says: a discrete plant's integrator may step 50 ms.
    load_scenario(overrides=["{plant_config: {time_step: 0.01}, simulator_config: "
                             "{integration_scheme: runge_kutta3, max_step_size: 0.05}}"])


def test_drakes_fields_are_in_the_projects_words(tables):
    """No Drake docstring leaks (its C++ `∷`, Doxygen's `%`, LCM on a field that is read),
    every field of Drake's structs has its words and no stale ones, and the fields marked
    `Not read` are accepted by the loader with any value (and nothing else checks them)."""
    from corobot_drake.config.drake_docs import DRAKE_DOCS, NOT_READ
    from corobot_drake.config.scenario import load_scenario

    for cls, docs in DRAKE_DOCS.items():
        assert set(docs) == {"", *(f.name for f in cls.__fields__)}, cls
    cells = [(t, f, row["what"]) for t, fields in tables.items() for f, row in fields.items()]
    assert [c for c in cells if re.search(r"∷|%\w|\(self\)|one of two ways:$", c[2])] == []
    assert [c for c in cells if "LCM" in c[2] and not c[2].startswith(NOT_READ)] == []
    camera = tables["CameraConfig"]
    not_read = sorted(f for f, row in camera.items() if row["what"].startswith(NOT_READ))
    assert not_read == ["background", "do_compress", "lcm_bus", "name"]
    assert all(camera[f]["unit"] == "—" for f in not_read)
    s = load_scenario(overrides=["{robots: {r: {cameras: {front: {lcm_bus: 'udpm://x', "
                                 "do_compress: false, name: other, background: {rgba: "
                                 "[1, 0, 0, 1]}}}}}}"])
    assert s.robots["r"].cameras["front"].lcm_bus == "udpm://x"


def test_the_python_reference_describes_the_robot_files_fields(scenario_page):
    """autodoc's entries of the robot file's fields (docs/reference/python.md): each has a
    docstring, or the reference's description (`docstrings.describe_fields`: the sensor maps
    a decorator adds)."""
    import dataclasses as dc

    from corobot_docs.docstrings import field_doc

    from corobot_drake.robots import file

    empty = [f"{cls.__name__}.{f.name}"
             for cls in (file.RobotFile, file.Wheels, file.RobotDrive, file.Tyres,
                         file.Casters, file.OdometryTest) for f in dc.fields(cls)
             if not scenario_page.docs_below(cls).get(f.name)
             and not field_doc(f"{cls.__module__}.{cls.__qualname__}.{f.name}")]
    assert empty == []
    assert "none by default" in field_doc("corobot_drake.robots.file.RobotFile.cameras")
