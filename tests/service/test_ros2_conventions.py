"""`--ros2` as a ROS 2 stack expects a node to be, from a separate process (`ros2_probe`, a
private network): `--ros-args` (a namespace remap, a params file, `-p`), the parameters' ranges
and their one-line refusals, /cmd_vel as TwistStamped and a publisher of the other type
reported, sensor topics that a reliable subscriber (RViz's default) receives, /diagnostics.
One headless simulation, its cameras off, without the HTTP services."""

import os
import subprocess
import sys
import threading

import pytest

pytest.importorskip("rclpy", reason="the [ros2] extra (tools/setup installs it)")
pytest.importorskip("corobot_interfaces.msg", reason="python -m corobot_drake.ros2.build")

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import DescribeParameters, GetParameters, SetParameters
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Range

from ros2_probe import (
    ONE_GRAPH_AT_A_TIME,
    WAIT,
    Probe,
    private_domain,
    private_network,
    ros2_simulation,
)

pytestmark = ONE_GRAPH_AT_A_TIME

NS = "/sim"
RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
QUIET = "robots: {corobot: {commands: [], cameras: {front: {rgb: false}}}}"


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    params = tmp_path_factory.mktemp("ros") / "params.yaml"  # as a launch file passes them
    params.write_text("/**:\n  ros__parameters:\n    cmd_vel_stamped: true\n")
    args = ["--headless", "--override", QUIET, "--ros-args", "-r", f"__ns:={NS}",
            "--params-file", str(params), "-p", "cmd_vel_timeout:=2", "--"]
    with ros2_simulation(args, serve=False) as (process, probe):
        lines, seen = [], threading.Condition()

        def read():
            for line in process.stderr:
                with seen:
                    lines.append(line.rstrip("\n"))
                    seen.notify_all()

        threading.Thread(target=read, daemon=True).start()
        probe.subscribe(f"{NS}/odom", Odometry, RELIABLE)
        probe.subscribe(f"{NS}/ir/front", Range, RELIABLE)  # RViz's default: reliable
        probe.subscribe("/diagnostics", DiagnosticArray, RELIABLE)
        probe.wait_for(f"{NS}/odom")  # discovered
        yield probe, lines, seen


def parameter(probe, name: str):
    answer = probe.call(f"{NS}/corobot_drake/get_parameters", GetParameters,
                        GetParameters.Request(names=[name]))
    return answer.values[0]


def set_parameter(probe, name: str, value: ParameterValue):
    answer = probe.call(f"{NS}/corobot_drake/set_parameters", SetParameters,
                        SetParameters.Request(parameters=[Parameter(name=name, value=value)]))
    return answer.results[0]


def test_ros_args_remap_the_namespace_and_set_parameters_checked_in_one_line(sim):
    probe, _, _ = sim
    timeout = parameter(probe, "cmd_vel_timeout")  # `-p cmd_vel_timeout:=2`: an integer
    assert (timeout.type, timeout.integer_value) == (ParameterType.PARAMETER_INTEGER, 2)
    assert parameter(probe, "cmd_vel_stamped").bool_value is True  # the params file's
    refused = set_parameter(probe, "cmd_vel_timeout", ParameterValue(
        type=ParameterType.PARAMETER_DOUBLE, double_value=-1.0))
    assert not refused.successful
    assert refused.reason == "cmd_vel_timeout: -1.0 is not a number of s in [0, 3600]"
    described = probe.call(f"{NS}/corobot_drake/describe_parameters", DescribeParameters,
                           DescribeParameters.Request(names=["cmd_vel_timeout"]))
    described = described.descriptors[0]
    assert described.additional_constraints == "a number of s in [0, 3600]"
    # the range in the descriptor's own fields too (`ros2 param describe`, rqt_reconfigure's
    # sliders), and still refused in the node's line, not rclpy's "out of range" words
    assert [(r.from_value, r.to_value) for r in described.floating_point_range] == [(0, 3600)]
    assert [(r.from_value, r.to_value) for r in described.integer_range] == [(0, 3600)]
    refused = set_parameter(probe, "cmd_vel_timeout", ParameterValue(
        type=ParameterType.PARAMETER_INTEGER, integer_value=4000))
    assert refused.reason == "cmd_vel_timeout: 4000 is not a number of s in [0, 3600]"
    # the node's clock is the simulation's /clock
    assert parameter(probe, "use_sim_time").bool_value is True
    taken = set_parameter(probe, "cmd_vel_timeout", ParameterValue(
        type=ParameterType.PARAMETER_INTEGER, integer_value=1))
    assert taken.successful, taken.reason
    read_only = set_parameter(probe, "sensor_qos", ParameterValue(
        type=ParameterType.PARAMETER_STRING, string_value="best_effort"))
    assert not read_only.successful  # read as the node starts


def test_the_simulation_interfaces_follow_the_namespace(sim):
    """Named relative to the node's namespace, as Gazebo's: `__ns:=/sim` moves them."""
    from simulation_interfaces.srv import GetSimulationState

    probe, _, _ = sim
    state = probe.call(f"{NS}/get_simulation_state", GetSimulationState,
                       GetSimulationState.Request())
    assert state.result.result == state.result.RESULT_OK
    services = {name for name, _ in probe.node.get_service_names_and_types()}
    assert {f"{NS}/spawn_entity", f"{NS}/simulate_steps/_action/send_goal"} <= services
    assert "/spawn_entity" not in services


