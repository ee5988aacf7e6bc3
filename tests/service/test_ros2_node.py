"""`--ros2` held to its contract from a separate process, as a user's node would hold it: the
topics' types and values against the simulation (its HTTP services: `robot.pose()`,
`robot.ir()`...), /cmd_vel and the deadman, the actions, the services. One simulation for
the module (real time, headless, with `--serve` beside it), in a private network
(`ros2_probe`)."""

import contextlib
import inspect
import math
import re
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
import yaml

pytest.importorskip("rclpy", reason="the [ros2] extra (tools/setup installs it)")
pytest.importorskip("corobot_interfaces.msg", reason="python -m corobot_drake.ros2.build")

from corobot_interfaces.action import DriveDistance, RotateDegrees
from corobot_interfaces.msg import DriveState, TipMargin, WheelLoads, WheelSlip
from corobot_interfaces.srv import SetPose
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image, JointState, Range
from std_msgs.msg import String
from std_srvs.srv import SetBool, Trigger
from tf2_msgs.msg import TFMessage

from corobot_drake.config.sensors import default_camera_config, default_ir_sensors
from corobot_drake.robots import robot_spec
from corobot_drake.serving.client import CorobotClient
from corobot_drake.serving.runner import SimRunner
from ros2_probe import ONE_GRAPH_AT_A_TIME, ros2_simulation

pytestmark = ONE_GRAPH_AT_A_TIME

_runner_defaults = inspect.signature(SimRunner).parameters
SNAPSHOT_LAG = (_runner_defaults["snapshot_period"].default
                + _runner_defaults["max_step"].default)
"""s: how far the HTTP side's simulated time (its latest snapshot's) may lag the simulation."""
SPEC, IR, CAMERA = robot_spec("corobot"), default_ir_sensors(), default_camera_config()
"""The Corobot as its robot file and model say: its spec, IR sensors and camera."""
POSE_TOLERANCE = 1e-3
"""m: /ground_truth against the simulation's pose (the issue's 1 mm; the same pose, so
~1e-12)."""
SETTLED_ODOMETRY = 0.01
"""m: /odom (the dead reckoning, put at the pose by the teleport) against the pose once the
robot has settled there: the wheels' roll while it settles is all it counts."""
RELIABLE = QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE)
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
TOPICS = {
    "/clock": (Clock, RELIABLE), "/odom": (Odometry, RELIABLE),
    "/ground_truth": (Odometry, RELIABLE),
    "/wheel_odom": (Odometry, RELIABLE), "/joint_states": (JointState, RELIABLE),
    "/tf": (TFMessage, RELIABLE), "/tf_static": (TFMessage, LATCHED),
    "/robot_description": (String, LATCHED), "/ir/front": (Range, None),
    "/ir/rear": (Range, None), "/camera/image_raw": (Image, None),
    "/camera/camera_info": (CameraInfo, None), "/drive_state": (DriveState, RELIABLE),
    "/wheel_loads": (WheelLoads, RELIABLE), "/wheel_slip": (WheelSlip, RELIABLE),
    "/tip_margin": (TipMargin, RELIABLE),
}
"""Every topic and the QoS the probe asks for (None: the sensor-data profile)."""


@pytest.fixture(scope="module")
def ros():
    with ros2_simulation(["--headless", "--camera-rate", "10"]) as (server, probe):
        for topic, (msgtype, qos) in TOPICS.items():
            probe.subscribe(topic, msgtype, qos)
        probe.wait_for("/clock")  # discovered
        for kind, name in ((DriveDistance, "/drive_distance"), (RotateDegrees, "/rotate_degrees")):
            probe.action_client(kind, name)  # discovered both ways before the first goal
        probe.client("/set_pose", SetPose)  # and before the first pose
        client = CorobotClient(server.url)
        yield probe, client, client.robot()
        client.close()


def stamp(msg) -> float:
    s = msg.header.stamp if hasattr(msg, "header") else msg.clock
    return s.sec + 1e-9 * s.nanosec


def yaw_of(q) -> float:
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y**2 + q.z**2))


def set_pose(probe, x, y, yaw):
    return probe.call("/set_pose", SetPose, SetPose.Request(x=x, y=y, yaw=yaw), retry=None)


