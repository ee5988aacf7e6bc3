"""Meshcat teleop: a key press (as Meshcat's browser sends it) drives the robot."""

import pytest
from pydrake.geometry import StartMeshcat

from conftest import make_sim
from corobot_drake.serving.teleop import MeshcatTeleop


def _msgpack_str(text: str) -> bytes:
    data = text.encode()
    assert len(data) < 256
    return (bytes([0xA0 | len(data)]) if len(data) < 32 else bytes([0xD9, len(data)])) + data


def press(meshcat, button: str) -> None:
    """What the browser sends on a click or the button's key: {"type": "button", "name": ...}."""
    message = bytes([0x82]) + _msgpack_str("type") + _msgpack_str("button") \
        + _msgpack_str("name") + _msgpack_str(button)
    meshcat._InjectWebsocketMessage(message)


@pytest.fixture(scope="module")
def meshcat():
    return StartMeshcat()


def test_keys_drive_stop_and_disable(meshcat):
    sim = make_sim()
    teleop = MeshcatTeleop(meshcat, sim)
    robot = sim.robot()
    meshcat.SetSliderValue("Power", 1.0)
    press(meshcat, "Forward (Up)")
    teleop.poll()
    sim.advance(1.5)
    assert robot.velocity().forward == pytest.approx(0.61, rel=0.05)
    press(meshcat, "Stop (Space)")
    teleop.poll()
    sim.advance(1.0)
    assert abs(robot.velocity().forward) < 0.01
    press(meshcat, "Turn left (Left)")
    teleop.poll()
    sim.advance(1.0)
    assert robot.velocity().yaw_rate > 0.5  # counter-clockwise seen from above
    press(meshcat, "Enable/disable (E)")
    teleop.poll()
    sim.advance(0.5)
    assert not robot.is_enabled()
    assert abs(robot.velocity().yaw_rate) < 0.05
    meshcat.DeleteAddedControls()


class Clock:
    """A wall clock the test sets."""

    def __init__(self):
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def test_a_held_key_drives_and_its_release_stops(meshcat):
    """Meshcat reports presses only: a held key is its auto-repeat's stream of presses; the
    move ends HOLD_REPEAT after the last (HOLD_FIRST after a lone first press)."""
    from corobot_drake.serving.teleop import HOLD_FIRST, HOLD_REPEAT

    sim, clock = make_sim(), Clock()
    teleop = MeshcatTeleop(meshcat, sim, clock=clock)
    robot = sim.robot()

    def last_command() -> str:
        return robot.command_log()[-1].command

    press(meshcat, "Forward (Up)")
    teleop.poll()
    assert last_command() == "SetPower"
    # The repeat delay: no press for 0.5 s, still driving.
    clock.now = 0.5
    teleop.poll()
    assert last_command() == "SetPower"
    # The repeats: every 40 ms for 1.5 s; the robot drives on (and is not re-commanded).
    seq = robot.command_log()[-1].seq
    for _ in range(38):
        clock.now += 0.04
        press(meshcat, "Forward (Up)")
        teleop.poll()
        sim.advance(0.04)
    assert robot.command_log()[-1].seq == seq
    assert robot.velocity().forward > 0.25
    # Released: stopped HOLD_REPEAT after the last repeat, not before.
    released = clock.now
    clock.now = released + HOLD_REPEAT - 0.01
    teleop.poll()
    assert last_command() == "SetPower"
    clock.now = released + HOLD_REPEAT + 0.01
    teleop.poll()
    assert last_command() == "AllStop"
    sim.advance(1.0)
    assert abs(robot.velocity().forward) < 0.01
    # A lone press (a tap or a click on the button) nudges for HOLD_FIRST.
    press(meshcat, "Turn left (Left)")
    teleop.poll()
    clock.now += HOLD_FIRST - 0.01
    teleop.poll()
    assert last_command() == "SetPower"
    clock.now += 0.02
    teleop.poll()
    assert last_command() == "AllStop"
    meshcat.DeleteAddedControls()


def test_the_robot_slider_picks_a_robot_and_a_button_names_it(meshcat):
    """three_robots.yaml lists the Corobot first: the teleop opens on it; the slider's next
    value drives the Burger (listed second), and the "Driving: ..." button says so."""
    from corobot_drake.resources import scenario_path

    sim, clock = make_sim(scenario=scenario_path("three_robots.yaml")), Clock()
    teleop = MeshcatTeleop(meshcat, sim, clock=clock)
    assert "Driving: corobot" in meshcat.GetButtonNames()
    meshcat.SetSliderValue("Robot #", 1)
    press(meshcat, "Forward (Up)")
    teleop.poll()
    names = meshcat.GetButtonNames()
    assert "Driving: burger" in names and "Driving: corobot" not in names
    assert sim.robot("burger").command_log()[-1].command == "SetPower"
    assert not any(entry.command == "SetPower" for entry in sim.robot("corobot").command_log())
    meshcat.DeleteAddedControls()


def test_the_view_frames_the_robot_and_the_box_and_follows(meshcat):
    import numpy as np

    from corobot_drake.config.scenario import load_scenario
    from corobot_drake.resources import DEFAULT_SCENARIO
    from corobot_drake.serving.view import FOLLOW_PERIOD, MESHCAT_FOV_DEG

    sim, clock = make_sim(), Clock()
    teleop = MeshcatTeleop(meshcat, sim, clock=clock)
    camera, target = teleop.camera.camera, teleop.camera.target
    # The robot (at the origin) and the giant box's 8 corners lie within the view's cone.
    giant = load_scenario(DEFAULT_SCENARIO).world.bodies["giant_box"]  # where the scene has it
    corners = [np.array(giant.pose.translation) + np.array([x, y, z]) * giant.shape.size[0] / 2
               for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    axis = (target - camera) / np.linalg.norm(target - camera)
    for point in (np.zeros(3), *corners):
        to = (point - camera) / np.linalg.norm(point - camera)
        assert np.degrees(np.arccos(to @ axis)) < MESHCAT_FOV_DEG / 2
    # Driving: the view moves with the robot (level), keeping its offset.
    sim.robot().set_power(1.0, 1.0)
    sim.advance(2.0)
    clock.now = 1.0
    teleop.poll()
    moved = np.array(sim.robot().position())
    np.testing.assert_allclose(teleop.camera.target[:2] - target[:2], moved[:2], atol=1e-9)
    np.testing.assert_allclose(teleop.camera.camera - teleop.camera.target, camera - target)
    # At most one move per FOLLOW_PERIOD of wall clock: a poll just after waits.
    sim.advance(0.5)
    clock.now += FOLLOW_PERIOD / 2
    teleop.poll()
    np.testing.assert_allclose(teleop.camera.target[:2] - target[:2], moved[:2], atol=1e-9)
    # F toggles it off: the view stays.
    clock.now += FOLLOW_PERIOD
    press(meshcat, "Follow camera (F)")
    teleop.poll()
    held = teleop.camera.target.copy()
    sim.advance(1.0)
    clock.now += 1.0
    teleop.poll()
    np.testing.assert_array_equal(teleop.camera.target, held)
    meshcat.DeleteAddedControls()
