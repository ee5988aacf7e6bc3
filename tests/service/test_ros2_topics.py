"""The ROS 2 front end without DDS: the interface files against the tables they come from,
the URDF against the SDF, each publisher alone (its CDR decoded by rclpy's own type support),
a rosbag2 written by `--rosbag` read back, and the one-line errors of the flags."""

import dataclasses as dc
import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("rosbags", reason="the [ros2] extra (tools/setup installs it)")
pytest.importorskip("rclpy", reason="the [ros2] extra (tools/setup installs it)")
pytest.importorskip("corobot_interfaces.msg", reason="python -m corobot_drake.ros2.build")

from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.math import SpatialVelocity
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant
from rclpy.serialization import deserialize_message

from conftest import Stepper
from corobot_drake import cli
from corobot_drake import topics as tp
from corobot_drake.config import scenario as sc
from corobot_drake.config.sensors import IrSensorConfig
from corobot_drake.model.sdf import corobot_sdf
from corobot_drake.resources import make_parser
from corobot_drake.robots import robot_spec
from corobot_drake.ros2 import interfaces as ifc
from corobot_drake.ros2.bus import Bus
from corobot_drake.ros2.graph import configure_discovery, ros_type
from corobot_drake.ros2.publishers import (
    ClockPublisher,
    RobotStatePublisher,
    StaticPublisher,
    TelemetryPublisher,
    TransformPublisher,
)
from corobot_drake.ros2.urdf import corobot_urdf
from corobot_drake.sensors.ir_sensor import DISTANCE, SCAN_TIME, scan_state_layout
from corobot_drake.systems.odometry import DriveState, WheelState
from corobot_drake.systems.odometry_error import error_model

SPEC = robot_spec("corobot")
"""The Corobot as its robot file and model say."""


class Memory:
    """A bus sink that keeps every message: {topic: [(t_ns, decoded message)]}."""

    def __init__(self):
        self.types, self.messages = {}, {}

    def declare(self, topic, msgtype, qos):
        self.types[topic] = msgtype
        self.messages[topic] = []

    def write(self, topic, data, t_ns):
        msg = deserialize_message(bytes(data), ros_type(self.types[topic]))
        self.messages[topic].append((t_ns, msg))


def _fields(path: Path) -> list[str]:
    """The field names of a .msg file (or one section of a .srv/.action)."""
    return [line.split()[1] for line in path.read_text().splitlines()
            if line.strip() and not line.startswith("#") and line != "---"]


def _sections(path: Path) -> list[list[str]]:
    return [[line.split()[1] for line in part.splitlines() if line.strip()
             and not line.startswith("#")] for part in path.read_text().split("\n---\n")]


# --- the interfaces against their sources ---


def test_telemetry_messages_and_actions_are_written_from_their_tables():
    for path, text in {**ifc.telemetry_files(), **ifc.action_files()}.items():
        assert path.read_text() == text, f"run python -m corobot_drake.ros2.interfaces ({path})"


def test_actions_are_the_scenario_commands():
    folder = ifc.INTERFACES_DIR / ifc.PACKAGE / "action"
    for action in ifc.ACTIONS:
        goal, result, feedback = _sections(folder / f"{action.type.split('/')[-1]}.action")
        assert goal == list(ifc.goal_fields(action.command))
        assert result == ["success", "reason"] and feedback == [action.feedback]
    request, response = _sections(ifc.INTERFACES_DIR / ifc.PACKAGE / "srv" / "SetPose.srv")
    assert request == [f.name.removesuffix("_deg") for f in dc.fields(sc.SetPose)]
    assert response == ["success", "reason"]


