"""`--ros2` with robots other than the Corobot, from a separate process as a user's node
sees it: the Burger and the Pioneer side by side (each under its namespace). Each robot's
/robot_description is its own model, /joint_states its own wheel joints, /tf its base_link
and wheels, its contact telemetry one value per wheel, its sensors' topics its own (the
Burger's lidar scan, the Pioneer's sonars). In a private network (`ros2_probe`)."""

import pytest

pytest.importorskip("rclpy", reason="the [ros2] extra (tools/setup installs it)")
pytest.importorskip("corobot_interfaces.msg", reason="python -m corobot_drake.ros2.build")

from corobot_interfaces.msg import WheelLoads
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState, LaserScan, Range
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage

from corobot_drake.robots import robot_spec
from corobot_drake.ros2.urdf import robot_urdf
from ros2_probe import ONE_GRAPH_AT_A_TIME, ros2_simulation

pytestmark = ONE_GRAPH_AT_A_TIME

RELIABLE = QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE)
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
SCENARIO = """
robots:
  burger: {robot: burger}
  pioneer: {robot: pioneer, pose: {translation: [0, -1.5, 0]}}
"""
ROBOTS = ("burger", "pioneer")


@pytest.fixture(scope="module")
def probe(tmp_path_factory):
    path = tmp_path_factory.mktemp("ros2_robots") / "two.yaml"
    path.write_text(SCENARIO)
    with ros2_simulation([str(path), "--headless"], serve=False) as (_, probe):
        for robot in ROBOTS:
            probe.subscribe(f"/{robot}/robot_description", String, LATCHED)
            probe.subscribe(f"/{robot}/joint_states", JointState, RELIABLE)
            probe.subscribe(f"/{robot}/wheel_loads", WheelLoads, RELIABLE)
        probe.subscribe("/tf", TFMessage, RELIABLE)
        probe.subscribe("/burger/scan/scan", LaserScan, RELIABLE)
        probe.subscribe("/pioneer/ir/sonar_left_10", Range, RELIABLE)
        yield probe


@pytest.mark.parametrize("robot", ROBOTS)
def test_each_robot_is_its_own_on_ros2(probe, robot):
    spec = robot_spec(robot)
    description = probe.wait_for(f"/{robot}/robot_description")
    assert description.data == robot_urdf(spec, robot)
    joints = probe.wait_for(f"/{robot}/joint_states")
    assert list(joints.name) == list(spec.wheel_joints)
    loads = probe.wait_for(f"/{robot}/wheel_loads", lambda m: m.header.stamp.sec > 0 or
                           m.header.stamp.nanosec > 0)
    assert list(loads.wheel_names) == list(spec.wheel_names)
    assert sum(loads.load) > 0  # standing on its wheels
    tf = probe.wait_for("/tf")
    frames = {t.child_frame_id for t in tf.transforms if t.child_frame_id.startswith(robot)}
    assert frames == {f"{robot}/base_link", *(f"{robot}/{w.link}" for w in spec.wheels)}


def test_each_robot_s_sensors_are_on_their_topics(probe):
    scan = probe.wait_for("/burger/scan/scan")
    assert (scan.header.frame_id, len(scan.ranges)) == ("burger/lidar_scan", 360)
    sonar = probe.wait_for("/pioneer/ir/sonar_left_10")
    assert sonar.header.frame_id == "pioneer/ir_sonar_left_10" and sonar.max_range == 5.0
