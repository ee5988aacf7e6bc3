"""The robot file and its RobotSpec: the Corobot's is exactly today's Corobot, a user's URDF
robot loads and names its figures, and a wrong robot file is one line at its field."""

import pytest
from pydrake.common.yaml import yaml_dump_typed
from robot_samples import two_wheel_robot as _robot

from corobot_drake.config import scenario as sc
from corobot_drake.config.scenario import ScenarioError, load_scenario
from corobot_drake.model import dimensions as dim
from corobot_drake.model.sdf import WheelContact
from corobot_drake.robots import LEFT, RIGHT, robot_spec
from corobot_drake.robots.load import load_spec


def test_the_corobots_spec_is_its_cads_to_the_bit():
    """The Corobot's robot file and generated model, measured, give its CAD's figures
    (what model generation makes it from) exactly; the drive is the scenario's default."""
    spec = robot_spec("corobot")
    assert spec.wheel_radius == dim.WHEEL_RADIUS
    assert spec.track == dim.TRACK and spec.half_track == dim.HALF_TRACK
    assert spec.wheelbase / 2 == dim.HALF_WHEELBASE
    assert spec.spin_yaw_per_rim_speed == dim.HALF_TRACK / (
        dim.HALF_WHEELBASE**2 + dim.HALF_TRACK**2)
    assert spec.wheel_names == dim.WHEEL_NAMES
    assert spec.sides == (LEFT, RIGHT, LEFT, RIGHT)
    assert spec.encoded == (0, 1)
    assert spec.mass == pytest.approx(dim.TOTAL_BODY_MASS + 4 * dim.WHEEL_MASS)
    assert spec.casters == ()
    assert spec.generated and spec.base == "chassis"
    assert spec.contact == WheelContact()
    assert spec.drive == sc.Drive()
    assert spec.encoder_ticks_per_revolution == 600


def test_the_corobots_robot_file_holds_the_scenarios_default_sensors():
    spec, robot = robot_spec("corobot"), sc.Robot()
    from corobot_drake.robots.file import RobotFile

    mine, theirs = RobotFile(), RobotFile()
    for field, configs in spec.sensors.items():
        setattr(mine, field, configs)
        setattr(theirs, field, getattr(robot, field))
    assert yaml_dump_typed(mine) == yaml_dump_typed(theirs)


def test_a_urdf_robot_is_measured_from_its_shapes(tmp_path):
    spec = load_spec(_robot(tmp_path))
    assert spec.wheel_names == ("left", "right") and spec.sides == (LEFT, RIGHT)
    assert spec.wheel_radius == pytest.approx(0.033)
    assert spec.track == pytest.approx(0.16)
    assert spec.wheelbase == 0.0
    assert spec.spin_yaw_per_rim_speed == pytest.approx(1 / 0.08)
    assert spec.mass == pytest.approx(1.1)
    assert spec.casters == ("base_link/caster",) or spec.casters[0].startswith("base_link/")
    assert spec.drive.motor_torque_scaling == pytest.approx(0.22 / 0.033)
    assert spec.drive.effective_track_width == pytest.approx(0.16)


def test_a_scenario_names_a_robot_file_and_starts_from_its_figures(tmp_path):
    _robot(tmp_path)
    scenario = load_scenario(data=f"robots: {{a: {{robot: {tmp_path}/robot.yaml}}, b: {{"
                             "pose: {translation: [1, 0, 0]}}}")
    a, b = scenario.robots["a"], scenario.robots["b"]
    assert a.robot == str(tmp_path / "robot.yaml") and b.robot == "corobot"
    assert a.wheel_angles == [0.0, 0.0] and len(b.wheel_angles) == 4
    assert a.drive.motor_torque_scaling == pytest.approx(0.22 / 0.033)
    assert a.ir_sensors == {} and set(b.ir_sensors) == {"front", "rear"}


def test_the_robots_keep_the_scenarios_order():
    """A robot with a `robot:` of its own is loaded before the layer's fields apply: it must
    still come where the scenario lists it (the teleop and the dashboard open on the first),
    and an override's new robot after the ones below it."""
    from corobot_drake.resources import scenario_path

    scenario = load_scenario(scenario_path("three_robots.yaml"))
    assert list(scenario.robots) == ["corobot", "burger", "pioneer"]
    scenario = load_scenario(data="robots: {z: {robot: burger}, a: {pose: {translation: "
                             "[0, 1, 0]}}}", overrides=["robots: {p: {robot: burger, pose: "
                                                         "{translation: [0, -1, 0]}}, z: {}}"])
    assert list(scenario.robots) == ["z", "a", "p"]


