"""/robot_description of any robot (`ros2.urdf.robot_urdf`): the robot's own model written
back as URDF, read again by Drake's URDF parser: the same mass, the wheels' joints by name
as continuous joints about their axles, the wheels where the robot's spec measured them."""

import numpy as np
import pytest
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant

from corobot_drake.resources import MODELS_DIR
from corobot_drake.robots import robot_spec
from corobot_drake.ros2.urdf import corobot_urdf, robot_urdf
from corobot_drake.topics import CHASSIS_FRAME

ROBOT_FILES = [str(MODELS_DIR / name / "robot.yaml") for name in ("burger", "pioneer")]


def _reparsed(text: str):
    plant = MultibodyPlant(0.0)
    (instance,) = Parser(plant).AddModelsFromString(text, "urdf")
    plant.Finalize()
    return plant, instance, plant.CreateDefaultContext()


def test_the_corobot_keeps_its_description():
    spec = robot_spec("corobot")
    assert robot_urdf(spec, "corobot") == corobot_urdf(None, "corobot")


@pytest.mark.parametrize("robot", ROBOT_FILES)
def test_a_robot_file_model_round_trips(robot):
    spec = robot_spec(robot)
    plant, instance, context = _reparsed(robot_urdf(spec, "r"))
    # The whole robot's mass to the printed digits (9 significant).
    assert plant.CalcTotalMass(context, [instance]) == pytest.approx(spec.mass, rel=1e-8)
    assert plant.HasBodyNamed(CHASSIS_FRAME)  # the base link, as /tf names it
    X_WB = plant.EvalBodyPoseInWorld(context, plant.GetBodyByName(CHASSIS_FRAME))
    for wheel in spec.wheels:
        joint = plant.GetJointByName(wheel.joint)
        assert joint.type_name() == "revolute"
        assert not np.isfinite(joint.position_upper_limits()[0])  # continuous
        X_WW = plant.EvalBodyPoseInWorld(context, plant.GetBodyByName(wheel.link))
        # Where the spec measured the wheel, to the 9 printed digits (sub-micrometre).
        np.testing.assert_allclose((X_WB.inverse() @ X_WW).translation(), wheel.center,
                                   atol=1e-8)
        # Its axle along the base's y, as the model's own.
        axis = X_WW.rotation() @ joint.revolute_axis()
        assert abs(axis[1]) == pytest.approx(1.0, abs=1e-8)


def test_an_offset_joint_frame_is_kept(tmp_path):
    """An SDFormat joint posed off its child link's origin: the URDF link is the joint's
    frame, so the link's shapes and inertia move with it and the wheel stays where it was."""
    (tmp_path / "bot.sdf").write_text("""<?xml version="1.0"?>
<sdf version="1.9"><model name="bot">
  <link name="base"><inertial><mass>2</mass><inertia>
    <ixx>0.01</ixx><iyy>0.01</iyy><izz>0.01</izz></inertia></inertial>
    <collision name="c"><pose>-0.1 0 0.01 0 0 0</pose><geometry><sphere><radius>0.01</radius>
    </sphere></geometry></collision></link>
  <link name="wl"><pose>0 0.1 0.05 -1.5707963267948966 0 0</pose><inertial><mass>0.1</mass>
    <inertia><ixx>1e-4</ixx><iyy>1e-4</iyy><izz>1e-4</izz></inertia></inertial>
    <collision name="c"><geometry><cylinder><radius>0.05</radius><length>0.02</length>
    </cylinder></geometry></collision></link>
  <link name="wr"><pose>0 -0.1 0.05 -1.5707963267948966 0 0</pose><inertial><mass>0.1</mass>
    <inertia><ixx>1e-4</ixx><iyy>1e-4</iyy><izz>1e-4</izz></inertia></inertial>
    <collision name="c"><geometry><cylinder><radius>0.05</radius><length>0.02</length>
    </cylinder></geometry></collision></link>
  <joint name="jl" type="revolute"><parent>base</parent><child>wl</child>
    <pose>0 0.01 0 0 0 0.3</pose><axis><xyz expressed_in="base">0 1 0</xyz><limit>
    <lower>-1e20</lower><upper>1e20</upper></limit></axis></joint>
  <joint name="jr" type="revolute"><parent>base</parent><child>wr</child>
    <axis><xyz expressed_in="base">0 1 0</xyz><limit><lower>-1e20</lower><upper>1e20</upper>
    </limit></axis></joint>
</model></sdf>
""")
    (tmp_path / "robot.yaml").write_text(
        "model: bot.sdf\nbase: base\nwheels: {left: [jl], right: [jr]}\n"
        "drive: {top_speed: 0.5}\n")
    spec = robot_spec(str(tmp_path / "robot.yaml"))
    plant, instance, context = _reparsed(robot_urdf(spec))
    X_WB = plant.EvalBodyPoseInWorld(context, plant.GetBodyByName(CHASSIS_FRAME))
    for wheel in spec.wheels:
        link = plant.GetBodyByName(wheel.link)
        X_BW = X_WB.inverse() @ plant.EvalBodyPoseInWorld(context, link)
        p_Bcm = X_BW @ link.default_spatial_inertia().get_com()
        np.testing.assert_allclose(p_Bcm, wheel.center, atol=1e-8)
    assert plant.CalcTotalMass(context, [instance]) == pytest.approx(spec.mass, rel=1e-8)
