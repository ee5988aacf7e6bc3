"""`--ros2` with several robots: each robot's names under `/<robot>/`, its frames prefixed
`<robot>/`, its commands its own. One simulation of scenarios/two_robots.yaml (scripts and
cameras off) for the module, in a private network (`ros2_probe`)."""

import math

import pytest

pytest.importorskip("rclpy", reason="the [ros2] extra (tools/setup installs it)")
pytest.importorskip("corobot_interfaces.msg", reason="python -m corobot_drake.ros2.build")

from corobot_interfaces.action import DriveDistance
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_srvs.srv import Trigger
from tf2_msgs.msg import TFMessage

from conftest import REPO
from ros2_probe import ONE_GRAPH_AT_A_TIME, ros2_simulation

pytestmark = ONE_GRAPH_AT_A_TIME

ROBOTS = ("corobot", "corobot_2")
QUIET = ("robots: {corobot: {commands: [], cameras: {front: {rgb: false}}}, "
         "corobot_2: {commands: [], cameras: {front: {rgb: false}}}}")
RELIABLE = QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE)
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)


@pytest.fixture(scope="module")
def probe():
    args = [str(REPO / "scenarios" / "two_robots.yaml"), "--headless", "--override", QUIET]
    with ros2_simulation(args, serve=False) as (_, probe):
        for robot in ROBOTS:
            probe.subscribe(f"/{robot}/odom", Odometry, RELIABLE)
        probe.subscribe("/tf", TFMessage, RELIABLE)
        probe.subscribe("/tf_static", TFMessage, LATCHED)
        for robot in ROBOTS:
            probe.wait_for(f"/{robot}/odom")
            probe.action_client(DriveDistance, f"/{robot}/drive_distance")  # discovered
        yield probe


def test_each_robot_has_its_namespace_and_frames(probe):
    names = dict(probe.node.get_topic_names_and_types())
    for robot in ROBOTS:
        assert names[f"/{robot}/odom"] == ["nav_msgs/msg/Odometry"]
        assert f"/{robot}/ir/front" in names and f"/{robot}/drive_state" in names
        odom = probe.messages[f"/{robot}/odom"][-1]
        assert (odom.header.frame_id, odom.child_frame_id) == (f"{robot}/odom",
                                                                f"{robot}/base_link")
    assert "/odom" not in names
    tf = probe.wait_for("/tf")
    pairs = {(t.header.frame_id, t.child_frame_id) for t in tf.transforms}
    for robot in ROBOTS:
        assert (f"{robot}/odom", f"{robot}/base_link") in pairs
        assert (f"{robot}/base_link", f"{robot}/front_left_wheel") in pairs
    static = probe.wait_for("/tf_static")
    joins = {(t.header.frame_id, t.child_frame_id) for t in static.transforms}
    assert {("world", f"{robot}/odom") for robot in ROBOTS} <= joins
    assert ("corobot_2/base_link", "corobot_2/ir_front") in joins
    # where the scenario puts them: corobot at the origin, corobot_2 at x = 2.4
    assert probe.messages["/corobot_2/odom"][-1].pose.pose.position.x == pytest.approx(
        2.4, abs=0.01)


def test_a_robots_commands_are_its_own(probe):
    publisher = probe.publisher("/corobot_2/cmd_vel", Twist)
    twist = Twist()
    twist.linear.x = 0.2
    start = {robot: probe.count(f"/{robot}/odom") for robot in ROBOTS}
    moving = None
    while moving is None:
        publisher.publish(twist)
        probe.wait_for("/corobot_2/odom", start=probe.count("/corobot_2/odom"))
        moving = next((m for m in probe.messages["/corobot_2/odom"][start["corobot_2"]:]
                       if m.twist.twist.linear.x > 0.15), None)
    still = probe.messages["/corobot/odom"][start["corobot"]:]
    assert still and all(math.hypot(m.twist.twist.linear.x, m.twist.twist.linear.y) < 1e-3
                         for m in still)
    response = probe.call("/corobot_2/all_stop", Trigger, Trigger.Request())
    assert response.success


def test_services_are_answered_while_every_robot_runs_a_goal(probe):
    """Each running goal holds one of the node's executor threads until its command ends:
    with both robots on a long drive, the node still answers a service at once (it has
    threads for every goal a robot can run and for the quick callbacks besides; with one
    thread per core, a 2-core machine's two were both taken until the drives ended)."""
    from rcl_interfaces.srv import GetParameters

    goals = [probe.wait_future(probe.action_client(DriveDistance, f"/{robot}/drive_distance")
                               .send_goal_async(DriveDistance.Goal(distance=2.0, power=0.3)))
             for robot in ROBOTS]  # ~10 s of driving each
    assert all(goal.accepted for goal in goals)
    answer = probe.call("/corobot_drake/get_parameters", GetParameters,
                        GetParameters.Request(names=["cmd_vel_timeout"]), timeout=5)
    assert answer.values[0].double_value > 0
    for goal in goals:
        probe.wait_future(goal.cancel_goal_async())
    results = [probe.wait_future(goal.get_result_async()) for goal in goals]
    assert not any(r.result.success for r in results)  # cancelled mid-drive: still running