def test_the_commands_interfaces_are_the_command_tables_ros2_column():
    """One mapping: the node's topic, actions and services, and docs/ros2.md's table of them
    (generated at the site's build), are what `commands.COMMANDS` declares (no list of their
    own)."""
    from corobot_drake import commands

    declared = {(s.ros2.kind, s.ros2.name, s.ros2.type) for s in commands.COMMANDS.values()
                if s.ros2 is not None}
    served = ({("topic", f"/{ifc.CMD_VEL[0]}", ifc.CMD_VEL[1])}
              | {("action", f"/{a.name}", a.type) for a in ifc.ACTIONS}
              | {("service", f"/{s.name}", s.type) for s in ifc.SERVICES})
    assert served == declared
    assert all(t.startswith(("corobot_interfaces/", "std_srvs/", "geometry_msgs/"))
               for _, _, t in declared)
    docs = Path(__file__).resolve().parents[2] / "docs"
    assert "<!-- reference: ros2_default_robot -->" in (docs / "ros2.md").read_text()
    sys.path.insert(0, str(docs / "_ext"))
    try:
        from corobot_docs import ros2 as generated
    finally:
        sys.path.remove(str(docs / "_ext"))
    names = {row.split(" | ")[0].strip("| `").split("`")[0]
             for row in generated.default_robot().splitlines()[2:]}
    assert {name for _, name, _ in declared} <= names
    assert {f"/{t.name}" for t in ifc.TOPICS} | {"/ir/front", "/camera/image_raw"} <= names


def test_drive_state_message_has_the_drive_states_fields():
    msg = ifc.INTERFACES_DIR / ifc.PACKAGE / "msg"
    # The header holds the time; which wheels have an encoder (`encoded`) is each wheel's
    # has_encoder on the wire.
    assert set(_fields(msg / "DriveState.msg")) == {
        "header", *(f.name for f in dc.fields(DriveState)
                    if f.name not in ("time_stamp", "encoded"))}
    assert "has_encoder" in _fields(msg / "WheelState.msg")
    assert {f.name for f in dc.fields(WheelState)} <= set(_fields(msg / "WheelState.msg"))


def test_bag_type_hashes_are_the_built_packages():
    """rosbags' hashes (the bag's metadata) equal rosidl's for the messages built here (into
    the environment: `ros2.build`)."""
    from corobot_drake.ros2.bus import typestore

    for name in ifc.message_definitions():
        package, _, cls = name.split("/")
        built = json.loads((Path(sys.prefix) / "share" / package / "msg" /
                            f"{cls}.json").read_text())
        assert typestore().hash_rihs01(name) == built["type_hashes"][0]["hash_string"], name


# --- the URDF against the SDF ---


def _wheel_frames(text: str, kind: str, base: str) -> dict:
    plant = MultibodyPlant(0.0)
    (instance,) = (make_parser(plant) if kind == "sdf" else Parser(plant)
                   ).AddModelsFromString(text, kind)
    plant.Finalize()
    context = plant.CreateDefaultContext()
    B = plant.GetBodyByName(base, instance)
    return {w: plant.GetBodyByName(f"{w}_wheel", instance).EvalPoseInWorld(context)
            .translation() - B.EvalPoseInWorld(context).translation()
            for w in SPEC.wheel_names}


def test_urdf_has_the_sdfs_wheels_where_the_sdf_has_them():
    urdf = _wheel_frames(corobot_urdf(), "urdf", tp.CHASSIS_FRAME)
    sdf = _wheel_frames(corobot_sdf(), "sdf", "chassis")
    for wheel in SPEC.wheel_names:
        np.testing.assert_allclose(urdf[wheel], sdf[wheel], atol=1e-9)
    text = corobot_urdf()
    boxes = [shape for _, shape, _ in SPEC.shapes if type(shape).__name__ == "Box"]
    assert len(boxes) == 2  # the chassis and the platform
    for box in boxes:
        assert " ".join(f"{v:.9g}" for v in box.size()) in text


# --- each publisher alone ---


def test_clock_publishes_every_10_ms():
    memory = Memory()
    stepper = Stepper(ClockPublisher(Bus([memory])), 0.01)
    stepper.tick(5)
    stamps = [m.clock.sec + 1e-9 * m.clock.nanosec for _, m in memory.messages["/clock"]]
    assert stamps == pytest.approx([0.0, 0.01, 0.02, 0.03, 0.04])
    assert [t for t, _ in memory.messages["/clock"]] == [round(s * 1e9) for s in stamps]


