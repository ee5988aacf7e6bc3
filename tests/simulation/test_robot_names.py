"""A misspelt robot name gets the closest names that exist ("did you mean"), from the one
helper (`corobot_drake.names`), wherever a user names a robot: Python, a scenario's override,
the HTTP API's client, the tools' writer of a scenario's drive fields."""

import pytest

from conftest import DEFAULT_SCENARIO, make_sim
from corobot_drake.config.scenario import ScenarioError, load_scenario
from corobot_drake.names import close_names, unknown_robot
from corobot_drake.tuning import sysid

TWO = "robots: {rover: {pose: {translation: [0.0, 1.0, 0.0]}}}"
"""Override: a second robot, `rover`, beside the default's `corobot`."""


def test_the_closest_names_are_named_and_a_far_one_gets_none():
    known = ["corobot", "rover"]
    assert close_names("corobt", known) == ["corobot"]
    assert close_names("ROVER", known) == ["rover"]  # case aside
    assert unknown_robot("corobt", known) == (
        "no robot named 'corobt' (did you mean 'corobot'?); robots: corobot, rover")
    assert unknown_robot("nobody", known) == "no robot named 'nobody'; robots: corobot, rover"


def test_python_names_the_closest_robot():
    sim = make_sim(TWO)
    with pytest.raises(KeyError) as e:
        sim.robot("corobt")
    assert e.value.args[0] == (
        "no robot named 'corobt' (did you mean 'corobot'?); robots: corobot, rover")
    assert sim.robot("rover").name == "rover"


def test_an_override_that_misspells_a_robot_says_which_it_meant():
    """A new name in an override adds a robot (at the origin, inside the one it meant): the
    one line says so and names the robot it was probably meant for."""
    with pytest.raises(ScenarioError) as e:
        load_scenario(DEFAULT_SCENARIO, overrides=["robots: {corobt: {drive: {slew_rate: 5}}}"])
    message = str(e.value)
    assert message.startswith("--override:1: robots.corobt.pose: robot 'corobt' starts")
    assert message.endswith("; 'corobt' adds a robot (did you mean 'corobot'?)")
    with pytest.raises(ScenarioError) as e:  # a name close to none gets no guess
        load_scenario(DEFAULT_SCENARIO, overrides=["robots: {zzz: {drive: {slew_rate: 5}}}"])
    assert "did you mean" not in str(e.value)


def test_the_drive_field_writer_names_the_closest_robot(tmp_path):
    source = tmp_path / "s.yaml"
    source.write_text(DEFAULT_SCENARIO.read_text())
    with pytest.raises(ScenarioError) as e:
        sysid.write_drive_fields(source, "Corobot", [sysid.DriveField("slew_rate", 5.0)])
    assert str(e.value) == (f"{source}: robots.Corobot.drive.slew_rate: no robot named "
                            "'Corobot' (did you mean 'corobot'?); robots: corobot")
    assert source.read_text() == DEFAULT_SCENARIO.read_text()


def test_the_http_client_names_the_closest_robot():
    from corobot_drake.serving.client import CorobotClient

    client = CorobotClient.__new__(CorobotClient)  # its robot lookup alone: no server
    client._robots, client._get = {}, lambda path: {"robots": ["corobot"]}  # GET /robots
    with pytest.raises(KeyError, match=r"did you mean 'corobot'\?"):
        client.robot("corobt")


def test_the_http_api_answers_404_naming_the_closest_robot():
    """`GET /robots/<name>/...`: the routes look the robot up through the backend."""
    from types import SimpleNamespace

    from fastapi import HTTPException

    from corobot_drake.serving.routes.backend import Backend

    backend = Backend(SimpleNamespace(robots={"corobot": object(), "rover": object()}))
    with pytest.raises(HTTPException) as e:
        backend.robot("corobt")
    assert e.value.status_code == 404
    assert e.value.detail == (
        "no robot named 'corobt' (did you mean 'corobot'?); robots: corobot, rover")


def test_a_study_names_the_closest_robot_and_field(tmp_path):
    """A program's `robot` and a grid path's robot or field, each at its line."""
    from corobot_drake.study.spec import load_study

    study = f"scenario: {DEFAULT_SCENARIO}\nduration: 0.3\n"
    cases = {
        "drive_test: {robot: corobt}\n":
            ":3: drive_test.robot: the scenario has no robot 'corobt' (did you mean "
            "'corobot'?); it has: corobot",
        "grid: {robots.corobt.drive.slew_rate: [5]}\n":
            ":3: grid.robots.corobt.drive.slew_rate: robots has no 'corobt' (did you mean "
            "'corobot'?); it has: corobot",
        "grid: {robots.corobot.drive.slew_rtae: [5]}\n":
            ":3: grid.robots.corobot.drive.slew_rtae: robots.corobot.drive (Drive) has no field "
            "'slew_rtae' (did you mean 'slew_rate'?); fields: motor_torque_scaling, slew_rate, ",
    }
    for text, expected in cases.items():
        path = tmp_path / "study.yaml"
        path.write_text(study + text)
        with pytest.raises(ScenarioError) as e:
            load_study(path)
        assert str(e.value).startswith(f"{path}{expected}"), e.value


def test_the_snapshot_tool_names_the_closest_robot(capsys):
    from conftest import load_tool

    snapshot = load_tool("snapshot")
    parser = snapshot._parser()
    with pytest.raises(SystemExit) as stop:
        snapshot._scenario(parser.parse_args(["--robot", "corobt"]), parser)
    assert stop.value.code == 2
    assert capsys.readouterr().err.splitlines()[-1].endswith(
        "error: --robot: no robot named 'corobt' (did you mean 'corobot'?); robots: corobot")


def test_the_ros2_entity_services_name_the_closest_entity():
    """GetEntityState and the other entity services' NOT_FOUND (no DDS: the lookup alone)."""
    from types import SimpleNamespace

    pytest.importorskip("rclpy", reason="the [ros2] extra (tools/setup installs it)")
    pytest.importorskip("simulation_interfaces.msg", reason="python -m corobot_drake.ros2.build")
    from corobot_drake.ros2.simulation_services import RefusedError, entity_body

    sim = SimpleNamespace(station=SimpleNamespace(robots={}), robots=["corobot"],
                          bodies=lambda: {"cone_goal": None, "cone_bonus_1": None})
    with pytest.raises(RefusedError) as e:
        entity_body(sim, "cone_gaol")
    assert str(e.value) == ("entity: no entity named 'cone_gaol' (did you mean 'cone_goal'?) "
                            "(there are: corobot, cone_goal, cone_bonus_1)")


def test_a_gym_robot_names_the_closest_shipped_robot():
    """It was "cannot read the file .../burgr", with no list nor suggestion."""
    gymnasium = pytest.importorskip("gymnasium", reason="the [gym] extra")
    from corobot_drake.gym import ENV_ID

    with pytest.raises(ValueError) as e:
        gymnasium.make(ENV_ID, robot="burgr")
    assert str(e.value) == ("GoToGoalConfig.robot: 'burgr' is neither a shipped robot (corobot, "
                            "burger, pioneer) nor a robot file (did you mean 'burger'?)")


def test_a_robot_kind_names_the_closest_shipped_robot():
    with pytest.raises(ScenarioError) as e:
        load_scenario(DEFAULT_SCENARIO, overrides=[
            "robots: {rover: {robot: burgr, pose: {translation: [0.0, 1.0, 0.0]}}}"])
    assert str(e.value) == ("--override:1: robots.rover.robot: 'burgr' is neither a shipped "
                            "robot (corobot, burger, pioneer) nor a robot file (did you mean "
                            "'burger'?)")
