"""What the node's line says about where ROS 2 discovery reaches (`graph.discovery_reach`: no
DDS), with ROS_STATIC_PEERS: static peers are discovered over the network under LOCALHOST as
under SUBNET (ROS 2's "Improved Dynamic Discovery"), so the line names them and warns."""

from corobot_drake.ros2.graph import discovery_reach

PEERS = {"ROS_STATIC_PEERS": "192.168.1.5; robot.example.org;"}
OPEN = ("any ROS 2 node on the network with this domain id can read the topics and drive the "
        "robot")
REACHED = ("warning: ROS 2 static peers 192.168.1.5, robot.example.org (ROS_STATIC_PEERS) are "
           "reached over the network: a ROS 2 node there with this domain id can read the "
           "topics and drive the robot")


def test_without_static_peers_the_range_alone():
    assert discovery_reach("LOCALHOST", {}) == ("LOCALHOST", [])
    assert discovery_reach("LOCALHOST", {"ROS_STATIC_PEERS": " ; "}) == ("LOCALHOST", [])
    assert discovery_reach("SUBNET", {}) == (
        "SUBNET", [f"warning: ROS 2 discovery SUBNET: {OPEN}"])


def test_static_peers_are_named_and_warned_about_under_localhost():
    """It said `discovery LOCALHOST`, no warning, while the peers communicate."""
    assert discovery_reach("LOCALHOST", PEERS) == (
        "LOCALHOST and the static peers 192.168.1.5, robot.example.org", [REACHED])
    assert discovery_reach("SUBNET", PEERS) == (
        "SUBNET and the static peers 192.168.1.5, robot.example.org",
        [f"warning: ROS 2 discovery SUBNET: {OPEN}", REACHED])


def test_off_discovers_no_static_peer():
    assert discovery_reach("OFF", PEERS) == (
        "OFF (ROS_STATIC_PEERS 192.168.1.5, robot.example.org unused: OFF discovers no node)",
        [])