def test_sensor_topics_reach_a_reliable_subscriber(sim):
    probe, _, _ = sim
    assert probe.wait_for(f"{NS}/ir/front").radiation_type == Range.INFRARED


def test_diagnostics_report_the_real_time_factor_and_each_robots_state(sim):
    probe, _, _ = sim
    array = probe.wait_for("/diagnostics", lambda m: any(
        s.name == "corobot_drake: simulation" and s.message.startswith("real-time factor")
        for s in m.status))
    status = {s.name: {v.key: v.value for v in s.values} for s in array.status}
    assert 0.3 < float(status["corobot_drake: simulation"]["realtime_factor"]) < 1.5  # 1x
    assert int(status["corobot_drake: simulation"]["slips"]) >= 0
    assert status["corobot_drake: corobot drive"] == {"stalls": "0"}
    assert set(status["corobot_drake: corobot wheel slip"]) == {
        "front_left", "front_right", "rear_left", "rear_right"}
    assert 20 < float(status["corobot_drake: corobot tip margin"]["tip_margin_deg"]) < 90
    assert array.header.stamp.sec + array.header.stamp.nanosec > 0  # simulation time


def test_twist_stamped_drives_and_a_twist_publisher_is_reported_once(sim):
    probe, lines, seen = sim
    stamped = probe.publisher(f"{NS}/cmd_vel", TwistStamped)
    command = TwistStamped()
    command.header.frame_id = "base_link"
    command.twist.linear.x = 0.3
    for _ in range(500):  # at most 10 s of /odom (50 Hz)
        stamped.publish(command)
        odom = probe.wait_for(f"{NS}/odom", start=probe.count(f"{NS}/odom"))
        if odom.twist.twist.linear.x > 0.1:
            break
    else:
        raise AssertionError("a TwistStamped on /cmd_vel did not move the robot")
    other = Probe(int(os.environ["ROS_DOMAIN_ID"]), name="plain_teleop")  # a node of its own:
    try:  # one DDS participant cannot offer both types on one topic
        other.publisher(f"{NS}/cmd_vel", Twist).publish(Twist())  # the other type
        wanted = "publishes geometry_msgs/Twist, this node takes geometry_msgs/TwistStamped"
        with seen:
            assert seen.wait_for(lambda: any(wanted in line for line in lines), WAIT), lines
        probe.wait_for(f"{NS}/odom", start=probe.count(f"{NS}/odom") + 250)  # 2 more looks
    finally:
        other.close()
    with seen:
        assert sum(wanted in line for line in lines) == 1  # once, not at every look


@pytest.mark.parametrize(("parameter", "line"), [
    ("odom_source:=gps", "odom_source: 'gps' is not one of wheel, ground_truth"),
    # out of the descriptor's integer_range: the node's line, not rclpy's
    ("cmd_vel_timeout:=-1", "cmd_vel_timeout: -1 is not a number of s in [0, 3600]")])
def test_a_bad_parameter_at_start_is_one_line_and_exit_2(parameter, line):
    with private_network():
        run = subprocess.run(
            [sys.executable, "-m", "corobot_drake", "--headless", "--ros2", "--duration", "1",
             "--ros-args", "-p", parameter], capture_output=True, text=True, timeout=120)
    assert run.returncode == 2
    assert run.stderr.strip().splitlines() == [f"error: --ros-args: {line}"]


def test_a_live_runs_closing_line_says_the_rate_it_went_at():
    """The closing line of a --ros2 run gives the measured rate (simulated over wall-clock s,
    paced at 1x real time), not the compute time's factor (this quiet scene headless: ~9x)."""
    import re

    with private_domain():
        run = subprocess.run(
            [sys.executable, "-m", "corobot_drake", "--headless", "--override", QUIET,
             "--ros2", "--duration", "1"], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    line = run.stdout.strip().splitlines()[-1]
    factor = re.fullmatch(r"simulated 1\.00 s at ([0-9.]+)x real time", line)
    assert factor, line
    assert 0.7 <= float(factor[1]) <= 1.05, line  # paced: at most a slip's worth off 1x


def test_action_feedback_comes_every_tenth_of_a_simulated_second_at_any_rate():
    """At 4x real time a drive's feedback still comes every 0.1 s of simulated time (paced
    on the wall clock, it came every 0.4 s of it)."""
    from corobot_interfaces.action import DriveDistance
    from rosgraph_msgs.msg import Clock

    with ros2_simulation(["--headless", "--override", QUIET, "--rate", "4"],
                         serve=False) as (_, probe):
        probe.subscribe("/clock", Clock, RELIABLE)
        probe.wait_for("/clock")
        client = probe.action_client(DriveDistance, "/drive_distance")
        feedback = []
        start = probe.wait_for("/clock", start=probe.count("/clock")).clock
        handle = probe.wait_future(client.send_goal_async(
            DriveDistance.Goal(distance=0.5, power=0.5),
            feedback_callback=lambda f: feedback.append(f.feedback.remaining)))
        assert probe.wait_future(handle.get_result_async()).result.success
        end = probe.wait_for("/clock", start=probe.count("/clock")).clock
    simulated = (end.sec - start.sec) + 1e-9 * (end.nanosec - start.nanosec)
    # every 0.1 s of the drive; its start and end lie within the span measured
    assert 0.6 * simulated / 0.1 < len(feedback) <= simulated / 0.1 + 1, (simulated, feedback)