def robot_state_publisher(memory, ground_truth: bool = False):
    """A namespaced robot's RobotStatePublisher with its inputs fixed, stepped once."""
    system = RobotStatePublisher(Bus([memory]), tp.RobotNames("bot", True), 1, sc.Drive(),
                                 ground_truth=ground_truth)
    stepper = Stepper(system, 0.02)
    X_WB = RigidTransform(RollPitchYaw(0, 0, 0.5), [1.0, 2.0, 0.0])
    V = SpatialVelocity([0, 0, 0.3], [0.4 * math.cos(0.5), 0.4 * math.sin(0.5), 0])
    stepper.fix("body_poses", [RigidTransform(), X_WB])
    stepper.fix("body_spatial_velocities", [SpatialVelocity.Zero(), V])
    stepper.fix("wheel_state", [0.1, 0.2, 0.3, 0.4, 2.0, 4.0, 2.0, 4.0])
    stepper.fix("drive_state", DriveState(0.0, True, SPEC.track, 10.0, {
        w: WheelState(0.1, 2.0, 7 if w.startswith("front") else None)
        for w in SPEC.wheel_names}, (1.0, 2.0, 0.0), 0.5))
    stepper.fix("odometry", [0.9, 2.1, 0.4])
    stepper.fix("travel", [3.0, 2.0])  # m rolled, rad turned since the last reset
    stepper.tick()


def test_robot_state_publisher_odom_wheel_odom_and_ground_truth():
    """/odom is the wheel odometry (the dead reckoning, its covariances the error model's),
    as /wheel_odom; /ground_truth the true pose in world."""
    memory = Memory()
    robot_state_publisher(memory)
    (_, truth), = memory.messages["/bot/ground_truth"]
    assert (truth.header.frame_id, truth.child_frame_id) == ("world", "bot/base_link")
    p = truth.pose.pose.position
    assert (p.x, p.y) == pytest.approx((1.0, 2.0))
    assert truth.twist.twist.linear.x == pytest.approx(0.4)  # in base_link: all forward
    assert truth.twist.twist.linear.y == pytest.approx(0.0, abs=1e-12)
    assert truth.twist.twist.angular.z == pytest.approx(0.3)
    assert not truth.pose.covariance.any()  # exact
    (_, wheel), = memory.messages["/bot/wheel_odom"]
    assert (wheel.header.frame_id, wheel.child_frame_id) == ("bot/odom", "bot/base_link")
    assert wheel.pose.pose.position.x == pytest.approx(0.9)
    drive = sc.Drive()
    r, track = drive.effective_wheel_radius, drive.effective_track_width
    assert wheel.twist.twist.linear.x == pytest.approx(r * 3.0)  # front axles 2 and 4 rad/s
    assert wheel.twist.twist.angular.z == pytest.approx(r * 2.0 / track)
    model = error_model(SPEC, drive)  # the Corobot's, after the travel fixed
    assert [wheel.pose.covariance[i] for i in (0, 7, 35)] == pytest.approx(
        model.pose_variances(3.0, 2.0), rel=1e-12)
    assert [wheel.twist.covariance[i] for i in (0, 35)] == pytest.approx(
        model.twist_variances(), rel=1e-12)
    (_, odom), = memory.messages["/bot/odom"]
    assert odom.pose == wheel.pose and odom.twist == wheel.twist
    ground = Memory()
    robot_state_publisher(ground, ground_truth=True)  # odom_source: ground_truth
    (_, odom), = ground.messages["/bot/odom"]
    assert odom.header.frame_id == "bot/odom" and odom.pose.pose.position.x == 1.0


def test_robot_state_publisher_joint_states_and_drive_state():
    memory = Memory()
    robot_state_publisher(memory)
    (_, joints), = memory.messages["/bot/joint_states"]
    assert list(joints.name) == [f"{w}_axle" for w in SPEC.wheel_names]
    assert list(joints.velocity) == [2.0, 4.0, 2.0, 4.0]
    (_, state), = memory.messages["/bot/drive_state"]
    assert [w.has_encoder for w in state.wheels] == [True, True, False, False]
    assert state.wheels[0].encoder_ticks == 7 and state.heading == 0.5