def at_rest(probe, after: float) -> Odometry:
    """The first /odom stamped after `after` (s) with the robot at rest."""
    return probe.wait_for("/odom", lambda m: stamp(m) > after and abs(
        m.twist.twist.linear.x) < 1e-3 and abs(m.twist.twist.angular.z) < 1e-3)


def test_every_topic_is_published_with_its_type(ros):
    probe, _, _ = ros
    for topic in TOPICS:
        probe.wait_for(topic)
    names = dict(probe.node.get_topic_names_and_types())
    assert names["/odom"] == ["nav_msgs/msg/Odometry"]
    assert names["/drive_state"] == ["corobot_interfaces/msg/DriveState"]


def test_odom_is_the_simulated_pose(ros):
    probe, client, robot = ros
    response = set_pose(probe, 0.4, -0.3, math.radians(30))
    assert response.success, response.reason
    rest = at_rest(probe, client.time)
    pose = robot.pose()  # at rest, the same pose whenever read
    truth = probe.wait_for("/ground_truth", lambda m: stamp(m) == stamp(rest))
    g, q = truth.pose.pose.position, truth.pose.pose.orientation
    assert abs(g.x - pose.x) < POSE_TOLERANCE and abs(g.y - pose.y) < POSE_TOLERANCE
    assert abs(g.x - 0.4) < 0.01 and abs(g.y + 0.3) < 0.01  # where it was put (settled)
    assert abs(yaw_of(q) - pose.yaw) < 1e-3 and truth.header.frame_id == "world"
    # /odom: the wheel odometry, which the teleport put there too
    p = rest.pose.pose.position
    assert math.hypot(p.x - pose.x, p.y - pose.y) < SETTLED_ODOMETRY
    assert abs(yaw_of(rest.pose.pose.orientation) - pose.yaw) < 0.01
    assert rest.pose.covariance[0] > 0 and rest.twist.covariance[0] > 0
    assert rest.header.frame_id == "odom" and rest.child_frame_id == "base_link"
    # /tf's odom -> base_link is the same transform, at the same stamps
    tf = probe.wait_for("/tf", lambda m: stamp(m.transforms[0]) == stamp(rest))
    t = {(x.header.frame_id, x.child_frame_id): x.transform for x in tf.transforms}
    base = t[("odom", "base_link")]
    assert (base.translation.x, base.translation.y) == pytest.approx((p.x, p.y), abs=1e-12)
    for wheel in SPEC.wheels:  # the wheels' frames at their axles' places
        w = t[("base_link", f"{wheel.short}_wheel")].translation
        assert (w.x, w.y, w.z) == pytest.approx(wheel.center, abs=2e-3)


def test_tf_static_and_robot_description(ros):
    probe, _, _ = ros
    static = probe.wait_for("/tf_static")
    t = {x.child_frame_id: x for x in static.transforms}
    assert {t[c].header.frame_id for c in ("camera_link", "ir_front", "ir_rear")} == {
        "base_link"}
    assert t["camera_optical_frame"].header.frame_id == "camera_link"
    front = t["ir_front"].transform.translation
    assert (front.x, front.y, front.z) == pytest.approx(IR["front"].X_PB.translation, abs=1e-9)
    rear = t["ir_rear"].transform.rotation
    assert abs(abs(yaw_of(rear)) - math.pi) < 1e-9  # it looks backwards
    urdf = probe.wait_for("/robot_description").data
    assert "<robot" in urdf and all(f'"{w}_axle"' in urdf for w in SPEC.wheel_names)


def test_range_is_the_ir_reading(ros):
    probe, _, robot = ros
    for sensor in ("front", "rear"):
        reading = robot.ir(sensor)
        msg = probe.wait_for(f"/ir/{sensor}", lambda m, t=reading.time: abs(stamp(m) - t) < 1e-6)
        nothing = reading.raw >= reading.range  # REP 117: +Inf
        assert msg.range == (math.inf if nothing else pytest.approx(reading.raw, abs=1e-6))
        assert msg.radiation_type == Range.INFRARED and msg.header.frame_id == f"ir_{sensor}"
        assert msg.max_range == pytest.approx(reading.range, rel=1e-6)
        assert msg.min_range <= msg.range and (nothing or msg.range <= msg.max_range + 1e-6)
        assert msg.field_of_view == pytest.approx(math.radians(IR[sensor].dispersion_cone_angle))


