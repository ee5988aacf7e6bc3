"""The run kept for replay: the Meshcat HTML replay, the MCAP file, the live Foxglove server."""

import base64
import json
import math
import os
import re
import time

import foxglove
import msgpack  # Meshcat's wire format (installed with Ray)
import numpy as np
import pytest
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from mcap.reader import make_reader

from conftest import SAP, TWO_CAMERAS, make_sim
from corobot_drake.cli import main
from corobot_drake.config.scenario import load_scenario
from corobot_drake.recording.foxglove_live import FoxgloveLive
from corobot_drake.recording.mcap_log import McapLog
from corobot_drake.recording.meshcat_html import RECORDING_FPS
from corobot_drake.recording.publishers import (
    STATE_PERIOD,
    TELEMETRY_PERIOD,
    RobotStatePublisher,
    TelemetryPublisher,
    in_window,
)
from corobot_drake.recording.topics import command_event
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.robots import robot_spec
from corobot_drake.simulation import Simulation
from corobot_drake.systems.drive import CommandRecord
from corobot_drake.systems.runlog import COLUMNS
from corobot_drake.topics import RobotNames
from lab.bench import NO_CAMERA
from lab.processes import listening_sockets, sockets_held
from mesh_samples import CORNERS, CUBE_OBJ, TRIANGLES, gltf

CURVE = "robots: {corobot: {commands: [!SetPower {left: 1, right: 0.5}]}}"
SCRIPT = ("robots: {corobot: {commands: [!SetPower {left: 1, right: 0.5}, !Wait {seconds: 0.5},"
          " !AllStop {}]}}")


# --- the Meshcat replay ----------------------------------------------------------------------


def _meshcat_messages(html: str) -> list[dict]:
    """The Meshcat commands a static HTML file replays (base64 msgpack in data: URLs)."""
    blobs = re.findall(r'data:application/octet-binary;base64,([A-Za-z0-9+/=]+)', html)
    return [msgpack.unpackb(base64.b64decode(b), strict_map_key=False) for b in blobs]


def _track(animation: dict, path: str, name: str) -> list:
    clip = next(a["clip"] for a in animation["animations"] if a["path"] == path)
    return next(t["keys"] for t in clip["tracks"] if t["name"] == name)


@pytest.mark.parametrize("plant, period", [((), 0.02), ((SAP,), 1 / 64)], ids=["cenic", "sap"])
def test_recording_is_a_self_contained_replay_of_the_run(tmp_path, plant, period):
    """A frame per visualizer publish: Drake's 64 Hz, or on CENIC's steps every 0.02 s."""
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[CURVE, *plant]), record=True)
    sim.advance(1.0)
    path = tmp_path / "run.html"
    size = sim.save_recording(path)
    html = path.read_text()
    assert size == len(html.encode()) > 100_000
    # Offline: no script, style or image fetched from the network.
    assert not re.search(r'<(script|link|img)[^>]+(src|href)="https?:', html)
    (animation,) = [m for m in _meshcat_messages(html) if m["type"] == "set_animation"]
    keys = _track(animation, "/drake/illustration/corobot/chassis", ".position")
    assert len(keys) == round(1.0 / period) + 1
    assert keys[-1]["time"] == round(1.0 * RECORDING_FPS)
    pose = sim.robot().pose()
    # The last frame is the robot where the run ended (published at t = 1 s exactly).
    assert keys[-1]["value"][:2] == pytest.approx([pose.x, pose.y], abs=1e-9)
    # It drove a curve: the path has moved more than a few centimetres from the start.
    assert np.hypot(*np.subtract(keys[-1]["value"][:2], keys[0]["value"][:2])) > 0.1


def test_recording_restarts_with_reset_and_carries_on_after_a_save(tmp_path):
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[CURVE]), record=True)
    sim.advance(0.5)
    sim.save_recording(tmp_path / "a.html")
    sim.advance(0.5)  # recording goes on after a save
    sim.save_recording(tmp_path / "b.html")
    sim.reset()
    sim.advance(0.25)
    sim.save_recording(tmp_path / "c.html")
    counts = []
    for name in "abc":
        (animation,) = [m for m in _meshcat_messages((tmp_path / f"{name}.html").read_text())
                        if m["type"] == "set_animation"]
        counts.append(len(_track(animation, "/drake/illustration/corobot/chassis",
                                 ".position")))
    # 0.5, 1.0 and (after the reset) 0.24 s at 50 Hz (on CENIC's steps), from 0.
    assert counts == [26, 51, 13]


def test_save_recording_needs_record():
    with pytest.raises(RuntimeError, match="record=True"):
        make_sim().save_recording("x.html")


# --- MCAP ------------------------------------------------------------------------------------