def test_ir_sensor_publisher_sends_each_scan_once():
    """An IR sensor's SensorPublisher on the bus: sensor_msgs/Range on /ir/<sensor>, in its
    frame, once per scan, at the scan's time."""
    from corobot_drake.recording.looks import SensorPublisher
    from corobot_drake.ros2.publishers import RosSensorSink
    from corobot_drake.sensors.ir_sensor import IrSensor, IrSensorKind
    from corobot_drake.sensors.kind import BuiltSensor

    memory = Memory()
    config = IrSensorConfig(scan_rate_hz=20.0)
    ir = IrSensor(config, None, [])
    sensor = BuiltSensor(IrSensorKind(), "corobot", "front", config, ir,
                         ir.GetOutputPort("reading"), config.scan_rate_hz)
    system = SensorPublisher(sensor, RosSensorSink(Bus([memory]), tp.RobotNames("corobot"),
                                                   sensor))
    size = scan_state_layout(ir.num_rays)[0]
    stepper = Stepper(system, 0.05)
    scan = np.zeros(size)
    scan[SCAN_TIME], scan[DISTANCE] = math.nan, 0.3
    stepper.fix("scan_state", scan)
    stepper.tick()  # no scan yet
    scan[SCAN_TIME] = 0.05
    stepper.fix("scan_state", scan)
    stepper.tick(3)  # the look at 0.1 publishes the scan at 0.05; later looks do not
    (t_ns, msg), = memory.messages["/ir/front"]
    assert t_ns == 50_000_000 and msg.range == pytest.approx(0.3)
    assert msg.max_range == pytest.approx(config.maximum_range)
    assert msg.header.frame_id == "ir_front" and msg.radiation_type == msg.INFRARED
    scan[SCAN_TIME], scan[DISTANCE] = 0.2, config.maximum_range  # nothing in range
    stepper.fix("scan_state", scan)
    stepper.tick(3)
    assert memory.messages["/ir/front"][-1][1].range == math.inf  # REP 117


class Unwatched(Memory):
    """A live topic's sink with nobody subscribed (`node.LiveSink.watched`), until `watch`."""

    def __init__(self):
        super().__init__()
        self.watching = False

    def watched(self, topic):
        return self.watching


def test_a_sensor_nobody_watches_makes_no_reading():
    """A sensor's publisher hands nothing on while no sink watches its topics, and does not
    make the reading (a camera's frame would render for it); once one does, the next scan
    goes out."""
    from corobot_drake.recording.looks import SensorPublisher
    from corobot_drake.ros2.publishers import RosSensorSink
    from corobot_drake.sensors.ir_sensor import IrSensor, IrSensorKind
    from corobot_drake.sensors.kind import BuiltSensor

    sink = Unwatched()
    config = IrSensorConfig(scan_rate_hz=20.0)
    ir = IrSensor(config, None, [])
    made = []

    class Kind(IrSensorKind):
        def wire_reading(self, sensor, inputs):
            made.append(sensor.name)
            return super().wire_reading(sensor, inputs)

    sensor = BuiltSensor(Kind(), "corobot", "front", config, ir, ir.GetOutputPort("reading"),
                         config.scan_rate_hz)
    system = SensorPublisher(sensor, RosSensorSink(Bus([sink]), tp.RobotNames("corobot"),
                                                   sensor))
    stepper = Stepper(system, 0.05)
    scan = np.zeros(scan_state_layout(ir.num_rays)[0])
    scan[SCAN_TIME], scan[DISTANCE] = 0.0, 0.3
    stepper.fix("scan_state", scan)
    stepper.tick(3)
    assert sink.messages["/ir/front"] == [] and made == []
    sink.watching = True
    scan[SCAN_TIME] = 0.15
    stepper.fix("scan_state", scan)
    stepper.tick(2)
    assert len(sink.messages["/ir/front"]) == 1 and made == ["front"]


def test_transform_publisher_odom_to_base_link_to_wheels():
    memory = Memory()
    names = tp.RobotNames("corobot")
    for ground_truth in (False, True):
        memory = Memory()
        system = TransformPublisher(Bus([memory]), [(names, 1, [(2, "front_left_wheel")])],
                                    ground_truth=ground_truth)
        stepper = Stepper(system, 0.02)
        X_WB = RigidTransform(RollPitchYaw(0, 0, math.pi / 2), [1.0, 0.0, 0.0])
        X_WW = RigidTransform(RollPitchYaw(0, 0.7, math.pi / 2), [1.0, 0.1, 0.06])  # the wheel
        stepper.fix("body_poses", [RigidTransform(), X_WB, X_WW])
        if not ground_truth:  # odom -> base_link is the dead reckoning's
            stepper.fix("corobot_odometry", [0.9, 0.2, 1.5])
        stepper.tick(2)
        assert [t for t, _ in memory.messages["/tf"]] == [0, 20_000_000]
        (_, tf) = memory.messages["/tf"][-1]
        base, wheel = tf.transforms
        assert (base.header.frame_id, base.child_frame_id) == ("odom", "base_link")
        b = base.transform.translation
        assert (b.x, b.y, b.z) == ((1.0, 0.0, 0.0) if ground_truth else (0.9, 0.2, 0.0))
        assert (wheel.header.frame_id, wheel.child_frame_id) == ("base_link",
                                                                 "front_left_wheel")
        w = wheel.transform.translation  # in base_link (facing world +y): 0.1 m ahead of it
        assert (w.x, w.y, w.z) == pytest.approx((0.1, 0.0, 0.06), abs=1e-12)


