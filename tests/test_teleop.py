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