def _decoders(summary) -> dict:
    """{schema id: bytes -> message} for the file's protobuf and JSON schemas."""
    out = {}
    for sid, schema in summary.schemas.items():
        if schema.encoding == "protobuf":
            pool = descriptor_pool.DescriptorPool()
            for fd in descriptor_pb2.FileDescriptorSet.FromString(schema.data).file:
                pool.Add(fd)
            out[sid] = message_factory.GetMessageClass(
                pool.FindMessageTypeByName(schema.name)).FromString
        else:
            assert schema.encoding == "jsonschema"
            out[sid] = json.loads
    return out


def read_mcap(path) -> dict[str, list]:
    """{topic: [(log time s, schema name, decoded message), ...]} in log-time order."""
    with open(path, "rb") as f:
        reader = make_reader(f)
        decode = _decoders(reader.get_summary())
        topics: dict[str, list] = {}
        for schema, channel, message in reader.iter_messages(log_time_order=True):
            topics.setdefault(channel.topic, []).append(
                (message.log_time / 1e9, schema.name, decode[schema.id](message.data)))
    return topics


EXPECTED_SCHEMAS = {
    "/tf": "foxglove.FrameTransforms", "/scene": "foxglove.SceneUpdate",
    "/joint_states": "foxglove.JointStates", "/odom": "foxglove.Odometry",
    "/drive_state": "corobot.DriveState", "/commands": "foxglove.Log",
    "/ir/front": "corobot.Range", "/ir/front/rays": "foxglove.SceneUpdate",
    "/ir/rear": "corobot.Range", "/ir/rear/rays": "foxglove.SceneUpdate",
    "/camera/image/compressed": "foxglove.CompressedImage",
    "/camera/camera_info": "foxglove.CameraCalibration",
    "/wheel_loads": "corobot.WheelLoads", "/wheel_slip": "corobot.WheelSlip",
    "/tip_margin": "corobot.TipMargin",
}


@pytest.fixture(scope="module")
def mcap_run(tmp_path_factory):
    """One second of the scripted run with the camera, logged to MCAP: (simulation, topics)."""
    path = tmp_path_factory.mktemp("mcap") / "run.mcap"
    with McapLog(path) as log:
        sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[SCRIPT]),
                         foxglove=log.context)
        sim.advance(1.0)
    return sim, read_mcap(path)


def test_under_cenic_mcap_has_every_scan_and_frame_once(tmp_path):
    """On a continuous plant the IR sensors scan and the camera takes its frames on the plant's
    steps (`IrSensor.events`): the publishers look on the same schedule, so each scan of
    1 s is published once, stamped with its step (k x 0.05 s, as 5k x 0.01), and each frame
    once, 30 ms after its step; and recording changes nothing of the motion."""
    from corobot_drake.config.scenario import CENIC_PLANT
    from corobot_drake.simulation import Simulation

    overrides = [SCRIPT, CENIC_PLANT % 0.01]
    with McapLog(tmp_path / "run.mcap") as log:
        sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=overrides),
                         foxglove=log.context)
        sim.advance(1.0)
    topics = read_mcap(tmp_path / "run.mcap")
    for topic in ("/ir/front", "/ir/rear"):
        assert [t for t, _, _ in topics[topic]] == pytest.approx(
            [k * 0.05 for k in range(20)], abs=1e-9), topic  # stamped in whole nanoseconds
    frames = [t for t, _, _ in topics["/camera/image/compressed"]]
    # Tick k at 0.5 ms past k / 30 s is taken at the next 10 ms step, out 30 ms later.
    steps = [math.ceil((0.0005 + k / 30) / 0.01) * 0.01 for k in range(30)]
    assert frames == pytest.approx([t for t in steps if t + 0.03 < 1.0], abs=1e-9)
    quiet = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=overrides))
    quiet.advance(1.0)
    assert quiet.robot().pose() == sim.robot().pose()


def test_mcap_has_every_topic_at_its_rate(mcap_run):
    _, topics = mcap_run
    assert {t: m[0][1] for t, m in topics.items()} == EXPECTED_SCHEMAS
    counts = {t: len(m) for t, m in topics.items()}
    # State topics: a look every 20 ms from 0 to 1 s inclusive.
    for topic in ("/tf", "/joint_states", "/odom", "/drive_state", "/tip_margin"):
        assert counts[topic] == round(1.0 / STATE_PERIOD) + 1, topic
    # Loads and slip: the samples at 0, 0.1, ..., 0.9 s, each published a period later (the
    # one at 1 s when the run goes on).
    for topic in ("/wheel_loads", "/wheel_slip"):
        assert counts[topic] == round(1.0 / TELEMETRY_PERIOD), topic
        assert [t for t, _, _ in topics[topic]] == pytest.approx(
            [k * TELEMETRY_PERIOD for k in range(10)], abs=1e-9)
    # IR: the scans at 0, 0.05, ..., 0.95 s (the one at 1 s is taken when the run goes on).
    for topic in ("/ir/front", "/ir/front/rays", "/ir/rear", "/ir/rear/rays"):
        assert counts[topic] == 20, topic
    # Camera at 30 Hz, taken on the first step at or after 0.0005 + k / 30 s and out 30 ms
    # later: k = 0..28 before 1 s (k = 29's, taken at 0.97 s, is out at 1 s, the end).
    assert counts["/camera/image/compressed"] == counts["/camera/camera_info"] == 29
    assert counts["/scene"] == 2  # at 0 and 1 s