def test_static_publisher_publishes_once_latched():
    memory = Memory()
    names = tp.RobotNames("corobot")
    mounts = [("base_link", "ir_front", RigidTransform([0.1, 0, 0.07]))]
    system = StaticPublisher(Bus([memory]), mounts, {names: "<robot/>"})
    Stepper(system, 0.02).tick(3)
    (_, static), = memory.messages["/tf_static"]
    assert static.transforms[0].child_frame_id == "ir_front"
    assert static.transforms[0].transform.translation.z == pytest.approx(0.07)
    (_, description), = memory.messages["/robot_description"]
    assert description.data == "<robot/>"


def test_telemetry_publisher_stamps_the_held_samples():
    memory = Memory()
    system = TelemetryPublisher(Bus([memory]), tp.RobotNames("corobot"), 0.02, 0.1)
    stepper = Stepper(system, 0.02)
    for port, value in (("wheel_loads", [9.0, 9.1, 9.2, 9.3]), ("wheel_slip_ratio", [0.1] * 4),
                        ("wheel_slip_angle", [2.0] * 4), ("tip_margin", [37.4])):
        stepper.fix(port, value)
    stepper.tick(6)  # looks at 0 ... 0.1 s
    assert len(memory.messages["/tip_margin"]) == 6
    (t_ns, loads), = memory.messages["/wheel_loads"]  # the look at 0.1: the sample of 0
    assert t_ns == 0 and list(loads.load) == [9.0, 9.1, 9.2, 9.3]
    assert list(loads.wheel_names) == list(SPEC.wheel_names)
    (_, slip), = memory.messages["/wheel_slip"]
    assert list(slip.slip_angle_deg) == [2.0] * 4


def test_each_camera_has_its_own_topics_and_frames():
    """A robot with two cameras on the bus: the front one on /camera/..., the other on
    /camera/<name>/..., each image its own camera's frame in its own optical frame, with
    each camera's link and optical frame on /tf_static."""
    from functools import partial

    from conftest import TWO_CAMERAS
    from corobot_drake.config.scenario import load_scenario
    from corobot_drake.resources import DEFAULT_SCENARIO
    from corobot_drake.ros2.publishers import add_ros2_topics
    from corobot_drake.simulation import Simulation

    memory = Memory()
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[TWO_CAMERAS]),
                     extras=[partial(add_ros2_topics, Bus([memory]))])
    sim.advance(0.1)
    robot = sim.robot()
    for name, topic, frame in (("front", "/camera", "camera_optical_frame"),
                               ("rear", "/camera/rear", "camera_rear_optical_frame")):
        t_ns, image = memory.messages[f"{topic}/image_raw"][-1]
        _, info = memory.messages[f"{topic}/camera_info"][-1]
        assert image.header.frame_id == info.header.frame_id == frame
        assert t_ns == round(robot.camera_image_time(name) * 1e9)
        pixels = np.frombuffer(bytes(image.data), np.uint8).reshape(image.height, image.width, 3)
        np.testing.assert_array_equal(pixels, robot.camera_image(name)[:, :, :3])
    (_, static), = memory.messages["/tf_static"]
    parents = {x.child_frame_id: x.header.frame_id for x in static.transforms}
    assert parents["camera_rear_optical_frame"] == "camera_rear_link"
    assert parents["camera_optical_frame"] == "camera_link"
    assert parents["camera_rear_link"] == parents["camera_link"] == "base_link"


