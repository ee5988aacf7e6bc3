"""A robot added to a running simulation on ROS 2, without DDS: its names (`topics.robot_names`:
the scenario's robots keep theirs, an added one is under its name), the bus that forgets a
deleted robot's topics (`Bus.building`), and the topics of a simulation rebuilt with one more
robot and then one less, as SpawnEntity and DeleteEntity rebuild it. The node's side, from
another process: tests/service/test_ros2_simulation.py."""

import functools

import pytest

pytest.importorskip("rosbags", reason="the [ros2] extra (tools/setup installs it)")
pytest.importorskip("rclpy", reason="the [ros2] extra (tools/setup installs it)")
pytest.importorskip("corobot_interfaces.msg", reason="python -m corobot_drake.ros2.build")

from rclpy.serialization import deserialize_message

from corobot_drake import topics as tp
from corobot_drake.config import scenario as sc
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.ros2.bus import Bus
from corobot_drake.ros2.graph import ros_type
from corobot_drake.ros2.publishers import add_ros2_topics
from corobot_drake.simulation import Simulation

QUIET = "robots: {corobot: {commands: [], cameras: {front: {rgb: false}}}}"
BURGER = ("robots: {burger: {robot: burger, pose: {translation: [0.0, 1.0, 0.0]}, "
          "commands: [!SetVelocity {linear: 0.2, angular: 0.0}]}}")


class Memory:
    """A bus sink that keeps every message ({topic: [decoded message]}) and what it was told
    to forget."""

    def __init__(self):
        self.types, self.messages, self.forgotten = {}, {}, []

    def declare(self, topic, msgtype, qos):
        self.types[topic], self.messages[topic] = msgtype, []

    def write(self, topic, data, t_ns):
        self.messages[topic].append(deserialize_message(bytes(data),
                                                        ros_type(self.types[topic])))

    def forget(self, topic):
        self.forgotten.append(topic)


class Bag:
    """A sink without `forget` (a bag keeps every topic)."""

    def declare(self, topic, msgtype, qos):
        pass

    def write(self, topic, data, t_ns):
        pass


def test_robot_names_keep_the_first_robots_and_put_an_added_one_under_its_name():
    alone = ("corobot",)
    assert tp.robot_names("corobot", alone).topic("odom") == "/odom"
    assert tp.robot_names("burger", alone, "base").topic("odom") == "/burger/odom"
    assert tp.robot_names("burger", alone, "base").base_frame() == "burger/base_link"
    pair = ("a", "b")
    assert [tp.robot_names(r, pair).topic("cmd_vel") for r in pair] == ["/a/cmd_vel",
                                                                       "/b/cmd_vel"]


def test_the_bus_forgets_a_topic_the_next_build_lacks_and_keeps_its_first_robots():
    memory, bag = Memory(), Bag()
    bus = Bus([memory, bag])
    with bus.building(["a"]):
        bus.channel("/odom", "nav_msgs/msg/Odometry", None)
        bus.channel("/b/odom", "nav_msgs/msg/Odometry", None)
    with bus.building(["a", "b"]):
        bus.channel("/odom", "nav_msgs/msg/Odometry", None)
    assert memory.forgotten == ["/b/odom"] and bus.first_robots == ("a",)
    with pytest.raises(RuntimeError), bus.building(["a"]):  # a build that fails forgets
        raise RuntimeError("no station")  # nothing (the simulation it would replace goes on)
    assert memory.forgotten == ["/b/odom"]


def _with(saved: sc.Scenario, layer: str | None = None, without: str | None = None):
    scenario = sc.load_scenario(data=layer, defaults=saved) if layer else saved
    if without:
        del scenario.robots[without]
    return scenario


def test_a_robot_added_then_deleted_by_rebuilding_has_its_topics_then_none():
    memory = Memory()
    bus = Bus([memory])
    extras = [functools.partial(add_ros2_topics, bus)]
    sim = Simulation(sc.load_scenario(DEFAULT_SCENARIO, overrides=[QUIET]), extras=extras)
    sim.advance_to(0.1)
    first = set(bus.topics)
    sim = Simulation(_with(sim.saved_scenario(), BURGER), extras=extras)  # as SpawnEntity
    assert sim.time == pytest.approx(0.1)
    added = set(bus.topics) - first
    assert added and all(t.startswith("/burger/") for t in added)  # the Corobot's stay bare
    assert {"/burger/odom", "/burger/scan/scan", "/burger/robot_description"} <= added
    sim.advance_to(0.5)
    odom = memory.messages["/burger/odom"][-1]
    assert (odom.header.frame_id, odom.child_frame_id) == ("burger/odom", "burger/base_link")
    assert 0.01 < odom.pose.pose.position.x < 0.1  # driven at 0.2 m/s for 0.4 s, from x = 0
    static = memory.messages["/tf_static"][-1]  # one tree: each odom hangs from the world
    assert {("world", "odom"), ("world", "burger/odom")} <= {
        (t.header.frame_id, t.child_frame_id) for t in static.transforms}
    assert memory.forgotten == []
    sim = Simulation(_with(sim.saved_scenario(), without="burger"), extras=extras)  # deleted
    assert sorted(memory.forgotten) == sorted(added)
    assert not any(t.header.frame_id == "world"
                   for t in memory.messages["/tf_static"][-1].transforms)