def test_a_mesh_body_is_drawn_in_the_scene_as_its_hull(tmp_path):
    """A body with meshes only (`!Mesh` world bodies, OBJ and GLB) is drawn in /scene as its
    mesh's convex hull, in its colour, scaled: the hull's corners are the cube's (to float
    precision: a GLB's vertices are 32-bit); the robot keeps its collision shapes."""
    (tmp_path / "cube.obj").write_text(CUBE_OBJ)
    (tmp_path / "cube.glb").write_bytes(gltf(CORNERS, TRIANGLES, glb=True))
    bodies = ", ".join(
        f"{name}: {{shape: !Mesh {{filename: '{tmp_path}/{name}', scale: {scale}}}, "
        f"mass: 2.0, color: [0.1, 0.2, 0.3, 1.0], pose: {{translation: [{x}, 1.0, 0.3]}}}}"
        for name, scale, x in (("cube.obj", 2.0, 0.5), ("cube.glb", 1.5, -0.5)))
    path = tmp_path / "run.mcap"
    with McapLog(path) as log:
        Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[f"world: {{bodies: {{{bodies}}}}}"]),
                   foxglove=log.context).advance(0.05)
    entities = {e.id: e for e in read_mcap(path)["/scene"][0][2].entities}
    for name, scale in (("cube.obj", 2.0), ("cube.glb", 1.5)):
        (hull,) = entities[name].triangles
        assert not (entities[name].cubes or entities[name].cylinders or entities[name].spheres)
        points = np.array([[p.x, p.y, p.z] for p in hull.points])
        assert len(points) % 3 == 0 and len(points) >= 36  # 6 faces, 2 triangles or more each
        assert np.abs(points).max(axis=1) == pytest.approx(0.1 * scale, rel=1e-6), name
        assert [hull.color.r, hull.color.g, hull.color.b] == pytest.approx([0.1, 0.2, 0.3])
    assert len(entities["front_left_wheel"].cylinders) == 1
    assert not entities["base_link"].triangles


def test_mcap_messages_hold_the_run(mcap_run):
    sim, topics = mcap_run
    robot = sim.robot()
    pose = robot.pose()
    t, _, tf = topics["/tf"][-1]
    assert t == pytest.approx(1.0)
    base = next(x for x in tf.transforms if x.child_frame_id == "base_link")
    assert base.parent_frame_id == "world"
    assert [base.translation.x, base.translation.y] == pytest.approx([pose.x, pose.y], abs=1e-12)
    frames = {x.child_frame_id for x in tf.transforms}
    assert {"giant_box", "front_left_wheel", "rear_right_wheel", "ir_front", "ir_rear",
            "camera_optical_frame"} <= frames
    odom = topics["/odom"][-1][2]
    assert [odom.pose.position.x, odom.pose.position.y] == pytest.approx([pose.x, pose.y])
    velocity = robot.velocity()
    # base_link's axes against the heading frame's: apart by the chassis's sub-millimetre
    # pitch and roll on flat ground, so 1 mm/s and 1 mrad/s.
    assert odom.linear_velocity.x == pytest.approx(velocity.forward, abs=1e-3)
    assert odom.angular_velocity.z == pytest.approx(velocity.yaw_rate, abs=1e-3)
    # Mid-drive (the script stops at 0.5 s), the twist matches the poses' central difference:
    # speed is steady after the 0.33 s slew, so 1%.
    odoms = {round(t, 2): m for t, _, m in topics["/odom"]}
    a, b, mid = odoms[0.38].pose.position, odoms[0.42].pose.position, odoms[0.4]
    speed = np.hypot(b.x - a.x, b.y - a.y) / 0.04
    assert speed > 0.3 and mid.linear_velocity.x == pytest.approx(speed, rel=0.01)
    joints = topics["/joint_states"][-1][2].joints
    assert {j.name: j.velocity for j in joints} == pytest.approx(
        {f"{w}_axle": v for w, v in robot.axle_speeds().items()}, abs=1e-12)
    scan = robot.ir("rear")
    t, _, rear = topics["/ir/rear"][-1]
    assert (t, rear["range"], rear["frame_id"]) == (pytest.approx(scan.time), scan.raw,
                                                    "ir_rear")
    rays = topics["/ir/rear/rays"][-1][2].entities[0].lines[0]
    assert len(rays.points) == 2 * 2 * 3  # 6 rays, origin and end each
    image = topics["/camera/image/compressed"][-1][2]
    assert image.format == "jpeg" and image.data[:2] == b"\xff\xd8"  # JPEG's start marker
    info = topics["/camera/camera_info"][-1][2]
    assert (info.width, info.height) == (320, 240)
    events = [(t, m.message) for t, _, m in topics["/commands"]]
    # Each start and end in the command log, at its time: the script's SetPower and its Wait
    # at 0 (both issued when the simulation starts; the SetPower ends as the drive takes it),
    # then the AllStop when the Wait ends, itself ended at the next update.
    expected = sorted([(r.start_time, command_event(r, False)) for r in robot.command_log()]
                      + [(r.end_time, command_event(r, True)) for r in robot.command_log()
                         if r.end_time is not None and r.end_time < 1.0])
    assert [m for _, m in expected] == ["Wait started", "seq 1 SetPower started",
                                        "seq 1 SetPower succeeded", "Wait succeeded",
                                        "seq 2 AllStop started", "seq 2 AllStop succeeded"]
    # Events of one instant in either order (sorted as `expected` is).
    assert sorted(events) == [(pytest.approx(t, abs=1e-9), m) for t, m in expected]


