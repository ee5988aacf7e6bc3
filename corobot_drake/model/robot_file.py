"""The Corobot's robot file kept in step with its CAD: `robot_file_text()`.

`models/corobot/robot.yaml` is where the simulator reads what the Corobot is; most of it
(the drive, the sensors' settings) is the file's own. What the CAD (`dimensions`) also fixes,
the wheels' radius, track and wheelbase and the mounts of the sensors its meshes show, this
writes from the CAD exactly (Drake's YAML writes a float's shortest round trip), so the
Corobot's RobotSpec is its generated model's to the bit. Regenerate the file with
`python tools/make_model.py --robot-file models/corobot/robot.yaml`; a test keeps it current.
"""

import math

from pydrake.common.yaml import yaml_dump_typed

from corobot_drake.config.poses import mount
from corobot_drake.config.sensors import CAMERA_ROTATION_RPY_DEG, FRONT_CAMERA
from corobot_drake.model import dimensions as dim
from corobot_drake.robots.corobot import FILE

HEADER = """\
# The Corobot: the CoroWare robot of the book's chapter, a four-wheel skid steer.
# This file is what the simulator reads the Corobot from. Its model is generated from its
# CAD (corobot_drake/model/dimensions.py, tools/make_model.py); the wheels' radius, track
# and wheelbase and the mounts of the IR sensors and the camera are that CAD's, written
# exactly (a test keeps them in step).
"""

IR_MOUNTS = {"front": dim.FRONT_IR, "rear": dim.REAR_IR}
"""The IR sensors the model's meshes show, by their name in the robot file."""


def robot_file(path=FILE):
    """The robot file at `path` with its CAD figures set from `dimensions`."""
    from corobot_drake.robots.load import load_robot_file

    robot, _ = load_robot_file(path)
    robot.wheels.radius = dim.WHEEL_RADIUS
    robot.wheels.track = dim.TRACK
    robot.wheels.wheelbase = 2 * dim.HALF_WHEELBASE
    for name, m in IR_MOUNTS.items():
        robot.ir_sensors[name].X_PB = mount(m.position, (0.0, 0.0, math.degrees(m.yaw)))
    roll, _, yaw = CAMERA_ROTATION_RPY_DEG
    robot.cameras[FRONT_CAMERA].X_PB = mount(
        dim.CAMERA.position, (roll, 0.0, yaw + math.degrees(dim.CAMERA.yaw)))
    return robot


def robot_file_text(path=FILE) -> str:
    """The Corobot's robot file's text, its CAD figures from `dimensions`."""
    from corobot_drake.robots.file import RobotFile

    return HEADER + yaml_dump_typed(robot_file(path), schema=RobotFile)
