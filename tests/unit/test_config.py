"""The scenario's one pose convention (Drake's schema Transform) and its one validation pass."""

import copy
import dataclasses as dc
import math

import numpy as np
import pytest
from pydrake.common.yaml import yaml_dump_typed
from pydrake.math import RigidTransform, RollPitchYaw

from conftest import DEFAULT_SCENARIO, make_sim
from corobot_drake.config import scenario as sc
from corobot_drake.config.poses import ground_pose, mount_frame, transform_from
from corobot_drake.config.scenario import ScenarioError, load_scenario
from corobot_drake.config.sensors import default_ir_sensors


def test_the_default_ir_sensors_are_at_the_spec_mounts():
    """The Corobot's IR sensors, 4.25 in ahead of and behind the axles' midpoint at the
    chassis box's mid-height (2.75 in), the front looking forward, the rear back."""
    inch = 0.0254
    for name, x, yaw in (("front", 4.25 * inch, 0.0), ("rear", -4.25 * inch, math.pi)):
        X_PB = default_ir_sensors()[name].X_PB
        assert X_PB.base_frame == "chassis"
        expected = RigidTransform(RollPitchYaw(0.0, 0.0, yaw), [x, 0.0, 2.75 * inch])
        np.testing.assert_allclose(X_PB.GetDeterministicValue().GetAsMatrix34(),
                                   expected.GetAsMatrix34(), rtol=0, atol=1e-15)


def test_ground_pose_stands_a_robot_on_the_ground():
    X = ground_pose(1.0, -2.0, 90.0).GetDeterministicValue()
    np.testing.assert_array_equal(X.translation(), [1.0, -2.0, 0.0])
    assert RollPitchYaw(X.rotation()).vector() == pytest.approx([0.0, 0.0, math.pi / 2])


def test_a_pose_written_back_reads_as_the_same_transform():
    X = RigidTransform(RollPitchYaw(0.01, -0.2, 2.9), [0.3, -1.2, 0.05])
    again = transform_from(X).GetDeterministicValue()
    assert again.IsNearlyEqualTo(X, 1e-14)


def test_sensors_ride_on_the_link_their_base_frame_names():
    sim = make_sim()
    plant, parts = sim.station.plant, sim.robot()._parts
    X_PB = default_ir_sensors()["rear"].X_PB
    body, X_BS = mount_frame(plant, parts.model_instance, X_PB)
    assert body.index() == parts.chassis.index()
    assert X_BS.IsExactlyEqualTo(X_PB.GetDeterministicValue())


def test_an_ir_sensor_can_ride_on_a_wheel():
    sim = make_sim("robots: {corobot: {ir_sensors: {hub: {X_PB: {base_frame: front_left_wheel, "
                   "translation: [0, 0.05, 0], rotation: !Rpy {deg: [0, 0, 90]}}}}}}")
    assert set(sim.robot().ir_distances()) == {"front", "rear", "hub"}


def test_a_saved_scenario_keeps_every_pose_in_the_one_convention(tmp_path):
    sim = make_sim("robots: {corobot: {commands: [!SetPower {left: 0.3, right: 0.6}]}}")
    sim.advance(0.5)
    path = tmp_path / "saved.yaml"
    sim.save_scenario(path)
    text = path.read_text()
    assert "yaw_deg" not in text.replace("!SetPose", "")  # no other pose form
    saved = load_scenario(path)
    X_saved = saved.robots["corobot"].pose.GetDeterministicValue()
    X_now = sim.station.plant.EvalBodyPoseInWorld(
        sim.station.plant.GetMyContextFromRoot(sim.context), sim.robot()._parts.chassis)
    assert X_saved.IsNearlyEqualTo(X_now, 1e-12)
    assert yaml_dump_typed(saved, schema=sc.Scenario) == text  # a fixed point


