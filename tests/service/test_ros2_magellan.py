"""The Robo-Magellan course over ROS 2, as the book's chapter plans it: the contestant
(examples/ros2_magellan.py, standard topics only) and the referee (examples/ros2_referee.py,
the Simulation Interfaces' ground truth) each a process of its own, the simulation headless at
4x real time, all in a private network. The contestant touches every cone and finishes; the
referee scores it; the test holds the referee's word to the ground truth it reads itself.

The three commands are docs/magellan.md's ("Run it"), read from the page, so its block runs
here (the tutorials' test leaves it to this one): the simulation headless, the contestant
`--verbose`, the referee `--json` with a time limit, for the test to read them."""

import json
import math
import re
import shlex
import subprocess
import sys

import pytest

pytest.importorskip("rclpy", reason="the [ros2] extra (tools/setup installs it)")
pytest.importorskip("simulation_interfaces.msg", reason="python -m corobot_drake.ros2.build")

from conftest import REPO
from ros2_probe import ONE_GRAPH_AT_A_TIME, WAIT, ros2_simulation

PAGE = REPO / "docs" / "magellan.md"
TIME_LIMIT = 60.0
"""s (simulated): the course takes ~26 (three cones, ~9 m, a barrel gone round)."""
REACH = 0.305 / 2 + 0.1 + 0.05
"""m: the Corobot's base frame to a touched cone's axis, at most (half its length with the
wheels, the cone's radius, the touching distance)."""


def page_commands() -> list[list[str]]:
    """The arguments after `python` of the page's "Run it" block's three commands (`&` gone):
    the simulation's, the contestant's and the referee's."""
    text = PAGE.read_text()
    block = re.search(r"^```sh\n(.*?)^```$", text[text.index("## Run it"):], re.M | re.S)[1]
    return [[a for a in argv[1:] if a != "&"]
            for argv in map(lambda line: shlex.split(line, comments=True), block.splitlines())
            if argv]


def _run(argv, *args):
    return subprocess.Popen([sys.executable, str(REPO / argv[0]), *argv[1:], *args],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


@ONE_GRAPH_AT_A_TIME
def test_the_contestant_finishes_the_course_and_the_referee_scores_it():
    from simulation_interfaces.msg import SimulationState
    from simulation_interfaces.srv import GetEntitiesStates, GetSimulationState

    simulation, contestant, referee = page_commands()
    # At 4x real time the course's ~26 s take ~7 s, with time to spare for the contestant's
    # reactions on a loaded machine (at `max` they lag by more simulated time).
    assert simulation == ["-m", "corobot_drake", "robo_magellan.yaml", "--ros2", "--paused",
                          "--rate", "4"]
    assert [contestant[0], referee[0]] == ["examples/ros2_magellan.py", "examples/ros2_referee.py"]
    with ros2_simulation([a for a in simulation[2:] if a != "--ros2"] + ["--headless"],
                         serve=False) as (_, probe):
        contestant = _run(contestant, "--verbose")
        referee = _run(referee, "--json", "--time-limit", str(TIME_LIMIT))
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
