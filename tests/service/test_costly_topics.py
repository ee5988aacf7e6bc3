"""Costly topics cost nothing unwatched: in a simulation with its ROS 2 topics on a bus (no
DDS: a sink that says which topics have a subscriber, as the live node's does from Fast DDS'
subscription counts), the camera renders no frame while nobody subscribes to its image topic,
and renders each frame once someone does."""

import collections
from functools import partial

import pytest

pytest.importorskip("rosbags", reason="the [ros2] extra (tools/setup installs it)")

from conftest import CENIC, DEFAULT_SCENARIO
from corobot_drake.config.scenario import load_scenario
from corobot_drake.config.sensors import RENDERER_NAME
from corobot_drake.ros2.bus import Bus
from corobot_drake.ros2.publishers import add_ros2_topics
from corobot_drake.simulation import Simulation

IMAGE, INFO = "/camera/image_raw", "/camera/camera_info"


class Subscriptions:
    """A bus sink standing for the live node's (`node.LiveSink`): a topic is watched while it
    is in `subscribed`; it counts the messages written on each."""

    def __init__(self):
        self.subscribed: set[str] = set()
        self.written = collections.Counter()

    def declare(self, topic, msgtype, qos):
        pass

    def write(self, topic, data, t_ns):
        self.written[topic] += 1

    def watched(self, topic) -> bool:
        return topic in self.subscribed


def test_the_camera_renders_no_frame_until_its_image_topic_has_a_subscriber():
    """At 10 frames a second under CENIC, the GL camera's frames render on its worker
    (`RenderWorker.renders` counts them): none in the first 0.5 s with /tf subscribed but not
    the image, then one per frame, each published, once /camera/image_raw has a subscriber;
    none again once it has gone."""
    sink = Subscriptions()
    scenario = load_scenario(DEFAULT_SCENARIO, overrides=[
        CENIC, "robots: {corobot: {cameras: {front: {fps: 10}}}}"])
    sim = Simulation(scenario, extras=[partial(add_ros2_topics, Bus([sink]))])
    if sim.station.renderers[RENDERER_NAME] != "RenderEngineGl":
        pytest.skip("no GL renderer here: VTK cameras render in place, on demand")
    worker = sim.station.diagram.GetSubsystemByName("corobot.camera.front.hold")._worker
    assert worker is not None, "a GL camera under CENIC renders on a worker"
    sink.subscribed.add("/tf")
    sim.advance(0.5)
    assert worker.renders == 0
    assert sink.written[IMAGE] == sink.written[INFO] == 0 and sink.written["/tf"] > 0
    sink.subscribed.add(IMAGE)
    sim.advance(0.5)
    # the frames captured at 0.5005 ... 0.9005 s (capture offset 0.5 ms, out 30 ms later):
    # each rendered once and published, its camera_info with it
    assert worker.renders == sink.written[IMAGE] == sink.written[INFO] == 5
    sink.subscribed.discard(IMAGE)
    rendered = worker.renders
    sim.advance(0.5)
    assert worker.renders == rendered