def test_a_bag_takes_a_topic_declared_while_it_is_written(tmp_path):
    """A robot spawned while `--rosbag` records: its topics' connections are added by the
    bag's writing thread in turn (the MCAP writer puts them in the chunk it writes to), and
    the bag reads back whole."""
    from rosbags.rosbag2 import Reader

    from corobot_drake.ros2.bag import BagSink
    from corobot_drake.ros2.bus import typestore
    from corobot_drake.ros2.interfaces import Qos

    store = typestore()
    Clock = store.types["rosgraph_msgs/msg/Clock"]
    Time = store.types["builtin_interfaces/msg/Time"]
    bag = BagSink(tmp_path / "bag")
    bus = Bus([bag])
    clock = bus.channel("/clock", "rosgraph_msgs/msg/Clock", Qos.RELIABLE)
    for k in range(500):
        sec, nanosec = divmod(k * 10_000_000, 1_000_000_000)
        clock.publish(k * 10_000_000, Clock(clock=Time(sec=sec, nanosec=nanosec)))
        if k == 250:
            late = bus.channel("/burger/clock", "rosgraph_msgs/msg/Clock", Qos.RELIABLE)
        if k >= 250:
            late.publish(k * 10_000_000, Clock(clock=Time(sec=0, nanosec=k)))
    bag.close()
    with Reader(tmp_path / "bag") as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        assert counts == {"/clock": 500, "/burger/clock": 250}
        assert sum(1 for _ in reader.messages()) == 750


def test_a_resource_names_a_robot_by_its_name_or_its_file(tmp_path):
    """SpawnEntity's `robot_resource`: what a scenario's `robots.<name>.robot` would say, or
    None for a world body or a model file."""
    pytest.importorskip("simulation_interfaces.msg", reason="python -m corobot_drake.ros2.build")
    from simulation_interfaces.msg import Resource

    from corobot_drake.robots import ROBOTS
    from corobot_drake.ros2.simulation_services import RefusedError, robot_resource

    copy = tmp_path / "my_robot.yaml"  # a robot file of the user's (its model beside it)
    copy.write_text(ROBOTS["burger"].read_text())
    body = tmp_path / "crate.yaml"
    body.write_text("shape: !Box {size: [0.2, 0.2, 0.2]}\nmass: 1.0\n")
    assert robot_resource(Resource(uri="burger")) == "burger"
    assert robot_resource(Resource(uri="turtlebot")) == "turtlebot"  # the loader says it is none
    assert robot_resource(Resource(uri=f"file://{copy}")) == str(copy)
    assert robot_resource(Resource(uri=str(body))) is None
    assert robot_resource(Resource(uri="/models/crate.sdf")) is None
    assert robot_resource(Resource(resource_string="shape: !Sphere {radius: 0.1}")) is None
    with pytest.raises(RefusedError, match="a robot file: give its uri instead"):
        robot_resource(Resource(resource_string=copy.read_text()))


def test_a_robot_file_that_does_not_load_is_refused_with_the_loaders_line(tmp_path):
    pytest.importorskip("simulation_interfaces.msg", reason="python -m corobot_drake.ros2.build")
    from simulation_interfaces.srv import SpawnEntity

    from corobot_drake.ros2.simulation_services import robot_refusal

    S = SpawnEntity.Response
    broken = tmp_path / "robot.yaml"
    broken.write_text("model: nowhere.sdf\nwheels: {left: [a], right: [b]}\n")
    saved = sc.load_scenario(DEFAULT_SCENARIO, overrides=[QUIET])
    cases = ((f"robots: {{b: {{robot: {broken}}}}}", S.RESOURCE_PARSE_ERROR,
              f"entity_resource.uri: {broken}:1: model: nowhere.sdf: cannot read the file"),
             ("robots: {b: {robot: burger}}", S.INVALID_POSE,  # at the Corobot's origin
              "initial_pose: robot 'b' starts "))
    for layer, code, words in cases:
        with pytest.raises(sc.ScenarioError) as raised:
            sc.load_scenario(data=layer, defaults=saved)
        refused = robot_refusal(raised.value)
        assert refused.code == code and str(refused).startswith(words), str(refused)