def _loads_or_names(override: str, field: str | None, words: str | None,
                    one_line: bool = False) -> None:
    """The override loads (`field` None), or is refused naming `field` (in one line if
    `one_line`)."""
    if field is None:
        load_scenario(DEFAULT_SCENARIO, overrides=[override])
        return
    with pytest.raises(ScenarioError) as e:
        load_scenario(DEFAULT_SCENARIO, overrides=[override])
    if one_line:
        assert str(e.value).count("\n") == 0
    assert f"--override:1: {field}:" in str(e.value) and words in str(e.value)


@pytest.mark.parametrize("override, field, words", [
    ("world: {bodies: {giant_box: {pose: {translation: [0, 0, -.inf]}}}}",
     "world.bodies.giant_box.pose.translation[2]", "must be in [-10000, 10000] m; got -inf"),
    ("world: {bodies: {giant_box: {pose: {rotation: !AngleAxis {angle_deg: 90, "
     "axis: [0, 0, 0]}}}}}", "world.bodies.giant_box.pose.rotation", "non-zero axis"),
    ("robots: {corobot: {pose: {translation: !UniformVector {min: [0, 0, 0], max: [1, 1, 0]}}}}",
     "robots.corobot.pose", "must be a fixed pose"),
    ("robots: {corobot: {ir_sensors: {rear: {X_PB: {base_frame: giant_box::giant_box}}}}}",
     None, None),  # a scoped link of the scenario: accepted
    ("robots: {corobot: {ir_sensors: {rear: {X_PB: {base_frame: other::chassis}}}}}",
     "robots.corobot.ir_sensors.rear.X_PB.base_frame", "not a link of the robot"),
])
def test_pose_errors_name_the_field(override, field, words):
    _loads_or_names(override, field, words)