def test_camera_image_and_info(ros):
    probe, _, robot = ros
    frame = robot.camera_image()  # with its capture time
    image = probe.wait_for("/camera/image_raw",
                           lambda m: abs(stamp(m) - robot._last_frame_time) < 1e-6)
    assert (image.width, image.height, image.encoding) == (CAMERA.width, CAMERA.height,
                                                           "rgb8")
    assert image.step == 3 * image.width and image.header.frame_id == "camera_optical_frame"
    pixels = np.frombuffer(bytes(image.data), np.uint8).reshape(image.height, image.width, 3)
    np.testing.assert_array_equal(pixels, frame[:, :, :3])  # the same frame (PNG: lossless)
    info = probe.wait_for("/camera/camera_info", lambda m: stamp(m) == stamp(image))
    assert (info.width, info.height) == (image.width, image.height)
    fy = CAMERA.height / 2 / math.tan(math.radians(CAMERA.focal.y) / 2)
    assert info.k[4] == pytest.approx(fy) and info.k[8] == 1.0


def test_clock_is_the_simulation_time(ros):
    probe, client, _ = ros
    before = client.time
    tick = probe.wait_for("/clock", lambda m: stamp(m) >= before)
    # Published as the simulation passed it: the HTTP side's time is its latest snapshot's,
    # at most a snapshot period and a step behind.
    assert stamp(tick) <= client.time + SNAPSHOT_LAG
    # Every 10 ms of simulated time. The node keeps the last 10 messages for a late reliable
    # reader (DDS's KEEP_LAST), so a probe stalled on a loaded machine may miss some: the
    # stamps received must stand on the 10 ms grid, in order, nearly all one step apart.
    probe.wait_for("/clock", start=40)  # 41 messages at least
    steps = np.diff([stamp(m) for m in probe.messages["/clock"][-40:]]) / 0.01
    whole = np.rint(steps)
    assert np.allclose(steps, whole, atol=1e-6) and whole.min() >= 1
    assert np.count_nonzero(whole == 1) >= 0.8 * len(steps)
    # /odom is stamped with a step's simulation time, on /clock's grid to the nanosecond (not
    # matched to a /clock message received: a stalled probe may have missed that one).
    odom = probe.wait_for("/odom", lambda m: stamp(m) >= before)
    assert (odom.header.stamp.sec * 10**9 + odom.header.stamp.nanosec) % 10_000_000 == 0


def test_cmd_vel_drives_and_the_deadman_stops(ros):
    probe, client, robot = ros
    assert set_pose(probe, 0.0, 0.0, 0.0).success
    publisher = probe.publisher("/cmd_vel", Twist)
    twist = Twist()
    twist.linear.x = 0.2
    start = probe.count("/odom")
    moving = None
    while moving is None:  # a user's teleop: Twists until the robot goes
        publisher.publish(twist)
        moving = next((m for m in probe.messages["/odom"][start:]
                       if m.twist.twist.linear.x > 0.15), None)
        if moving is None:
            probe.wait_for("/odom", start=probe.count("/odom"))
    last_twist = client.time  # the Twists stop here
    stopped = at_rest(probe, last_twist)
    assert stamp(stopped) > last_twist + 0.5 - 0.05  # not before the deadman's 0.5 s
    assert robot.command_log()[-1]["command"] == "AllStop"
    assert stopped.pose.pose.position.x > 0.05  # it drove meanwhile


def action(probe, kind, name, **goal):
    client = probe.action_client(kind, name)
    feedback = []
    handle = probe.wait_future(client.send_goal_async(
        kind.Goal(**goal), feedback_callback=lambda f: feedback.append(f.feedback)))
    assert handle.accepted
    return client, handle, feedback