def test_discovery_stays_on_this_machine_unless_asked():
    assert configure_discovery(False, {}) == "LOCALHOST"
    assert configure_discovery(False, {"ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET"}) == "SUBNET"
    assert configure_discovery(True, {}) == "SUBNET"
    assert configure_discovery(False, {"ROS_AUTOMATIC_DISCOVERY_RANGE": ""}) == "LOCALHOST"


def test_a_bad_ros_environment_or_topic_is_one_line(monkeypatch, capsys):
    """Refused before any DDS starts (in a private network all the same, should one)."""
    pytest.importorskip("corobot_interfaces.msg", reason="python -m corobot_drake.ros2.build")
    from corobot_drake.ros2 import inspection
    from ros2_probe import private_network

    with private_network():
        for variable, value, allowed in (
                ("ROS_DOMAIN_ID", "abc", "a whole number in [0, 232] (0-101 are clear of the "
                                         "ephemeral ports)"),
                ("ROS_DOMAIN_ID", "300", "a whole number in [0, 232] (0-101 are clear of the "
                                         "ephemeral ports)"),
                ("ROS_AUTOMATIC_DISCOVERY_RANGE", "BOGUS",
                 "one of LOCALHOST, SUBNET, OFF, SYSTEM_DEFAULT (or unset: LOCALHOST)")):
            with monkeypatch.context() as env:
                env.setenv(variable, value)
                assert cli.main(["--ros2", "--headless", "--duration", "0.1"]) == 2
                assert capsys.readouterr().err == (f"error: --ros2: {variable}={value}: must "
                                                   f"be {allowed}\n")
                assert inspection.main(["--wait", "0", "list"]) == 2
                assert capsys.readouterr().err == (
                    f"error: python -m corobot_drake.ros2: {variable}={value}: must be "
                    f"{allowed}\n")
        monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
        assert inspection.main(["--wait", "0", "echo", "bad name"]) == 2
        assert capsys.readouterr().err == (
            "error: echo: bad name: not a topic name (topic name must not contain characters "
            "other than alphanumerics, '_', '~', '{', or '}')\n")
        for argv in (["echo", "/odom", "-n", "-1"], ["--timeout", "nan", "list"]):
            with pytest.raises(SystemExit) as stop:
                inspection.main(argv)
            assert stop.value.code == 2
        assert capsys.readouterr().err == (
            "error: argument --count/-n: a whole number >= 0; got -1\n"
            "error: argument --timeout: a number of s >= 0; got nan\n")


# --- a bag read back ---


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    path = tmp_path_factory.mktemp("ros2") / "run"
    subprocess.run([sys.executable, "-m", "corobot_drake", "--headless", "--duration", "1",
                    "--rosbag", str(path), "--override",
                    "robots: {corobot: {commands: [!SetVelocity {linear: 0.2, angular: 0.5}]}}"],
                   check=True, capture_output=True)
    return path


def test_bag_round_trips(bag):
    from rosbags.rosbag2 import Reader

    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert (info["version"], info["storage_identifier"]) == (9, "mcap")  # ROS 2 Jazzy's
    assert info["ros_distro"] == "jazzy"
    assert all(t["topic_metadata"]["type_description_hash"].startswith("RIHS01_")
               for t in info["topics_with_message_count"])
    with Reader(bag) as reader:
        topics = {c.topic: c.msgtype for c in reader.connections}
        assert set(topics) >= {"/clock", "/tf", "/tf_static", "/odom", "/ir/front",
                               "/camera/image_raw", "/drive_state", "/wheel_slip"}
        counts = dict.fromkeys(topics, 0)
        for connection, t_ns, data in reader.messages():
            msg = deserialize_message(data, ros_type(connection.msgtype))
            counts[connection.topic] += 1
            stamp = msg.clock if connection.topic == "/clock" else (
                msg.transforms[0].header.stamp if connection.msgtype.startswith("tf2")
                else msg.header.stamp if hasattr(msg, "header") else None)
            if stamp is not None:
                assert stamp.sec * 1_000_000_000 + stamp.nanosec == t_ns  # logged at its stamp
            if connection.topic == "/camera/image_raw":
                assert (msg.width, msg.height, msg.encoding) == (320, 240, "rgb8")
    assert counts["/clock"] == 101  # 0 to 1 s, both ends, every 10 ms
    assert counts["/odom"] == 51  # every 20 ms
    assert counts["/tf_static"] == counts["/robot_description"] == 1


