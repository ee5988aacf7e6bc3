"""The ROS 2 tools a user runs beside the simulation, when it does not answer: the inspection
tool (`python -m corobot_drake.ros2`) and the examples (examples/ros2_square.py,
ros2_teleop.py) end at their `--timeout` with a line that says what they waited for. In a
private network (`ros2_probe`), against no simulation or a stand-in that never finishes."""

import os
import pty
import re
import subprocess
import sys
import threading

import pytest

pytest.importorskip("rclpy", reason="the [ros2] extra (tools/setup installs it)")
pytest.importorskip("corobot_interfaces.msg", reason="python -m corobot_drake.ros2.build")

from conftest import REPO
from ros2_probe import ONE_GRAPH_AT_A_TIME, Probe, private_domain

pytestmark = ONE_GRAPH_AT_A_TIME

HANG = 120
"""s (wall clock) after which a tool that should have ended at its --timeout is a hang."""


@pytest.fixture(scope="module")
def graph():
    """A private network and a domain of the module's own: yields the domain id."""
    with private_domain() as domain:
        yield domain


def run(args: list[str], **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, timeout=HANG,
                          **kwargs)


def test_the_inspection_tool_ends_at_its_timeout(graph):
    listed = run(["-m", "corobot_drake.ros2", "--timeout", "2", "list"])
    assert (listed.returncode, listed.stderr) == (1, (
        "error: no node /corobot_drake found in 2 s (is `python -m corobot_drake --ros2` "
        "running in this ROS_DOMAIN_ID?)\n"))


def test_the_watchdog_names_what_it_waited_for(capsys):
    """What ends the tool should rclpy itself stop answering (a starved machine)."""
    from corobot_drake.ros2.inspection import _Watchdog

    ended = threading.Event()
    status = []
    watchdog = _Watchdog(exit=lambda code: (status.append(code), ended.set()))
    watchdog.stage("ROS 2 to shut down", 0.05, 0)
    assert ended.wait(10)
    assert status == [0]
    assert capsys.readouterr().err == ("error: still waiting for ROS 2 to shut down after "
                                       "0.05 s (a starved machine?): stopped\n")
    watchdog.stage("`list` to finish", 60)
    watchdog.stop()  # in time: nothing said


def test_ros2_square_says_which_goal_the_simulation_left_unanswered(graph):
    """A stand-in for the simulation accepts the drive and never reports on it."""
    from corobot_interfaces.action import DriveDistance, RotateDegrees
    from rclpy.action import ActionServer
    from rclpy.task import Future

    never = Future()

    async def never_ends(goal_handle):  # waits without holding an executor thread
        await never

    stand_in = Probe(graph, name="corobot_drake")
    servers = [ActionServer(stand_in.node, DriveDistance, "/drive_distance", never_ends),
               ActionServer(stand_in.node, RotateDegrees, "/rotate_degrees", never_ends)]
    try:
        square = run([str(REPO / "examples" / "ros2_square.py"), "--timeout", "3"])
    finally:
        stand_in.close()  # the goal never ends: nothing runs after the executor's shutdown
        for server in servers:
            server.destroy()
    assert square.returncode == 1
    assert re.fullmatch(r"error: leg 1: drive 1 m: no (feedback nor result|answer to the goal) "
                        r"in 3 s \(is the simulation stopped, or the machine starved\?\)\n",
                        square.stderr), square.stderr


def test_ros2_teleop_says_nobody_listens(graph):
    """No simulation: the keys would go nowhere (a terminal of its own, as a user's)."""
    terminal, user = pty.openpty()
    try:
        teleop = run([str(REPO / "examples" / "ros2_teleop.py"), "--timeout", "2"], stdin=user)
    finally:
        os.close(user)
        os.close(terminal)
    assert (teleop.returncode, teleop.stderr) == (1, (
        "error: no subscriber on /cmd_vel in 2 s (is `python -m corobot_drake --ros2` "
        "running in this ROS_DOMAIN_ID?)\n"))


EXAMPLES = ["ros2_square", "ros2_teleop", "ros2_magellan", "ros2_referee"]


def test_the_examples_refuse_a_ros2_environment_in_one_line(graph):
    """A domain id or a discovery range rcl would not take: the example's line and exit 2,
    before any DDS (a domain id of `abc` was an RCLError traceback and 300 Fast DDS errors;
    BOGUS, a wait of the whole timeout blaming the simulation)."""
    wrong = {"ROS_DOMAIN_ID": ("abc", "ROS_DOMAIN_ID=abc: must be a whole number in [0, 232] "
                                      "(0-101 are clear of the ephemeral ports)"),
             "ROS_AUTOMATIC_DISCOVERY_RANGE": (
                 "BOGUS", "ROS_AUTOMATIC_DISCOVERY_RANGE=BOGUS: must be one of LOCALHOST, "
                 "SUBNET, OFF, SYSTEM_DEFAULT (or unset: LOCALHOST)")}
    for variable, (value, line) in wrong.items():
        for example in EXAMPLES:
            ended = run([str(REPO / "examples" / f"{example}.py"), "--timeout", "30"],
                        env={**os.environ, variable: value}, stdin=subprocess.DEVNULL)
            assert (ended.returncode, ended.stderr, ended.stdout) == (
                2, f"error: examples/{example}.py: {line}\n", ""), (example, variable)
