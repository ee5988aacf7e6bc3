"""The example files users open beside a run name only what the project publishes.

examples/corobot.rviz (RViz 2): every topic a display subscribes to is one of the ROS 2
node's (`ros2.interfaces.TOPICS`, and the sensor kinds' `ros2_channels` for the sensors of
scenarios/corobot.yaml and corobot_lidar.yaml, whose lidar the LaserScan display shows),
subscribed Reliable as the node offers by default (a latched topic also Transient Local),
and its frames are the node's (odom, base_link). examples/corobot.foxglove-layout.json: every
topic its panels read and every frame they follow is in a short MCAP recording of
scenarios/corobot_lidar.yaml (its channels, and its /tf's frames)."""

import json
import re

import pytest
import yaml

from conftest import REPO
from corobot_drake import topics
from corobot_drake.config.scenario import load_scenario
from corobot_drake.ros2 import interfaces
from corobot_drake.ros2.publishers import ODOM_FRAME, WORLD_FRAME
from corobot_drake.sensors.registry import KINDS

RVIZ = REPO / "examples" / "corobot.rviz"
LAYOUT = REPO / "examples" / "corobot.foxglove-layout.json"
SCENARIOS = ("corobot.yaml", "corobot_lidar.yaml")


def ros2_topics() -> dict[str, str]:
    """{/topic: QoS name} the node publishes for the Corobot of the shipped scenarios."""
    out = {f"/{t.name}": t.qos.value for t in interfaces.TOPICS}
    for name in SCENARIOS:
        robot = load_scenario(REPO / "scenarios" / name).robots["corobot"]
        for kind in KINDS:
            for sensor, config in getattr(robot, kind.field).items():
                if kind.enabled(config):
                    for sub, (_, qos) in kind.ros2_channels().items():
                        out["/" + kind.topic_name(sensor) + (f"/{sub}" if sub else "")] = qos
    return out


def subscriptions(node) -> list[dict]:
    """Every `Topic` or `Description Topic` mapping of an RViz config, depth first."""
    if isinstance(node, dict):
        found = [v for k, v in node.items() if k in ("Topic", "Description Topic")]
        return found + [s for v in node.values() for s in subscriptions(v)]
    if isinstance(node, list):
        return [s for v in node for s in subscriptions(v)]
    return []


def test_the_rviz_config_subscribes_to_the_nodes_topics_reliably():
    config = yaml.safe_load(RVIZ.read_text())
    published = ros2_topics()
    subscribed = subscriptions(config)
    names = {s["Value"] for s in subscribed}
    assert {"/robot_description", "/odom", "/ir/front", "/ir/rear", "/scan/top",
            "/camera/image_raw"} <= names
    for sub in subscribed:
        assert sub["Value"] in published, f"{sub['Value']}: not published by the node"
        assert sub["Reliability Policy"] == "Reliable", sub
        latched = published[sub["Value"]] == interfaces.Qos.LATCHED.value
        assert (sub["Durability Policy"] == "Transient Local") == latched, sub
    kinds = {d["Class"].split("/")[-1] for d in config["Visualization Manager"]["Displays"]}
    assert {"RobotModel", "TF", "LaserScan", "Range", "Image", "Odometry"} <= kinds


def test_the_rviz_configs_frames_are_the_nodes():
    manager = yaml.safe_load(RVIZ.read_text())["Visualization Manager"]
    assert manager["Global Options"]["Fixed Frame"] == ODOM_FRAME
    assert manager["Views"]["Current"]["Target Frame"] == topics.CHASSIS_FRAME


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    """(channel topics, /tf's raw messages) of 0.3 s of corobot_lidar.yaml as MCAP."""
    from mcap.reader import make_reader

    from corobot_drake.recording.mcap_log import McapLog
    from corobot_drake.simulation import Simulation

    path = tmp_path_factory.mktemp("layout") / "run.mcap"
    with McapLog(str(path)) as log:
        sim = Simulation.from_file(REPO / "scenarios" / "corobot_lidar.yaml",
                                   foxglove=log.context)
        sim.advance(0.3)
    with open(path, "rb") as f:
        reader = make_reader(f)
        tf = [m.data for _, c, m in reader.iter_messages(topics=["/tf"])]
        f.seek(0)
        channels = {c.topic for c in make_reader(f).get_summary().channels.values()}
    return channels, tf


def layout_topics(layout: dict) -> set[str]:
    """The topics a Foxglove layout's panels read: 3D topics, image and calibration topics,
    and the topic part of each plot path (`/odom.pose.position.x`)."""
    found = set()
    for panel in layout["configById"].values():
        found |= set(panel.get("topics", {}))
        found |= {v for k, v in panel.get("imageMode", {}).items() if k.endswith("Topic")}
        found |= {re.match(r"[^.{\[]+", p["value"]).group(0) for p in panel.get("paths", [])}
    return found


def test_the_foxglove_layout_reads_the_recordings_topics(recording):
    channels, _ = recording
    layout = json.loads(LAYOUT.read_text())
    read = layout_topics(layout)
    assert {"/odom", "/camera/image/compressed", "/scan/top", "/scene"} <= read
    assert read <= channels, read - channels
    panels = {key.split("!")[0] for key in layout["configById"]}
    assert {"3D", "Image", "Plot"} <= panels


def test_the_foxglove_layouts_frames_are_the_recordings(recording):
    _, tf = recording
    layout = json.loads(LAYOUT.read_text())
    frames = {WORLD_FRAME, topics.CHASSIS_FRAME}
    for panel in layout["configById"].values():
        named = {panel["followTf"]} if panel.get("followTf") else set()
        named |= {k.removeprefix("frame:") for k in panel.get("transforms", {})}
        named |= {layer["frameId"] for layer in panel.get("layers", {}).values()
                  if "frameId" in layer}
        assert named <= frames, named
        for frame in named:  # each is in a /tf message (protobuf: its id stands as bytes)
            assert any(frame.encode() in data for data in tf), frame
