"""A `Robot` offers the IR sensors' and cameras' accessors only when it has those parts: the
Burger (a lidar, no IR, no camera) has neither, the Corobot both, and a Corobot with its
cameras turned off keeps its IR accessors alone; every robot keeps the generic sensor API."""

import pytest

from conftest import REPO, make_sim
from corobot_drake.robot_api.sensors import Cameras, IrSensors

IR_ONLY = ("ir", "ir_change_threshold")
CAMERA_ONLY = ("camera_image", "camera_image_time")
GENERIC = ("reading", "sensors", "sensor_json", "ir_names", "camera_names", "has_camera",
           "ir_distances")  # ({} without IR: a signal every robot has)


@pytest.mark.parametrize(("scenario", "camera", "ir", "cameras"), [
    ("corobot.yaml", True, True, True),
    ("corobot.yaml", False, True, False),
    ("burger.yaml", True, False, False),
])
def test_a_robot_has_the_accessors_of_the_parts_it_has(scenario, camera, ir, cameras):
    robot = make_sim(scenario=REPO / "scenarios" / scenario, camera=camera).robot()
    assert isinstance(robot, IrSensors) is ir and isinstance(robot, Cameras) is cameras
    assert all(hasattr(robot, name) is ir for name in IR_ONLY)
    assert all(hasattr(robot, name) is cameras for name in CAMERA_ONLY)
    assert all(hasattr(robot, name) for name in GENERIC)
    assert bool(robot.ir_names) is ir and robot.has_camera is cameras
    if not ir:
        assert "ir" not in dir(robot) and robot.ir_names == () and robot.ir_distances() == {}