def test_drive_distance_succeeds_with_feedback(ros):
    probe, _client, robot = ros
    assert set_pose(probe, 0.0, 0.0, 0.0).success
    start = robot.pose()
    _, handle, feedback = action(probe, DriveDistance, "/drive_distance", distance=0.3,
                                 power=0.5)
    result = probe.wait_future(handle.get_result_async()).result
    assert result.success and result.reason == ""
    end = robot.pose()
    assert math.hypot(end.x - start.x, end.y - start.y) == pytest.approx(0.3, abs=0.02)
    remaining = [f.remaining for f in feedback]
    assert remaining and remaining[0] > remaining[-1] >= 0.0 and remaining[0] <= 0.3


def test_rotate_degrees_succeeds_and_a_disabled_drive_fails(ros):
    probe, _, robot = ros
    start = robot.pose().yaw
    _, handle, _ = action(probe, RotateDegrees, "/rotate_degrees", degrees=45.0, power=0.5)
    result = probe.wait_future(handle.get_result_async()).result
    assert result.success
    turned = math.degrees(math.remainder(robot.pose().yaw - start, 2 * math.pi))
    assert turned == pytest.approx(45.0, abs=3.0)
    assert probe.call("/enable_drive", SetBool, SetBool.Request(data=False)).success
    probe.wait_for("/drive_state", lambda m: not m.is_enabled)
    _, handle, _ = action(probe, DriveDistance, "/drive_distance", distance=0.3, power=0.5)
    result = probe.wait_future(handle.get_result_async()).result
    assert not result.success and result.reason == "disabled"
    assert probe.call("/enable_drive", SetBool, SetBool.Request(data=True)).success
    probe.wait_for("/drive_state", lambda m: m.is_enabled, start=probe.count("/drive_state"))


def test_a_bad_goal_is_rejected_as_it_is_sent(ros):
    probe, _, _ = ros
    client = probe.action_client(DriveDistance, "/drive_distance")
    handle = probe.wait_future(client.send_goal_async(DriveDistance.Goal(distance=0.3,
                                                                         power=7.0)))
    assert not handle.accepted


def test_cancel_stops_and_a_newer_command_supersedes(ros):
    probe, client, robot = ros
    assert set_pose(probe, 0.0, 0.0, 0.0).success
    _, handle, _feedback = action(probe, DriveDistance, "/drive_distance", distance=5.0,
                                 power=0.5)
    probe.wait_for("/odom", lambda m: m.twist.twist.linear.x > 0.1)
    probe.wait_future(handle.cancel_goal_async())
    result = probe.wait_future(handle.get_result_async())
    assert result.status == 5 and result.result.reason == "canceled"  # GoalStatus CANCELED
    at_rest(probe, client.time)
    assert robot.pose().x < 4.0  # stopped long before the goal
    _, first, _ = action(probe, DriveDistance, "/drive_distance", distance=-2.0, power=0.5)
    probe.wait_for("/odom", lambda m: m.twist.twist.linear.x < -0.1)
    _, second, _ = action(probe, RotateDegrees, "/rotate_degrees", degrees=20.0, power=0.5)
    superseded = probe.wait_future(first.get_result_async())
    assert superseded.status == 6 and superseded.result.reason == "superseded"  # ABORTED
    assert probe.wait_future(second.get_result_async()).result.success


def test_services_act(ros):
    probe, client, robot = ros
    blocked = set_pose(probe, -1.8, 0.0, 0.0)  # inside the giant box
    assert not blocked.success and blocked.reason == "blocked"
    response = probe.call("/all_stop", Trigger, Trigger.Request())
    assert response.success, response.message
    # The answer means accepted: the command source logs the AllStop at its next update.
    seq = int(re.fullmatch(r"AllStop issued \(seq (\d+), t = [\d.]+ s\)", response.message)[1])
    deadline = time.monotonic() + 30
    while not [r for r in robot.command_log() if r["seq"] == seq]:
        assert time.monotonic() < deadline, "the AllStop was never logged"
        time.sleep(0.05)
    assert [r["command"] for r in robot.command_log() if r["seq"] == seq] == ["AllStop"]
    assert set_pose(probe, 0.2, 0.5, -1.0).success
    rest = at_rest(probe, client.time)
    assert rest.pose.pose.position.y == pytest.approx(0.5, abs=0.01)
    assert yaw_of(rest.pose.pose.orientation) == pytest.approx(-1.0, abs=0.01)