def test_checks_of_meaning_name_the_line_of_the_field(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text("robots:\n  corobot:\n    ir_sensors:\n      rear:\n"
                    "        maximum_range: -1\n")
    with pytest.raises(ScenarioError) as e:
        load_scenario(path)
    assert str(e.value).startswith(
        f"{path}:5: robots.corobot.ir_sensors.rear.maximum_range: must be in (0, 100] m; got -1")



def test_a_field_the_layer_does_not_write_is_blamed_on_the_layer_line():
    # A study's grid sets fields no YAML line wrote: the error names the layer and the field,
    # and finding the line ends (it once walked up "robots" forever).
    from corobot_drake.config.validate import LayerChecks

    checks = LayerChecks("study grid", "{}")
    with pytest.raises(ScenarioError, match=r"^study grid:1: robots\.corobot\.drive: bad"):
        checks.fail("robots.corobot.drive", "bad")


def test_a_scenario_built_in_python_gets_the_loaders_checks():
    """`Simulation(scenario)` checks a scenario built or changed in Python as `load_scenario`
    checks a file: one ScenarioError line naming the field (no line: there is no file), before
    Drake sees it."""
    from corobot_drake.config.scenario import Scenario, ScenarioError
    from corobot_drake.simulation import Simulation

    scenario = load_scenario(DEFAULT_SCENARIO)
    scenario.robots["corobot"].drive.slew_rate = -1.0
    with pytest.raises(ScenarioError) as e:
        Simulation(scenario)
    assert str(e.value) == ("<Python scenario>: robots.corobot.drive.slew_rate: must be in "
                            "(0, 10000] rad/s^2; got -1")
    built = Scenario()
    built.plant_config.time_step = 1.0
    with pytest.raises(ScenarioError, match=r"^<Python scenario>: plant_config.time_step: "):
        Simulation(built)
    scenario = load_scenario(DEFAULT_SCENARIO)
    scenario.robots["corobot"].drive = None  # a wrong type: named, not an AttributeError
    with pytest.raises(ScenarioError, match=r"robots\.corobot\.drive: expected Drive, got None"):
        Simulation(scenario)


def _command(fields: str) -> str:
    return f"robots: {{corobot: {{commands: [{fields}]}}}}"


@pytest.mark.parametrize("override, field, words", [
    (_command("!DriveDistance {distance: 1, recent_progress: [0.1]}"),
     "commands[0].recent_progress", "needs `start`"),
    (_command("!RotateDegrees {degrees: 9, start: [0, 0, 0], recent_progress: [" + "0, " * 10
              + "0]}"), "commands[0].recent_progress", "at most 10 values"),
    (_command("!RotateDegrees {degrees: 9, start: [0, 0, 0], recent_progress: [-1, 2e6]}"),
     "commands[0].recent_progress[1]", "must be in [-1e+06, 1e+06] deg; got 2e+06"),
    (_command("!DriveDistance {distance: 1, start: [0, 0, 0], recent_progress: [.nan]}"),
     "commands[0].recent_progress[0]", "NaN is not allowed"),
    (_command("!DriveDistance {distance: 1, start: [0, 0, 0], recent_progress: [1e5]}"),
     "commands[0].recent_progress[0]", "must be in [-10000, 10000] m; got 100000"),
    ("robots: {corobot: {drive: {control_period: 0.05}, commands: [!DriveDistance {distance: "
     "1, start: [0, 0, 0], recent_progress: [0, 0, 0]}]}}", "commands[0].recent_progress",
     "at most 2 values"),  # the seed profile's 0.1 s at this robot's control period
    (_command("!DriveDistance {distance: 1, start: [0, 0, 0], recent_progress: [0, 0.01]}"),
     None, None),
])
def test_a_saved_commands_recent_progress_is_checked(override, field, words):
    """The field a saved scene writes for a running command (docs/commands.md, Saving)."""
    _loads_or_names(override, field and f"robots.corobot.{field}", words, one_line=True)


def test_a_loaded_scenario_is_checked_once_until_it_changes(monkeypatch):
    """`load_scenario`'s result is marked checked: `Simulation` does not validate it again,
    but any change since (a field set, an array or a list changed in place) is checked."""
    from corobot_drake.config import validate

    calls = []
    validate_once = validate.LayerChecks.validate
    monkeypatch.setattr(validate.LayerChecks, "validate",
                        lambda self, s, **kw: (calls.append(s), validate_once(self, s, **kw)))
    scenario = load_scenario(DEFAULT_SCENARIO)
    loaded = len(calls)
    assert loaded == 1  # one layer: validated once as it loads
    validate.check_scenario(scenario)
    assert len(calls) == loaded  # unchanged: not again
    for change in (lambda s: setattr(s.robots["corobot"].drive, "slew_rate", 29.0),
                   lambda s: s.robots["corobot"].velocity.__setitem__(0, 0.01),  # in place
                   lambda s: s.robots["corobot"].commands.append(sc.Wait(1.0)),
                   lambda s: setattr(s.robots["corobot"].cameras["front"], "fps", 15.0),
                   lambda s: setattr(s.simulator_config, "max_step_size", 0.005)):
        change(scenario)
        before = len(calls)
        validate.check_scenario(scenario)
        validate.check_scenario(scenario)
        assert len(calls) == before + 1  # the change checked, once


def _other(number):
    """Another number of the same type, in [0, 1] if `number` is (a colour channel)."""
    if isinstance(number, int | np.integer):
        return number + 1
    return 0.0 if not math.isfinite(number) else number - 0.25 if number >= 0.25 else (
        number + 0.25)


def _leaves(value, path=""):
    """(path, setter) of every number and string in a scenario (dataclass and Drake fields,
    dicts, lists, arrays: Drake's are read-only, set whole)."""
    children = (value.items() if isinstance(value, dict) else enumerate(value)
                if isinstance(value, list) else
                [(f.name, getattr(value, f.name)) for f in dc.fields(value)]
                if dc.is_dataclass(value) else
                [(f.name, getattr(value, f.name)) for f in type(value).__fields__]
                if hasattr(type(value), "__fields__") else [])
    for key, child in children:
        if isinstance(child, np.ndarray):
            for i in range(child.size):
                def bump_item(obj=value, name=key, old=child, i=i):
                    new = old.copy()
                    new.flat[i] = _other(new.flat[i])
                    setattr(obj, name, new)
                yield f"{path}.{key}[{i}]", bump_item
        elif isinstance(child, bool | int | float | str) and isinstance(value, list):
            def bump_entry(obj=value, i=key, old=child):
                obj[i] = _other(old)
            yield f"{path}[{key}]", bump_entry
        elif isinstance(child, bool | int | float | str) and not isinstance(value, dict):
            def bump(obj=value, name=key, old=child):
                setattr(obj, name, (not old) if isinstance(old, bool) else old + "x"
                        if isinstance(old, str) else _other(old))
            yield f"{path}.{key}", bump
        else:
            yield from _leaves(child, f"{path}.{key}")


def test_the_checked_marker_sees_every_field_change():
    """Every number, flag and string of the default scenario, changed alone, makes the
    scenario's content differ from the one marked at load: nothing changes unseen."""
    from corobot_drake.config import validate

    loaded = load_scenario(DEFAULT_SCENARIO)
    leaves = list(_leaves(loaded))
    assert len(leaves) > 150  # the walk reaches the Drake structs' fields too
    for i, (path, _) in enumerate(leaves):
        scenario = copy.deepcopy(loaded)  # the marker too
        marked = scenario._checked_content
        assert marked == validate._content(scenario)
        list(_leaves(scenario))[i][1]()
        assert validate._content(scenario) != marked, path


def test_the_old_camera_key_says_what_to_write_instead():
    """A scenario from before the cameras' map: one line, at the key's line, naming the new
    key and the front camera, for a file and for an override."""
    with pytest.raises(ScenarioError) as e:
        load_scenario(data="robots:\n  corobot:\n    camera: {fps: 10}\n")
    assert str(e.value) == ("<scenario text>:3: robots.corobot.camera: replaced by `cameras`, a "
                            "map of cameras by name: write `cameras: {front: {...}}` (front: "
                            "the Corobot's own camera)")
    with pytest.raises(ScenarioError, match=r"^--override:1: robots\.corobot\.camera: replaced"):
        load_scenario(overrides=["robots: {corobot: {camera: {rgb: false}}}"])


def test_a_new_camera_starts_as_the_spec_camera():
    """A camera the defaults lack starts as the Corobot's (its size, rate, renderer), not as
    Drake's CameraConfig defaults; what the layer writes applies on top, in this layer or a
    later one, for a new robot too."""
    from corobot_drake.config.sensors import default_camera_config

    s = load_scenario(overrides=[
        "robots: {corobot: {cameras: {rear: {fps: 10}}}, other: {pose: {translation: [0, 2, 0]}, "
        "cameras: {top: {}}}}",
        "robots: {corobot: {cameras: {rear: {width: 64}}}}"])
    spec = default_camera_config()
    rear, top = s.robots["corobot"].cameras["rear"], s.robots["other"].cameras["top"]
    assert list(s.robots["corobot"].cameras) == ["front", "rear"]
    assert (rear.fps, rear.width, rear.height) == (10.0, 64, spec.height)
    assert (top.fps, top.width, top.renderer_name) == (spec.fps, spec.width, spec.renderer_name)
    assert s.robots["corobot"].cameras["front"].fps == spec.fps


UNBOUNDED = {
    "Scenario.random_seed": "a seed: any of Drake's ints (DRAKE_INT, the bound of an int "
                            "that declares none) is one",
    "IrSensorConfig.noise_seed": "a seed, as random_seed",
    "LidarConfig.noise_seed": "a seed, as random_seed",
    "ImuConfig.noise_seed": "a seed, as random_seed",
}
"""The number fields of the scenario without a bound of their own, and why."""


def _number_fields(tp, path: str, seen: frozenset, out: dict) -> None:
    """{`Class.field`: its bound or None} of every float or int `tp` holds (through lists,
    maps, unions, dataclasses and Drake's structs); a pose (`Transform`) is checked as a pose
    (translations by POSITION, angles by ANGLE: config/validate.py), so not walked."""
    import typing

    from pydrake.common.schema import Transform

    from corobot_drake.config.bounds import DRAKE_BOUNDS
    from corobot_drake.limits import bound_of

    if typing.get_args(tp):
        for arg in typing.get_args(tp):
            _number_fields(arg, path, seen, out)
        return
    if tp in (float, int):
        out.setdefault(path, None)
        return
    if not isinstance(tp, type) or tp in seen or tp is Transform:
        return
    if dc.is_dataclass(tp):
        fields = [(f.name, typing.get_type_hints(tp)[f.name], bound_of(f)) for f in dc.fields(tp)]
    elif hasattr(tp, "__fields__"):  # Drake's struct
        fields = [(f.name, f.type, DRAKE_BOUNDS.get(tp, {}).get(f.name)) for f in tp.__fields__]
    else:
        return
    for name, hint, bound in fields:
        found = {}
        _number_fields(hint, f"{tp.__name__}.{name}", seen | {tp}, found)
        for field, inner in found.items():
            out[field] = out.get(field) or inner or (
                bound if field == f"{tp.__name__}.{name}" else None)


def test_every_number_of_the_scenario_has_a_bound():
    """Each float and int field a scenario may set declares its range (`limits.bounded`,
    `config.bounds.DRAKE_BOUNDS`), but for the few `UNBOUNDED` says why."""
    fields = {}
    _number_fields(sc.Scenario, "Scenario", frozenset(), fields)
    assert len(fields) > 100  # the robots, their drive, tyres, commands, sensors; Drake's
    assert {"Robot.axle_speed_command", "DriveDistance.start", "RotateDegrees.start",
            "SimulatorConfig.max_step_size", "LightParameter.cone_angle"} <= set(fields)
    unbounded = {field for field, bound in fields.items() if bound is None}
    assert unbounded == set(UNBOUNDED)


@pytest.mark.parametrize("override, field, words", [
    ("robots: {corobot: {axle_speed_command: [1e300, -1e300]}}",
     "robots.corobot.axle_speed_command[0]", "must be in [-200, 200] rad/s; got 1e+300"),
    (_command("!DriveDistance {distance: 1, start: [2e4, 0, 0]}"),
     "robots.corobot.commands[0].start[0]", "must be in [-10000, 10000] m; got 20000"),
    (_command("!RotateDegrees {degrees: 9, start: [0, 0, 1e9]}"),
     "robots.corobot.commands[0].start[2]", "must be in [-3600, 3600] deg; got 1e+09"),
    ("robots: {corobot: {cameras: {front: {renderer_class: !RenderEngineVtkParams {lights: "
     "[{type: spot, cone_angle: 120}]}}}}}",
     "robots.corobot.cameras.front.renderer_class.lights[0].cone_angle",
     "must be in [0, 90] deg"),
    # a vector of Drake's struct: each number finite
    ("robots: {corobot: {cameras: {front: {renderer_class: !RenderEngineVtkParams {lights: "
     "[{type: point, position: [0, 0, .nan]}]}}}}}",
     "robots.corobot.cameras.front.renderer_class.lights[0].position[2]",
     "must be a finite number; got nan"),
    # a list longer than its per-element bounds: its length is what is wrong
    ("robots: {corobot: {odometry: [0, 0, 0, 1, 2, 3]}}", "robots.corobot.odometry",
     "needs [], [x, y, yaw] or [x, y, yaw, left ticks, right ticks]"),
    (_command("!DriveDistance {distance: 1, start: [0, 0, 0, 1]}"),
     "robots.corobot.commands[0].start", "expected [] or [x, y, yaw_deg], got 4 numbers"),
])
def test_a_resumed_drive_and_a_renderers_numbers_are_bounded(override, field, words):
    _loads_or_names(override, field, words, one_line=True)