def test_each_camera_has_its_own_topics_and_frame(tmp_path):
    """Two cameras: the front one on /camera/..., the other on /camera/<name>/..., each
    image its own camera's (JPEG-decoded: the same picture as the Python API's, to JPEG's
    loss) in its own optical frame, mounted on base_link."""
    import io

    from PIL import Image

    path = tmp_path / "two.mcap"
    with McapLog(path) as log:
        sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[TWO_CAMERAS]),
                         foxglove=log.context)
        sim.advance(0.1)
    topics = read_mcap(path)
    robot = sim.robot()
    for name, topic, frame in (("front", "/camera", "camera_optical_frame"),
                               ("rear", "/camera/rear", "camera_rear_optical_frame")):
        t, _, image = topics[f"{topic}/image/compressed"][-1]
        info = topics[f"{topic}/camera_info"][-1][2]
        assert image.frame_id == info.frame_id == frame
        assert (info.width, info.height) == (64, 48)
        assert t == pytest.approx(robot.camera_image_time(name), abs=1e-9)
        decoded = np.asarray(Image.open(io.BytesIO(image.data)).convert("RGB"), dtype=int)
        # JPEG at quality 85 moves a 64 x 48 frame's pixels by a few grey levels on average;
        # the other camera's picture is tens of levels away (test_camera.py).
        assert np.abs(decoded - robot.camera_image(name)[:, :, :3]).mean() < 5
    mounts = {x.child_frame_id: x.parent_frame_id for x in topics["/tf"][-1][2].transforms}
    assert mounts["camera_optical_frame"] == mounts["camera_rear_optical_frame"] == "base_link"


SPEC = robot_spec("corobot")
"""The Corobot as its robot file and model say."""
ROBOT_WEIGHT = SPEC.mass * 9.81
"""N: what the four wheels carry at rest (the plant's gravity, 9.81 m/s^2)."""


def test_mcap_telemetry_holds_the_robot_s_loads_slip_and_tip_margin(mcap_run):
    """The script drives a right-hand curve (left side at full power, right at half) from 0 to
    0.5 s, then stops."""
    sim, topics = mcap_run
    robot = sim.robot()
    loads = {round(t, 2): m["wheels"] for t, _, m in topics["/wheel_loads"]}
    slips = {round(t, 2): m["wheels"] for t, _, m in topics["/wheel_slip"]}
    # Placed at z = 0 the tyres just touch: next to nothing carried at 0 s (under a gram's
    # weight, 0.01 N; the robot settles onto them within 40 ms). From then on the four carry
    # m (g + a_z): the chassis rocks on its compliant tyres as the drive's 30 rad/s^2 slew
    # speeds it up and stops it (measured within 1.5% of m g here), so 5%: a vertical
    # acceleration of the centre of mass up to 0.5 m/s^2.
    assert sum(w["load"] for w in loads[0.0].values()) < 0.01
    for t in sorted(loads)[1:]:
        assert sum(w["load"] for w in loads[t].values()) == pytest.approx(ROBOT_WEIGHT,
                                                                           rel=0.05), t
    # Weight moves to the rear wheels as the robot speeds up (0.1 s), to the front as it
    # brakes (0.6 s): measured 7.3 vs 12.3 N and 11.8 vs 8.0 N.
    front, rear = ("front_left", "front_right"), ("rear_left", "rear_right")
    assert max(loads[0.1][w]["load"] for w in front) < min(loads[0.1][w]["load"] for w in rear)
    assert min(loads[0.6][w]["load"] for w in front) > max(loads[0.6][w]["load"] for w in rear)
    # Mid-curve, skid-steering turns the robot clockwise about its middle: the fast left side
    # pulls (slip ratio +), the slow right side is dragged (-); the front wheels are scrubbed
    # to the right (slip angle -), the rear ones to the left (+).
    for t in (0.3, 0.4):
        w = slips[t]
        assert w["front_left"]["slip_ratio"] > 0 and w["rear_left"]["slip_ratio"] > 0, t
        assert w["front_right"]["slip_ratio"] < 0 and w["rear_right"]["slip_ratio"] < 0, t
        assert w["front_left"]["slip_angle_deg"] < 0 and w["front_right"]["slip_angle_deg"] < 0
        assert w["rear_left"]["slip_angle_deg"] > 0 and w["rear_right"]["slip_angle_deg"] > 0
    # Each sample is the run log's (the same holds' instants): the rows half a period later.
    rows = robot.run_log()
    for t, wheels in loads.items():
        (row,) = rows[np.isclose(rows[:, 0], t + TELEMETRY_PERIOD / 2)]
        assert [wheels[w]["load"] for w in SPEC.wheel_names] == list(
            row[[COLUMNS.index(f"load_{c}") for c in ("fl", "fr", "rl", "rr")]]), t
        assert [slips[t][w]["slip_angle_deg"] for w in SPEC.wheel_names] == list(
            row[[COLUMNS.index(f"slip_angle_{c}") for c in ("fl", "fr", "rl", "rr")]]), t
    # Upright on level ground: atan(half wheelbase / CoM height) = 37.4 deg at the start (to
    # its rounding). Driving on flat ground the chassis pitches a fraction of a degree on its
    # tyres (measured 37.37-37.41 deg): 0.5 deg. The last look is the robot's margin now.
    margins = [m["tip_margin_deg"] for _, _, m in topics["/tip_margin"]]
    assert margins[0] == pytest.approx(37.4, abs=0.05)
    assert margins == pytest.approx([37.4] * len(margins), abs=0.5)
    assert margins[-1] == robot.tip_margin_deg()