@pytest.mark.parametrize(("yaml", "field", "words"), [
    ("base: base_link\nwheels: {left: [left_joint], right: [right_joint]}\n", "model",
     "names the robot's"),
    ("model: twowheel.urdf\nbase: nowhere\nwheels: {left: [left_joint], right: [right_joint]}"
     "\ndrive: {top_speed: 0.2}\n", "base", "no link 'nowhere'"),
    ("model: twowheel.urdf\nbase: base_link\nwheels: {left: [left_joint], right: [rite]}\n"
     "drive: {top_speed: 0.2}\n", "wheels.right[0]", "no joint 'rite'"),
    ("model: twowheel.urdf\nbase: base_link\nwheels: {left: [left_joint]}\n"
     "drive: {top_speed: 0.2}\n", "wheels.right", "each side"),
    ("model: twowheel.urdf\nbase: base_link\nwheels: {left: [left_joint], right: [right_joint],"
     " radius: 0.05}\ndrive: {top_speed: 0.2}\n", "wheels.radius", "measure"),
    ("model: twowheel.urdf\nbase: base_link\nwheels: {left: [left_joint], right: [right_joint]}"
     "\n", "drive", "top_speed"),
    ("model: twowheel.urdf\nbase: base_link\nwheels: {left: [left_joint], right: [right_joint]}"
     "\ndrive: {top_speed: 0.2}\nlidars: {scan: {X_PB: {base_frame: mast}}}\n",
     "lidars.scan.X_PB.base_frame", "not a link"),
    ("model: twowheel.urdf\nbase: base_link\nwheels: {left: [left_joint], right: [right_joint]}"
     "\ndrive: {top_speed: 0.2}\nodometry: {end_error: 0.001}\n", "odometry", "needs all of"),
    ("model: twowheel.urdf\nbase: base_link\nwheels: {left: [left_joint], right: [right_joint]}"
     "\ndrive: {top_speed: 0.2}\nodometry: {heading_error_deg: 400}\n",
     "odometry.heading_error_deg", "must be in"),
])
def test_a_wrong_robot_file_is_one_line_at_its_field(tmp_path, yaml, field, words):
    path = _robot(tmp_path, yaml)
    with pytest.raises(ScenarioError) as e:
        load_spec(path)
    assert e.value.field == field and words in e.value.message, str(e.value)
    assert str(e.value).startswith(f"{path}:") and "\n" not in str(e.value)


def test_a_wheel_off_the_ground_is_named(tmp_path):
    with pytest.raises(ScenarioError, match=r"wheels.left\[0\]: .*does not touch the ground"):
        load_spec(_robot(tmp_path, z=0.05))


def test_a_fixed_wheel_joint_is_named(tmp_path):
    with pytest.raises(ScenarioError, match=r"wheels.left\[0\]: .*weld joint"):
        load_spec(_robot(tmp_path, joint_type="fixed"))


_CHASSIS = '<box size="0.14 0.12 0.06"/>'


@pytest.mark.parametrize(("old", "new", "words"), [
    # The chassis box (centre 8 cm up) 1 cm into the ground: a body, not a caster.
    ('<origin xyz="0 0 0.08"/>', '<origin xyz="0 0 0.02"/>', "base_link/Box goes 10 mm "
     "into the ground at the start pose (at most 2 mm"),
    (_CHASSIS, '<box size="1e9 1e9 1e9"/>', "base_link/Box goes 5e+08 m into the ground"),
    # Drake's parser replaces such an inertia, saying only that an assertion failed.
    ('<mass value="0.05"/>', '<mass value="0"/>', "twowheel.urdf:12: link 'left_wheel' has "
     "no mass (0 kg or less) but an inertia"),
    ('ixx="0.01" iyy="0.01" izz="0.01"', 'ixx="0" iyy="0" izz="0"', "the base link "
     "'base_link' (with what is fixed to it) has no rotational inertia about an axis (a "
     "point mass; its principal moments [0.0, 0.0, 0.0] kg m^2)"),
])
def test_a_model_the_robot_cannot_be_is_one_line(tmp_path, old, new, words):
    path = _robot(tmp_path)
    model = tmp_path / "twowheel.urdf"
    model.write_text(model.read_text().replace(old, new, 1))
    with pytest.raises(ScenarioError) as e:
        load_spec(path)
    assert e.value.field == "model" and words in e.value.message, str(e.value)
    assert "bazel" not in str(e.value) and "\n" not in str(e.value)


def test_a_mesh_over_the_limit_says_by_how_much(tmp_path):
    from corobot_drake.robots.model_files import mib

    assert mib(32 << 20) == "32.0 MiB" and mib((32 << 20) + 1) == "32.1 MiB"
    assert mib(int(32.96 * (1 << 20))) == "33.0 MiB"


def test_robot_check_says_what_it_understood_and_writes_the_urdf(tmp_path, capsys):
    from corobot_drake.robot import main

    urdf = tmp_path / "out.urdf"
    assert main(["check", str(_robot(tmp_path)), "--urdf", str(urdf)]) == 0
    out = capsys.readouterr().out
    assert "differential drive: 1 left, 1 right wheel(s)" in out
    assert "wheel radius 0.0330 m, track 0.1600 m" in out
    assert "casters: base_link/caster" in out and "top speed 0.220 m/s" in out
    assert '<joint name="left_joint"' in urdf.read_text()