def test_a_bad_yaw_is_named_in_rad(ros):
    probe, _, _ = ros
    response = set_pose(probe, 0.0, 0.0, 100.0)
    assert not response.success
    assert response.reason == "yaw: must be in [-62.8319, 62.8319] rad; got 100"


def test_a_burst_of_service_calls_is_answered_in_full(ros):
    """200 calls at once from one client: each answered (the requests wait in the service's
    queue while the executor takes them one by one; ROS's default keeps 10). The client keeps
    as many answers (its own queue: the probe's executor is busy with the topics)."""
    from ros2_probe import RETRY

    probe, _, _ = ros
    deep = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    client = probe.node.create_client(Trigger, "/all_stop", qos_profile=deep)
    assert client.wait_for_service(timeout_sec=60)
    for _ in range(6):  # each side has discovered the other once one call is answered
        first = client.call_async(Trigger.Request())
        with contextlib.suppress(AssertionError):
            probe.wait_future(first, RETRY)
            break
        client.remove_pending_request(first)
    futures = [client.call_async(Trigger.Request()) for _ in range(200)]
    answers = [probe.wait_future(f) for f in futures]
    assert all(a.success for a in answers)
    assert len({a.message for a in answers}) == 200  # each its own AllStop


def inspect_topics(*commands: list[str]) -> list[subprocess.CompletedProcess]:
    """`python -m corobot_drake.ros2 ARGS` for each of `commands`, as a user runs it, all at
    once: each a process (and so a DDS participant) of its own, in this test's network and
    domain."""
    processes = [subprocess.Popen([sys.executable, "-m", "corobot_drake.ros2", *args],
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                 for args in commands]
    done = []
    try:
        for process in processes:
            out, err = process.communicate(timeout=180)
            done.append(subprocess.CompletedProcess(process.args, process.returncode, out, err))
    finally:
        for process in processes:
            if process.poll() is None:
                process.kill()
                process.wait()
    return done


def test_the_inspection_tool_lists_echoes_and_counts(ros):
    listed, echo, hz, missing, once = inspect_topics(
        ["list"], ["echo", "/ir/rear", "-n", "1", "--timeout", "60"],
        ["hz", "/clock", "-n", "30", "--timeout", "60"],
        ["--wait", "1", "echo", "/no_such_topic"],
        ["hz", "/robot_description", "--timeout", "3"])  # latched: one message
    assert listed.returncode == 0, listed.stderr
    assert "  /odom [nav_msgs/msg/Odometry]" in listed.stdout
    assert "  /set_pose [corobot_interfaces/srv/SetPose]" in listed.stdout
    assert "  /drive_distance\n" in listed.stdout and "  /rotate_degrees\n" in listed.stdout
    assert echo.returncode == 0, echo.stderr
    echoed = yaml.safe_load(echo.stdout.split("---")[0])  # a best-effort stream, read
    assert echoed["header"]["frame_id"] == "ir_rear" and echoed["radiation_type"] == 1
    assert hz.returncode == 0, hz.stderr
    # Every 10 ms of its stamps: the closest two (a best-effort stream may drop some under
    # load, which lowers the mean rate, never raises it).
    report = hz.stdout.splitlines()[-1]
    assert report.endswith("over 30 messages, stamps 10.0 ms apart at the closest")
    assert float(report.split(", ")[1].split()[0]) <= 100.0 + 1e-9
    assert missing.returncode == 1
    assert missing.stderr.startswith("error: no topic /no_such_topic found in 1 s")
    assert (once.returncode, once.stderr.splitlines()[-1]) == (
        1, "error: 1 message(s) on /robot_description in 3 s (2 needed)")


def test_the_deadman_is_a_parameter(ros):
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import GetParameters, SetParameters

    probe, _, _ = ros
    got = probe.call("/corobot_drake/get_parameters", GetParameters,
                     GetParameters.Request(names=["cmd_vel_timeout"]))
    assert got.values[0].double_value == 0.5

    def set_to(value):
        request = SetParameters.Request(parameters=[Parameter(
            name="cmd_vel_timeout", value=ParameterValue(type=ParameterType.PARAMETER_DOUBLE,
                                                         double_value=value))])
        return probe.call("/corobot_drake/set_parameters", SetParameters, request).results[0]

    refused = set_to(-1.0)
    assert not refused.successful and "cmd_vel_timeout" in refused.reason
    assert set_to(0.5).successful


def test_the_node_goes_on_serving_after_a_callback_fails(caplog):
    """rclpy re-raises a callback's exception from `spin` (e.g. the RCLError of a response
    Fast DDS could not send): the node's thread logs it and spins on, until it is closed."""
    import threading

    from rclpy.executors import ExternalShutdownException

    from corobot_drake.ros2.node import spin_until_closed

    class Executor:
        def __init__(self, outcomes):
            self.outcomes, self.spins = list(outcomes), 0

        def spin(self):
            self.spins += 1
            outcome = self.outcomes.pop(0)
            if outcome is not None:
                raise outcome

    failing = Executor([RuntimeError("failed to send response"), RuntimeError("again"), None])
    spin_until_closed(failing, threading.Event())
    assert failing.spins == 3  # spun again after each failure, returned when spin returned
    assert caplog.text.count("a ROS 2 callback failed; the node goes on serving") == 2
    shut_down = Executor([ExternalShutdownException()])
    spin_until_closed(shut_down, threading.Event())
    assert shut_down.spins == 1
    closed = threading.Event()
    closed.set()
    never = Executor([])
    spin_until_closed(never, closed)
    assert never.spins == 0


def test_a_namesake_is_warned_about_and_a_goal_running_at_the_stop_is_aborted():
    """A simulation of its own (cameras off): a second node named corobot_drake joins its
    domain (warned about on stderr); then the simulation is stopped (Ctrl-C) during a long
    drive, whose goal ends aborted, with the reason."""
    import os
    import signal
    import threading

    from corobot_drake.ros2.node import NODE_STOPPED
    from ros2_probe import WAIT, Probe

    quiet = "robots: {corobot: {commands: [], cameras: {front: {rgb: false}}}}"
    with ros2_simulation(["--headless", "--override", quiet], serve=False) as (sim, probe):
        lines, seen = [], threading.Condition()

        def read():
            for line in sim.stderr:
                with seen:
                    lines.append(line.rstrip("\n"))
                    seen.notify_all()

        threading.Thread(target=read, daemon=True).start()
        probe.action_client(DriveDistance, "/drive_distance")  # discovered long before the goal
        domain = int(os.environ["ROS_DOMAIN_ID"])  # the simulation's (`ros2_simulation`)
        namesake = Probe(domain, name="corobot_drake")
        try:
            with seen:
                assert seen.wait_for(lambda: any(
                    line.startswith("warning: ROS 2: 2 nodes named /corobot_drake in "
                                    f"ROS_DOMAIN_ID {domain}: ") for line in lines), WAIT), lines
        finally:
            namesake.close()
        _, handle, _ = action(probe, DriveDistance, "/drive_distance", distance=5.0, power=0.3)
        result = handle.get_result_async()
        sim.send_signal(signal.SIGINT)
        try:
            stopped = probe.wait_future(result)
        except AssertionError:
            raise AssertionError(f"no result; the simulation said {lines}") from None
        assert (stopped.status, stopped.result.reason) == (6, NODE_STOPPED)  # ABORTED
        assert not stopped.result.success


@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                    reason="signal handlers are set, and run, in the main thread only")
def test_a_stop_signal_as_a_live_run_ends_lets_its_outputs_finish(monkeypatch):
    """Ctrl-C as a --ros2 run reaches its end, before its outputs are begun (here `finish`'s
    first act, in the simulation thread, which takes the signal): the main thread hears it
    within a slice (`runner.wait_for`), waits on for `finish` to end and returns its status.
    The KeyboardInterrupt used to leave `run_live` instead (the outputs cut short when the
    process ended under the simulation thread; "stopped before the run started")."""
    import signal
    import types

    from corobot_drake import cli
    from corobot_drake.config.scenario import load_scenario
    from corobot_drake.resources import DEFAULT_SCENARIO
    from corobot_drake.ros2.run import run_live
    from corobot_drake.serving.runner import SIGNAL_WAIT
    from corobot_drake.simulation import Simulation

    scenario = load_scenario(DEFAULT_SCENARIO, overrides=[
        "robots: {corobot: {commands: [], cameras: {front: {rgb: false}}}}"])
    written = []

    def finish(sim):
        signal.raise_signal(signal.SIGINT)  # to this thread: its handler runs in the main one
        time.sleep(3 * SIGNAL_WAIT)  # the outputs being written; the main thread hears it
        written.append(sim.time)
        return cli.stopped_status()

    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    switch = sys.getswitchinterval()
    monkeypatch.setattr(cli, "STOPPED_BY", None)
    cli.ctrl_c_stops()
    try:
        status = run_live(types.SimpleNamespace(attach=lambda runner: None),
                          lambda meshcat: Simulation(scenario), meshcat=False, duration=0.2,
                          run_log_window=None, finish=finish)
    finally:
        for signum, handler in before.items():
            signal.signal(signum, handler)
        sys.setswitchinterval(switch)
    assert cli.STOPPED_BY == signal.SIGINT  # heard, while `finish` ran
    assert status == 130 and len(written) == 1 and written[0] >= 0.2 - 1e-9