def test_telemetry_publisher_alone():
    """TelemetryPublisher on its own, its inputs fixed: /tip_margin at every look, stamped with
    it; /wheel_loads and /wheel_slip (held inputs) from the second look on, stamped with their
    sample's time, a period before."""
    import io

    from pydrake.systems.analysis import Simulator

    context = foxglove.Context()
    buffer = io.BytesIO()
    writer = foxglove.open_mcap(buffer, context=context)
    publisher = TelemetryPublisher(context, RobotNames("r", namespaced=True), period=0.02,
                                   costly_period=0.1)
    simulator = Simulator(publisher)
    system_context = simulator.get_mutable_context()
    for name, value in (("wheel_loads", [9.0, 10.0, 11.0, 12.0]),
                        ("wheel_slip_ratio", [0.1, -0.1, 0.2, -0.2]),
                        ("wheel_slip_angle", [-5.0, -6.0, 7.0, 8.0]), ("tip_margin", [30.0])):
        publisher.GetInputPort(name).FixValue(system_context, value)
    simulator.AdvanceTo(0.25)
    writer.close()
    buffer.seek(0)
    reader = make_reader(buffer)
    decode = _decoders(reader.get_summary())
    got: dict[str, list] = {}
    for schema, channel, message in reader.iter_messages(log_time_order=True):
        got.setdefault(channel.topic, []).append((message.log_time, schema.name,
                                                  decode[schema.id](message.data)))
    assert {t: m[0][1] for t, m in got.items()} == {
        "/r/wheel_loads": "corobot.WheelLoads", "/r/wheel_slip": "corobot.WheelSlip",
        "/r/tip_margin": "corobot.TipMargin"}
    # Looks at 0, 0.02, ..., 0.24 s; the held ones' at 0.1 and 0.2 s publish 0 and 0.1 s.
    assert [ns for ns, _, _ in got["/r/tip_margin"]] == [k * 20_000_000 for k in range(13)]
    assert [ns for ns, _, _ in got["/r/wheel_loads"]] == [0, 100_000_000]
    assert got["/r/tip_margin"][-1][2] == {"timestamp": {"sec": 0, "nsec": 240_000_000},
                                           "tip_margin_deg": 30.0}
    assert got["/r/wheel_slip"][-1][2]["wheels"]["rear_right"] == {"slip_ratio": -0.2,
                                                                   "slip_angle_deg": 8.0}
    assert {w: v["load"] for w, v in got["/r/wheel_loads"][0][2]["wheels"].items()} == dict(
        zip(SPEC.wheel_names, [9.0, 10.0, 11.0, 12.0], strict=True))


def test_a_reset_run_publishes_the_same_messages(tmp_path):
    """The publishers keep nothing outside the Context: after a reset the run is published
    again, message for message."""
    path = tmp_path / "twice.mcap"
    with McapLog(path) as log:
        sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[SCRIPT, NO_CAMERA]),
                         foxglove=log.context)
        sim.advance(0.6)
        sim.reset()
        sim.advance(0.6)
    for topic, messages in read_mcap(path).items():
        n = len(messages) // 2
        first = sorted((t, str(m)) for t, _, m in messages)[::2]
        second = sorted((t, str(m)) for t, _, m in messages)[1::2]
        assert len(messages) == 2 * n and first == second, topic


