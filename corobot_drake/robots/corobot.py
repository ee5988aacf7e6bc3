"""The Corobot's robot file, written from `model/dimensions.py`: `robot_file_text()`.

`models/corobot/robot.yaml` is this module's output (a test keeps them equal); regenerate it
with `python -m corobot_drake.robots.corobot > models/corobot/robot.yaml`. Every figure is
written exactly (Drake's YAML writes a float's shortest round trip), so the Corobot's
RobotSpec is `dimensions.py`'s to the bit.
"""

from pydrake.common.yaml import yaml_dump_typed

from corobot_drake.model import dimensions as dim
from corobot_drake.model.sdf import WheelContact
from corobot_drake.robots.file import RobotDrive, RobotFile, Wheels
from corobot_drake.sensors.registry import KINDS

HEADER = """\
# The Corobot: the CoroWare robot of the book's chapter, a four-wheel skid steer.
# Its model is generated from corobot_drake/model/dimensions.py (tools/make_model.py);
# this file is that module's figures, written exactly (a test keeps them in step).
"""


def robot_file() -> RobotFile:
    """The Corobot as a robot file: its generated model, its wheels' exact figures, its
    drive and motors, and its default sensors (each kind's `defaults`)."""
    contact = WheelContact()
    robot = RobotFile(
        model="../corobot.sdf", base="chassis",
        wheels=Wheels(left=["front_left_axle", "rear_left_axle"],
                      right=["front_right_axle", "rear_right_axle"],
                      radius=dim.WHEEL_RADIUS, track=dim.TRACK,
                      wheelbase=2 * dim.HALF_WHEELBASE),
        drive=RobotDrive(motor_torque_scaling=dim.MOTOR_TORQUE_SCALING,
                         max_axle_speed=dim.MAX_AXLE_SPEED, slew_rate=dim.SLEW_RATE,
                         torque_limit=contact.effort_limit,
                         encoder_ticks_per_revolution=dim.ENCODER_TICKS_PER_REVOLUTION,
                         control_period=dim.CONTROL_PERIOD,
                         servo_damping=contact.servo_damping))
    for kind in KINDS:
        setattr(robot, kind.field, kind.defaults())
    return robot


def robot_file_text() -> str:
    """`models/corobot/robot.yaml`'s text."""
    return HEADER + yaml_dump_typed(robot_file(), schema=RobotFile)


if __name__ == "__main__":
    print(robot_file_text(), end="")