def test_sigterm_stops_a_ros2_run_and_writes_its_outputs(tmp_path):
    """SIGTERM (`kill`, a service manager) to a headless --ros2 run once it runs: it stops
    at once, saying so, writes the summary of the run so far, and exits 128 + 15."""
    import json
    import signal

    summary = tmp_path / "summary.json"
    quiet = "robots: {corobot: {commands: [], cameras: {front: {rgb: false}}}}"
    with ros2_simulation(["--headless", "--override", quiet, "--summary", str(summary)],
                         serve=False) as (sim, probe):
        probe.subscribe("/clock", Clock, RELIABLE)
        # Under way: 0.1 s simulated (t = 0 is published as the simulation is built, and a
        # signal then stops it before the run started, with nothing to write).
        probe.wait_for("/clock", lambda m: stamp(m) >= 0.1)
        sim.send_signal(signal.SIGTERM)
        start = time.monotonic()
        _, err = sim.communicate(timeout=30)
        stopped_in = time.monotonic() - start
    assert sim.returncode == 128 + signal.SIGTERM, err
    assert "\nstopped\n" in err, err
    assert json.loads(summary.read_text())["time"] > 0
    # The stop, the summary and the node's shutdown take well under a second on an idle
    # machine; 10 s leaves room for a loaded one, far below the 30 s of a lost signal.
    assert stopped_in < 10.0, stopped_in