def test_command_events_alone():
    """RobotStatePublisher on its own: a look at t publishes the starts and ends in
    [t - period, t)."""
    publisher = RobotStatePublisher(foxglove.Context(), RobotNames("r"), chassis_index=1)
    context = publisher.CreateDefaultContext()
    log = (CommandRecord(1, "SetPower", 0.0, 0.03, "succeeded"),
           CommandRecord(2, "DriveDistance", 0.03, 0.05, "failed", "stalled"))
    publisher.GetInputPort("command_log").FixValue(context, log)
    seen = []
    for k in range(5):
        context.SetTime(k * STATE_PERIOD)
        seen.append([m for _, m, _ in publisher.command_events(context)])
    assert seen == [[], ["seq 1 SetPower started"],  # looks at 0 and 0.02 s
                    ["seq 1 SetPower succeeded", "seq 2 DriveDistance started"],  # 0.04 s
                    ["seq 2 DriveDistance failed (stalled)"], []]  # 0.06, 0.08 s
    assert in_window(0.02, 0.04, 0.02) and not in_window(0.04, 0.04, 0.02)


# --- live ------------------------------------------------------------------------------------


@pytest.mark.parametrize("offered", [["foxglove.sdk.v1", "foxglove.websocket.v1"],
                                     ["foxglove.websocket.v1"]])
def test_foxglove_live_serves_the_topics_and_stops(offered):
    """Clients offering the SDK's subprotocol name or only the older one get the topics."""
    from websockets.sync.client import connect

    live = FoxgloveLive(port=0)
    try:
        sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[NO_CAMERA]),
                         foxglove=live.context)
        with connect(live.url, subprotocols=offered, open_timeout=10) as ws:
            assert ws.subprotocol == offered[0]
            advertised = {}
            while "/odom" not in advertised:
                message = json.loads(ws.recv(timeout=10))
                if message["op"] == "advertise":
                    advertised.update({c["topic"]: c for c in message["channels"]})
            assert set(EXPECTED_SCHEMAS) - {"/camera/image/compressed",
                                            "/camera/camera_info"} <= set(advertised)
            ws.send(json.dumps({"op": "subscribe", "subscriptions": [
                {"id": 1, "channelId": advertised["/odom"]["id"]}]}))
            sim.advance(0.2)
            data = ws.recv(timeout=10)
            while isinstance(data, str):  # status and other text frames
                data = ws.recv(timeout=10)
            assert data[0] == 1 and int.from_bytes(data[1:5], "little") == 1  # message, sub 1
    finally:
        (listener,) = sockets_held(os.getpid()) & listening_sockets(live.port)
        live.stop()
    live.stop()  # idempotent
    deadline = time.monotonic() + 5.0  # the server's socket closes on its own thread
    while listener in listening_sockets():
        assert time.monotonic() < deadline, "still listening 5 s after stop()"
        time.sleep(0.05)


def _handshake_status(url: str, **kwargs) -> int:
    """The HTTP status of a WebSocket handshake with `url` (101: connected)."""
    from websockets.exceptions import InvalidStatus
    from websockets.sync.client import connect

    try:
        with connect(url, open_timeout=10, proxy=None, **kwargs) as ws:
            json.loads(ws.recv(timeout=10))  # the serverInfo: the protocol runs
            return 101
    except InvalidStatus as e:
        return e.response.status_code


def test_foxglove_live_holds_clients_to_the_http_servers_rules():
    """A token (when there is one) in the URL or an Authorization header, the served Host, one
    Host header, a Foxglove subprotocol: else the handshake is refused with a 4xx."""
    import socket

    sdk = {"subprotocols": ["foxglove.sdk.v1"]}
    with FoxgloveLive(port=0, token="s3cret") as live:
        base = f"ws://127.0.0.1:{live.port}"
        assert live.url == f"{base}/?token=s3cret"
        assert _handshake_status(live.url, **sdk) == 101
        assert _handshake_status(base, additional_headers={"Authorization": "Bearer s3cret"},
                                 **sdk) == 101
        assert _handshake_status(base, **sdk) == 401
        assert _handshake_status(f"{base}/?token=wrong", **sdk) == 401
        assert _handshake_status(live.url, subprotocols=["chat"]) == 400
        assert _handshake_status(live.url) == 400  # no subprotocol offered
        with socket.create_connection(("127.0.0.1", live.port), timeout=10) as raw:
            raw.sendall(b"GET /?token=s3cret HTTP/1.1\r\nHost: evil.example\r\n"
                        b"Upgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: "
                        b"dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
                        b"Sec-WebSocket-Protocol: foxglove.sdk.v1\r\n\r\n")
            assert raw.recv(100).startswith(b"HTTP/1.1 421 ")
        with socket.create_connection(("127.0.0.1", live.port), timeout=10) as raw:
            raw.sendall(b"GET /?token=s3cret HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                        b"Host: evil.example\r\nUpgrade: websocket\r\n"
                        b"Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
                        b"Sec-WebSocket-Version: 13\r\nSec-WebSocket-Protocol: foxglove.sdk.v1"
                        b"\r\n\r\n")
            assert raw.recv(100).startswith(b"HTTP/1.1 400 ")
    with FoxgloveLive(port=0) as live:  # loopback without --token: none needed
        assert live.token is None and _handshake_status(live.url, **sdk) == 101