# --- the flags' errors ---


def test_ros2_without_the_extra_is_one_line(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "rclpy", None)  # as if not installed
    assert cli.main(["--ros2", "--headless"]) == 2
    assert capsys.readouterr().err == (
        "error: --ros2 needs the [ros2] extra: pip install '.[ros2]' in corobot-drake's clone "
        "or unpacked sdist (it is not on PyPI; tools/setup installs every extra)\n")


def test_rosbag_into_an_existing_directory_is_one_line(tmp_path, capsys):
    assert cli.main(["--headless", "--rosbag", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert re.fullmatch(r"error: --rosbag: .*: exists already: name a new directory.*\n", err)


def test_rosbag_paths_that_cannot_be_a_bag_are_one_line(tmp_path, capsys):
    import os

    (tmp_path / "dangling").symlink_to(tmp_path / "gone")
    os.mkfifo(tmp_path / "fifo")
    long = tmp_path / ("b" * 300)
    for path, problem in (
            (tmp_path / "dangling", f"is a dangling symlink (to {tmp_path / 'gone'}): name a "
                                    "new directory (rosbag2 makes it)"),
            (long, "its name is 300 bytes: with .mcap (its MCAP file's name) it must fit the "
                   "file system's 255"),
            (tmp_path / "fifo" / "bag", f"{tmp_path / 'fifo'} is a FIFO, not a directory")):
        assert cli.main(["--headless", "--rosbag", str(path)]) == 2
        assert capsys.readouterr().err == f"error: --rosbag: {path}: {problem}\n"


def test_a_full_disk_finishes_the_bag_with_what_was_written(tmp_path):
    """A 3 MiB tmpfs (as root; else skipped) that the camera's frames fill in a third of a
    simulated second: one line, exit status 1, and a bag whose metadata counts the messages
    its MCAP file holds."""
    import os

    from rosbags.rosbag2 import Reader

    disk = tmp_path / "disk"
    disk.mkdir()
    if os.geteuid() != 0 or subprocess.run(
            ["mount", "-t", "tmpfs", "-o", "size=3m", "tmpfs", str(disk)],
            capture_output=True).returncode != 0:
        pytest.skip("needs root to mount a small tmpfs")
    try:
        run = subprocess.run([sys.executable, "-m", "corobot_drake", "--headless", "--duration",
                              "1", "--rosbag", str(disk / "bag")], capture_output=True,
                             text=True, timeout=300)
        with Reader(disk / "bag") as reader:
            counted = reader.message_count
            read = sum(1 for _ in reader.messages())
    finally:
        subprocess.run(["umount", str(disk)], check=True)
    assert run.returncode == 1, run.stderr
    error, = [line for line in run.stderr.splitlines() if line.startswith("error")]
    assert error.startswith(f"error: --rosbag: {disk / 'bag'}: cannot write (No space left on "
                            f"device); the bag is finished with the {read} messages written "
                            "before, up to t = ")
    assert "Traceback" not in run.stderr
    assert counted == read > 0


def test_sensor_topics_are_offered_reliable_unless_best_effort_is_asked():
    """One offer table (`interfaces.offer`) makes the node's profiles and the bag's: a sensor
    stream reliable (RViz's default subscription matches it) or, with the node's sensor_qos
    parameter, best effort; state reliable; latched topics transient local."""
    from rclpy.qos import DurabilityPolicy, ReliabilityPolicy

    from corobot_drake.ros2.bag import _qos
    from corobot_drake.ros2.node import qos_profile

    assert qos_profile(ifc.Qos.SENSOR).reliability == ReliabilityPolicy.RELIABLE
    assert (qos_profile(ifc.Qos.SENSOR, "best_effort").reliability
            == ReliabilityPolicy.BEST_EFFORT)
    assert qos_profile(ifc.Qos.LATCHED).durability == DurabilityPolicy.TRANSIENT_LOCAL
    assert qos_profile(ifc.Qos.SENSOR).depth == _qos(ifc.Qos.SENSOR).depth == 5
    assert _qos(ifc.Qos.SENSOR).reliability.name == "RELIABLE"  # a replay offers the same