def test_robot_check_of_a_bad_robot_file_is_one_line_and_exit_2(tmp_path, capsys):
    from corobot_drake.robot import main

    path = _robot(tmp_path, z=0.05)
    assert main(["check", str(path), "--no-urdf"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"error: {path}:3: wheels.left[0]: ")


def test_robot_check_says_where_its_urdf_went_and_never_over_the_model(tmp_path, capsys,
                                                                          monkeypatch):
    from corobot_drake.robot import main

    (tmp_path / "mine").mkdir()
    path = _robot(tmp_path / "mine")
    monkeypatch.chdir(tmp_path)
    assert main(["check", str(path)]) == 0  # by default into the current folder, as <robot>
    assert capsys.readouterr().out.endswith(f"wrote {tmp_path / 'mine.urdf'} (the robot's "
                                            "URDF, for RViz and robot_state_publisher)\n")
    model = tmp_path / "mine" / "twowheel.urdf"
    before = model.read_text()
    assert main(["check", str(path), "--urdf", str(model)]) == 2
    err = capsys.readouterr().err
    assert err == (f"error: {model} is the robot's own model: not written over (--urdf FILE "
                   "names another, --no-urdf writes none)\n")
    assert model.read_text() == before


def test_a_sensor_a_scenario_adds_to_a_robot_rides_on_its_base_link(tmp_path):
    path = _robot(tmp_path)
    scenario = load_scenario(data=f"robots: {{u: {{robot: {path}, ir_sensors: {{side: {{}}}}}}}}")
    assert scenario.robots["u"].ir_sensors["side"].X_PB.base_frame == "base_link"


def test_a_robot_is_measured_again_when_its_model_changes(tmp_path):
    import os

    path = _robot(tmp_path)
    assert robot_spec(str(path)).wheel_radius == pytest.approx(0.033)
    assert robot_spec(str(path)) is robot_spec(str(path))  # measured once
    model = tmp_path / "twowheel.urdf"
    stat = model.stat()
    _robot(tmp_path, radius=0.04, z=0.04)  # rewrites the model (and the robot file, the same)
    os.utime(model, ns=(stat.st_atime_ns, stat.st_mtime_ns + 1_000_000))
    assert robot_spec(str(path)).wheel_radius == pytest.approx(0.04)


def test_the_shipped_corobot_robot_file_is_its_generators_output():
    from corobot_drake.model.robot_file import robot_file_text
    from corobot_drake.robots.corobot import FILE

    assert FILE.read_text() == robot_file_text()


def test_a_default_with_no_robot_at_hand_is_the_corobots_robot_file():
    """`robots/corobot.py`, what the scenario's defaults and the tables built at import read,
    gives the Corobot as its robot file and model say: its measured spec's figures."""
    from corobot_drake.robots import corobot

    spec = robot_spec("corobot")
    assert corobot.spec() is spec
    assert corobot.wheel_names() == spec.wheel_names
    assert corobot.model_file() == spec.model_file
    drive = sc.Drive()
    for field in ("motor_torque_scaling", "slew_rate", "max_axle_speed", "control_period"):
        assert getattr(drive, field) == corobot.drive(field) == getattr(spec.drive, field)
    assert drive.effective_wheel_radius == corobot.wheels("radius") == spec.wheel_radius
    assert drive.effective_track_width == corobot.wheels("track") == spec.track
    assert corobot.drive("encoder_ticks_per_revolution") == spec.encoder_ticks_per_revolution
    for name, part in (("chassis", dim.CHASSIS), ("platform", dim.PLATFORM)):
        size, centre = corobot.box(name)  # the model's, its CAD's to its SDF's 9 digits
        assert size == pytest.approx(part.size, abs=1e-12)
        assert centre == pytest.approx(part.center, abs=1e-12)


MODEL_GENERATION = {"corobot_drake/model/dimensions.py", "corobot_drake/model/sdf.py",
                    "corobot_drake/model/meshes.py", "corobot_drake/model/robot_file.py"}
"""The modules that make the Corobot's model and robot file from its CAD."""


def test_only_model_generation_reads_the_corobots_cad():
    """The package, its tools and the lab read the Corobot from its robot file and model
    (`robots/corobot.py`, its `RobotSpec`); the CAD module is model generation's alone."""
    import re

    from conftest import REPO

    imports = re.compile(r"^\s*(from corobot_drake\.model(\.dimensions)? import .*\bdimensions\b|"
                         r"from corobot_drake\.model\.dimensions import|"
                         r"import corobot_drake\.model\.dimensions)", re.MULTILINE)
    readers = sorted(str(path.relative_to(REPO)) for folder in ("corobot_drake", "tools", "lab")
                     for path in (REPO / folder).rglob("*.py")
                     if imports.search(path.read_text()))
    assert set(readers) <= MODEL_GENERATION, readers