def test_cli_foxglove_and_serve_share_one_token_off_loopback():
    """Off loopback --serve and --foxglove need a token: --token, or one made once for both
    (the address is not bound here: tests listen on loopback only)."""
    import argparse

    from corobot_drake.cli import ArgumentError, shared_token

    def args(**kw):
        return argparse.Namespace(**{"serve": False, "foxglove": None, "host": "127.0.0.1",
                                     "token": None, **kw})

    made = shared_token(args(foxglove=8765, serve=True, host="0.0.0.0"))
    assert made and len(made) >= 32
    assert shared_token(args(foxglove=8765, host="192.0.2.7")) not in (None, made)
    assert shared_token(args(foxglove=8765, host="0.0.0.0", token="T")) == "T"
    assert shared_token(args(foxglove=8765)) is None
    with pytest.raises(ArgumentError, match="--token must not be empty"):
        shared_token(args(foxglove=8765, token=" "))


def test_cli_foxglove_with_a_token_prints_the_url_carrying_it(capsys):
    assert main(["--headless", "--duration", "0.05", "--override", NO_CAMERA, "--foxglove",
                 "0", "--token", "s3cret"]) == 0
    url = capsys.readouterr().err.split("Foxglove: ")[1].split()[0]
    assert re.fullmatch(r"ws://127\.0\.0\.1:\d+/\?token=s3cret", url)


def test_cli_foxglove_on_every_address_names_it_for_other_machines(capsys):
    """As --serve's line: no client connects to 0.0.0.0, so this machine's name is given too."""
    import socket

    assert main(["--headless", "--duration", "0.05", "--override", NO_CAMERA, "--foxglove",
                 "0", "--host", "0.0.0.0", "--token", "s3cret"]) == 0
    err = capsys.readouterr().err
    port = re.search(r"Foxglove: ws://127\.0\.0\.1:(\d+)/\?token=s3cret ", err)[1]
    assert (f"  from other machines ws://{socket.gethostname()}:{port}/?token=s3cret  (or any of "
            "this machine's addresses)\n") in err


# --- the command line ------------------------------------------------------------------------


def test_cli_writes_the_replay_and_the_mcap_headless(tmp_path, capsys):
    html, mcap = tmp_path / "run.html", tmp_path / "run.mcap"
    assert main(["--headless", "--duration", "0.4", "--override", CURVE, "--override",
                 NO_CAMERA, "--record", str(html), "--mcap", str(mcap)]) == 0
    assert "set_animation" in {m["type"] for m in _meshcat_messages(html.read_text())}
    topics = read_mcap(mcap)
    assert len(topics["/odom"]) == round(0.4 / STATE_PERIOD) + 1
    assert "/camera/image/compressed" not in topics


