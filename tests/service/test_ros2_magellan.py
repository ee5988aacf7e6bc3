"""The Robo-Magellan course over ROS 2, as the book's chapter plans it: the contestant
(examples/ros2_magellan.py, standard topics only) and the referee (examples/ros2_referee.py,
the Simulation Interfaces' ground truth) each a process of its own, the simulation headless at
4x real time, all in a private network. The contestant touches every cone and finishes; the
referee scores it; the test holds the referee's word to the ground truth it reads itself."""

import json
import math
import subprocess
import sys

import pytest

pytest.importorskip("rclpy", reason="the [ros2] extra (tools/setup installs it)")
pytest.importorskip("simulation_interfaces.msg", reason="python -m corobot_drake.ros2.build")

from conftest import REPO
from ros2_probe import ONE_GRAPH_AT_A_TIME, WAIT, ros2_simulation

COURSE = REPO / "scenarios" / "robo_magellan.yaml"
RATE = "4"
"""Simulated s per wall-clock s: the course's ~26 s in ~7 s, with time to spare for the
contestant's reactions on a loaded machine (at `max` they lag by more simulated time)."""
TIME_LIMIT = 60.0
"""s (simulated): the course takes ~26 (three cones, ~9 m, a barrel gone round)."""
REACH = 0.305 / 2 + 0.1 + 0.05
"""m: the Corobot's base frame to a touched cone's axis, at most (half its length with the
wheels, the cone's radius, the touching distance)."""


def _run(path, *args):
    return subprocess.Popen([sys.executable, str(REPO / "examples" / path), *args],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


@ONE_GRAPH_AT_A_TIME
def test_the_contestant_finishes_the_course_and_the_referee_scores_it():
    from simulation_interfaces.msg import SimulationState
    from simulation_interfaces.srv import GetEntitiesStates, GetSimulationState

    with ros2_simulation([str(COURSE), "--headless", "--paused", "--rate", RATE],
                         serve=False) as (_, probe):
        contestant = _run("ros2_magellan.py", "--course", str(COURSE), "--verbose")
        referee = _run("ros2_referee.py", "--start", "--json", "--time-limit", str(TIME_LIMIT))
        try:
            said, _ = referee.communicate(timeout=3 * WAIT)
            drove, _ = contestant.communicate(timeout=WAIT)
        finally:
            for process in (referee, contestant):
                if process.poll() is None:
                    process.kill()
                    process.wait()
        assert referee.returncode == 0, said + drove
        assert contestant.returncode == 0, drove
        assert "cone_goal: touched: finished" in drove
        result = json.loads(said.splitlines()[-1])
        assert result["finished"]
        assert list(result["touched"]) == ["cone_bonus_1", "cone_bonus_2", "cone_goal"]  # in turn
        assert result["bonus_cones"] == ["cone_bonus_1", "cone_bonus_2"]
        assert 10.0 < result["time"] < TIME_LIMIT  # ~9 m at <= 0.5 m/s
        assert result["time"] == result["touched"]["cone_goal"]
        assert result["score"] == pytest.approx(result["time"] * 0.8 ** 2, rel=1e-12)
        # The ground truth, read here: paused by the referee, the robot touching the goal cone.
        state = probe.call("/get_simulation_state", GetSimulationState,
                           GetSimulationState.Request())
        assert state.state.state == SimulationState.STATE_PAUSED
        request = GetEntitiesStates.Request()
        request.filters.filter = "^(corobot|cone_goal)$"
        truth = probe.call("/get_entities_states", GetEntitiesStates, request)
        (robot, cone) = (truth.states[truth.entities.index(n)].pose.position
                         for n in ("corobot", "cone_goal"))
        assert math.hypot(cone.x - robot.x, cone.y - robot.y) < REACH
        stamp = truth.states[0].header.stamp
        assert stamp.sec + 1e-9 * stamp.nanosec >= result["time"]
