"""The Robo-Magellan examples' parts without ROS: the contestant's course map (read as the
project's loader reads the scenario), its orange rule and obstacle rule, the referee's touch
geometry and scoring (test_ros2_magellan runs them together over ROS 2)."""

import importlib.util
import math
import sys

import numpy as np
import pytest

from conftest import REPO
from corobot_drake.config.scenario import load_scenario

COURSE = REPO / "scenarios" / "robo_magellan.yaml"


def _example(name: str):
    spec = importlib.util.spec_from_file_location(name, REPO / "examples" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # its dataclasses look their module up
    spec.loader.exec_module(module)
    return module


magellan, referee = _example("ros2_magellan"), _example("ros2_referee")


def test_the_course_map_is_the_scenarios_cones_bonus_first():
    course = magellan.load_course(COURSE)
    bodies = load_scenario(COURSE).world.bodies
    assert [name for name, _, _ in course] == ["cone_bonus_1", "cone_bonus_2", "cone_goal"]
    for name, x, y in course:
        assert (x, y) == tuple(bodies[name].pose.translation[:2])


def test_a_course_without_a_goal_cone_is_refused(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("world: {bodies: {cone_bonus_1: {pose: {translation: [1, 0, 0]}}}}")
    with pytest.raises(ValueError, match="needs one cone_goal"):
        magellan.load_course(path)


def test_orange_blobs_lit_and_shaded_and_nothing_else():
    image = np.zeros((240, 320, 3), np.uint8)
    image[:120] = (135, 186, 235)  # sky
    image[120:] = (65, 89, 56)  # grass
    image[60:130, 40:60] = (126, 50, 0)  # a cone in shade (as rendered)
    image[80:125, 200:210] = (250, 100, 0)  # one in the sun, farther
    image[30:130, 120:180] = (25, 38, 89)  # the blue barrel
    image[50:60, 300:304] = (204, 115, 38)  # brown (the giant box's colour): not a cone
    blobs = magellan.orange_blobs(image)
    assert [(round(c, 1), n) for c, n in blobs] == [(49.5, 70 * 20), (204.5, 45 * 10)]


def test_the_ir_tells_an_obstacle_from_the_cone_it_expects():
    driver = magellan.Driver(magellan.load_course(COURSE))  # cone_bonus_1 at (2, 1)
    yaw = math.atan2(1.0, 2.0)  # facing it
    far = magellan.Sensed(0.0, 0.0, 0.0, yaw, ir=0.3, bearings=[])
    assert driver.step(far) == (0.0, magellan.TURN * 1.0) and driver.mode == "turn_away"
    driver = magellan.Driver(magellan.load_course(COURSE))
    x, y = 2.0 - 0.5 * math.cos(yaw), 1.0 - 0.5 * math.sin(yaw)  # 0.5 m from its axis
    near = magellan.Sensed(0.0, x, y, yaw, ir=0.5 - 0.21, bearings=[0.0])
    v, _ = driver.step(near)
    assert driver.mode == "home" and v > 0  # the cone itself: homing on it


def test_touching_is_the_cones_side_within_reach_of_the_footprint():
    footprint, r = referee.FOOTPRINT, 0.1
    ahead = (footprint[0] / 2 + r + 0.04, 0.0)
    assert referee.gap((0.0, 0.0, 0.0), footprint, ahead, r) == pytest.approx(0.04)
    beside = (0.0, -(footprint[1] / 2 + r + 0.07))
    assert referee.gap((0.0, 0.0, 0.0), footprint, beside, r) == pytest.approx(0.07)
    # turned 90 deg, what was ahead is beside, (1, 2) m away
    turned = (1.0, 2.0, math.pi / 2)
    cone = (1.0 + ahead[1], 2.0 + ahead[0])
    assert referee.gap(turned, footprint, cone, r) == pytest.approx(0.04)
    corner = (footprint[0] / 2 + 0.3, footprint[1] / 2 + 0.4)  # off the corner: 0.5 to it
    assert referee.gap((0.0, 0.0, 0.0), footprint, corner, r) == pytest.approx(0.5 - r)


def test_the_score_is_the_time_times_the_bonus_factors_before_the_goal():
    card = referee.Scorecard(bonus_factor=0.8)
    card.look(2.0, [])  # the start
    card.look(5.0, ["cone_bonus_1"])
    card.look(6.0, ["cone_bonus_1"])  # counted once
    card.look(12.0, ["cone_goal"])
    card.look(13.0, ["cone_bonus_2"])  # after the finish: not counted
    result = card.result()
    assert result["finished"] and result["time"] == 10.0
    assert result["bonus_cones"] == ["cone_bonus_1"]
    assert result["score"] == pytest.approx(10.0 * 0.8)
    assert result["touched"] == {"cone_bonus_1": 3.0, "cone_goal": 10.0}
    unfinished = referee.Scorecard(bonus_factor=0.8)
    unfinished.look(0.0, ["cone_bonus_2"])
    assert unfinished.result()["score"] is None and unfinished.result()["bonus_cones"] == [
        "cone_bonus_2"]
