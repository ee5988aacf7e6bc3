"""An episode of GoToGoal: where the robot starts, where the goal is, where the boxes stand.

Everything is drawn from one numpy Generator (the env's `np_random`), so a seed gives one
layout. World frame, metres and radians. The giant box stands where the default scene has it
(`giant_box`); the task's boxes are `GoToGoalConfig.boxes` cubes, the first one usually on
the way to the goal, the others anywhere near; a box that finds no free place is parked out
of the way (`PARKING`), far beyond the IR sensors' range.
"""

from __future__ import annotations

import dataclasses as dc
import functools
import math

import numpy as np
from pydrake.common.yaml import yaml_load

from corobot_drake.resources import DEFAULT_SCENARIO

PARKING = (0.0, 50.0)
"""m: where a box that found no place stands (x, y of the first; the next ones 2 m apart in x)."""
_TRIES = 50
"""Rejection-sampling attempts per box before it is parked."""
_GOAL_TRIES = 10_000
"""Rejection-sampling attempts for the goal before the config is refused."""


@dc.dataclass(frozen=True)
class Layout:
    """One episode's start, goal and boxes (world frame)."""

    start: tuple[float, float, float]
    """x, y (m), yaw (rad) of the robot."""
    goal: tuple[float, float]
    """x, y (m) of the goal point."""
    boxes: tuple[tuple[float, float, float], ...]
    """x, y (m), yaw (rad) of each box's centre."""


@functools.cache
def giant_box() -> tuple[tuple[float, float, float], float]:
    """(centre (m, world frame), side m) of the giant box where the default scene has it
    (`resources.DEFAULT_SCENARIO`'s `world.bodies.giant_box`, read as written)."""
    body = yaml_load(filename=str(DEFAULT_SCENARIO))["world"]["bodies"]["giant_box"]
    return tuple(body["pose"]["translation"]), body["shape"]["size"][0]


def _giant_box_gap(x: float, y: float) -> float:
    """m from (x, y) to the giant box's footprint (0 inside)."""
    (cx, cy, _), size = giant_box()
    half = size / 2
    dx = max(abs(x - cx) - half, 0.0)
    dy = max(abs(y - cy) - half, 0.0)
    return math.hypot(dx, dy)


def draw_layout(rng: np.random.Generator, config) -> Layout:
    """A layout for `config` (a `GoToGoalConfig`) from `rng`."""
    sx, sy = rng.uniform(-config.start_spread, config.start_spread, 2)
    start = (float(sx), float(sy), float(rng.uniform(-math.pi, math.pi)))
    for _ in range(_GOAL_TRIES):
        bearing = rng.uniform(-math.pi, math.pi)
        distance = rng.uniform(*config.goal_distance)
        goal = (float(sx + distance * math.cos(bearing)), float(sy + distance * math.sin(bearing)))
        if _giant_box_gap(*goal) > config.goal_clearance:
            break
    else:  # the config's check leaves only a sliver of goals far enough out
        raise ValueError(f"GoToGoalConfig.goal_clearance: no goal {config.goal_clearance:g} m "
                         f"clear of the giant box in {_GOAL_TRIES} draws from start "
                         f"({sx:.3f}, {sy:.3f}): ask for less clearance or a farther goal")
    boxes = []
    for i in range(config.boxes):
        in_the_way = i == 0 and rng.uniform() < config.blocking_probability
        boxes.append(_place_box(rng, config, start, goal, boxes, in_the_way, i))
    return Layout(start, goal, tuple(boxes))


def _place_box(rng, config, start, goal, placed, in_the_way: bool, index: int):
    half_diagonal = config.box_size * math.sqrt(0.5)
    for _ in range(_TRIES):
        if in_the_way:  # on the straight line to the goal, a little to one side or the other
            f = rng.uniform(0.35, 0.65)
            side = rng.uniform(-config.blocking_offset, config.blocking_offset)
            dx, dy = goal[0] - start[0], goal[1] - start[1]
            length = math.hypot(dx, dy)
            x = start[0] + f * dx - side * dy / length
            y = start[1] + f * dy + side * dx / length
        else:
            dx, dy = rng.uniform(-config.box_area, config.box_area, 2)
            x, y = start[0] + dx, start[1] + dy
        yaw = float(rng.uniform(-math.pi / 4, math.pi / 4))
        if (math.hypot(x - start[0], y - start[1]) > config.start_clearance + half_diagonal
                and math.hypot(x - goal[0], y - goal[1]) > config.goal_clearance + half_diagonal
                and _giant_box_gap(x, y) > half_diagonal + config.goal_clearance
                and all(math.hypot(x - bx, y - by) > 2 * half_diagonal + config.goal_clearance
                        for bx, by, _ in placed)):
            return (float(x), float(y), yaw)
    return (PARKING[0] + 2.0 * index, PARKING[1], 0.0)