@pytest.mark.parametrize("flag", ["--record", "--mcap"])
def test_cli_output_paths_are_checked(flag, tmp_path, capsys):
    assert main(["--headless", flag, str(tmp_path / "no" / "such" / "x")]) == 2
    assert main(["--headless", flag, str(tmp_path)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 2 and all(line.startswith(f"error: {flag}: ") for line in err)


def ir_sensor_alone(period: float = 0.05):
    """A BuiltSensor of an IR sensor `front` on robot `r` whose system is in no diagram:
    what its publisher reads (its `scan_state`, fixed by a test) and how often."""
    from corobot_drake.config.sensors import IrSensorConfig
    from corobot_drake.sensors.ir_sensor import IrSensor, IrSensorKind
    from corobot_drake.sensors.kind import BuiltSensor

    config = IrSensorConfig(scan_rate_hz=1.0 / period)
    system = IrSensor(config, None, [])
    return BuiltSensor(IrSensorKind(), "r", "front", config, system,
                       system.GetOutputPort("reading"), config.scan_rate_hz)


def test_ir_sensor_publisher_alone_publishes_each_scan_once():
    """An IR sensor's SensorPublisher on its own, its scan_state fixed: the look at t
    publishes a scan taken in [t - period, t), at the scan's time, with its range and rays,
    on the IR kind's two channels."""
    import io

    from pydrake.systems.analysis import Simulator

    from corobot_drake.recording.looks import SensorPublisher
    from corobot_drake.recording.publishers import FoxgloveSensorSink
    from corobot_drake.sensors.ir_sensor import DISTANCE, SCAN_TIME, scan_state_layout

    context = foxglove.Context()
    buffer = io.BytesIO()
    writer = foxglove.open_mcap(buffer, context=context)
    sensor = ir_sensor_alone()
    publisher = SensorPublisher(sensor, FoxgloveSensorSink(context, RobotNames("r"), sensor))
    simulator = Simulator(publisher)
    system_context = simulator.get_mutable_context()
    size, _, ends, hits = scan_state_layout(sensor.system.num_rays)
    scan = np.zeros(size)
    scan[[DISTANCE, SCAN_TIME]] = 0.4, 0.1
    scan[ends] = np.tile([1.0, 0.0, 0.0], sensor.system.num_rays)
    scan[hits] = 1.0
    publisher.get_input_port().FixValue(system_context, scan)
    simulator.AdvanceTo(0.22)  # looks at 0.05, 0.1, 0.15, 0.2 s: only 0.15 s sees the scan
    writer.close()
    buffer.seek(0)
    reader = make_reader(buffer)
    decode = _decoders(reader.get_summary())
    got = [(c.topic, m.log_time, decode[s.id](m.data)) for s, c, m in reader.iter_messages()]
    assert [(topic, ns) for topic, ns, _ in got] == [("/ir/front", 100_000_000),
                                                     ("/ir/front/rays", 100_000_000)]
    assert got[0][2]["range"] == 0.4 and got[0][2]["max_range"] == 0.762
    assert got[0][2]["frame_id"] == "ir_front"
    assert len(got[1][2].entities[0].lines[0].points) == 2 * sensor.system.num_rays


def test_cli_foxglove_on_a_taken_port_is_one_line(capsys):
    import socket

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        assert main(["--headless", "--duration", "0.1", "--foxglove", str(port)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: --foxglove: ")


def test_command_source_exports_its_command_log():
    """The CommandSource's `command_log` output (what /commands reads) is its log, with the
    latest reported status recorded: the same records as `Robot.command_log()`."""
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[SCRIPT, NO_CAMERA]))
    sim.advance(0.6)
    source = sim.robot()._parts.command_source
    log = source.GetOutputPort("command_log").Eval(source.GetMyContextFromRoot(sim.context))
    assert list(log) == sim.robot().command_log()
    assert [r.command for r in log] == ["SetPower", "Wait", "AllStop"]


def test_several_robots_are_namespaced(tmp_path):
    """Two robots: each one's topics and frames under its name, as ROS namespaces and tf
    prefixes; /tf and /scene shared."""
    two = ("robots: {corobot: {cameras: {front: {rgb: false}}, commands: [!AllStop {}]}, "
           "second: {pose: {translation: [0, 1.5, 0]},"
           " cameras: {front: {rgb: false}}, commands: [!SetPower {left: -1, right: -1}]}}")
    path = tmp_path / "two.mcap"
    with McapLog(path) as log:
        sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[two]), foxglove=log.context)
        sim.advance(0.2)
    topics = read_mcap(path)
    per_robot = {"odom", "joint_states", "drive_state", "commands", "ir/front", "ir/rear/rays",
                 "wheel_loads", "wheel_slip", "tip_margin"}
    assert {f"/{r}/{t}" for r in ("corobot", "second") for t in per_robot} <= set(topics)
    assert "/odom" not in topics and {"/tf", "/scene"} <= set(topics)
    tf = topics["/tf"][-1][2].transforms
    second = next(x for x in tf if x.child_frame_id == "second/base_link")
    assert second.parent_frame_id == "world" and second.translation.y == pytest.approx(1.5,
                                                                                      abs=0.01)
    assert {("second/base_link", "second/front_left_wheel"), ("corobot/base_link",
            "corobot/ir_rear")} <= {(x.parent_frame_id, x.child_frame_id) for x in tf}
    assert topics["/second/odom"][-1][2].body_frame_id == "second/base_link"



def test_a_robot_added_by_a_rebuild_is_recorded_under_its_name_and_the_first_keeps_its_own(
        tmp_path):
    """A run that started with the Corobot alone, rebuilt with a Burger beside it (ROS 2's
    SpawnEntity does this): the Corobot's topics and frames stay bare (/odom, base_link), the
    Burger's go under its name (/burger/odom, burger/base_link), as on ROS 2 (here each
    base_link hangs from world)."""
    first = load_scenario(DEFAULT_SCENARIO, overrides=[NO_CAMERA])
    both = load_scenario(data="robots: {burger: {robot: burger, pose: {translation: "
                         "[0.0, 1.0, 0.0]}}}", defaults=first)
    with McapLog(tmp_path / "run.mcap") as log:
        sim = Simulation(both, foxglove=log.context, started_with=tuple(first.robots))
        sim.advance_to(0.1)
    topics = read_mcap(tmp_path / "run.mcap")
    assert {"/odom", "/burger/odom", "/joint_states", "/burger/joint_states"} <= set(topics)
    assert not any(t.startswith("/corobot/") for t in topics)
    frames = {(t.parent_frame_id, t.child_frame_id)
              for _, _, m in topics["/tf"] for t in m.transforms}
    assert {("world", "base_link"), ("world", "burger/base_link")} <= frames