def test_a_simulate_steps_goal_running_at_the_stop_is_aborted_with_the_reason():
    """Paused, then a SimulateSteps goal of a million steps under way when the simulation is
    stopped (Ctrl-C): its result still goes out, aborted, saying the simulation or the node
    stopped (the node waits for it as for a robot's goal, counted from its acceptance)."""
    import signal

    from simulation_interfaces.action import SimulateSteps
    from simulation_interfaces.msg import SimulationState
    from simulation_interfaces.srv import SetSimulationState

    from ros2_probe import WAIT

    quiet = "robots: {corobot: {commands: [], cameras: {front: {rgb: false}}}}"
    with ros2_simulation(["--headless", "--override", quiet], serve=False) as (sim, probe):
        pause = probe.node.create_client(SetSimulationState, "/set_simulation_state")
        assert pause.wait_for_service(timeout_sec=WAIT)
        paused = probe.wait_future(pause.call_async(SetSimulationState.Request(
            state=SimulationState(state=SimulationState.STATE_PAUSED))))
        assert paused.result.result == 1
        client = probe.action_client(SimulateSteps, "/simulate_steps")
        handle = probe.wait_future(client.send_goal_async(SimulateSteps.Goal(steps=1_000_000)))
        assert handle.accepted
        result = handle.get_result_async()
        sim.send_signal(signal.SIGINT)
        stopped = probe.wait_future(result)
        said = stopped.result.result.error_message
        assert stopped.status == 6  # ABORTED
        # The simulation stops first (its thread ends, or has ended) or the node does: it says.
        assert any(words in said for words in ("the simulation stopped",
                                               "the simulation is not running",
                                               "the node stopped")), said
