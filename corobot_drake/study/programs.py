"""Scripts a study writes per run (the study's program fields), for tests whose commands are
random, like the book's drive test (`drive_test`), or that also turn the robot, like driving
into the box behind it (`box_approach`). A grid or random path `<program>.<field>` (e.g.
`box_approach.power`) sets that field of the program for the run."""

import dataclasses as dc
import math

import numpy as np
from pydrake.common.schema import Transform
from pydrake.math import RigidTransform, RotationMatrix

from corobot_drake.config.scenario import DriveDistance, RotateDegrees, Scenario, SetPower
from corobot_drake.limits import DRIVE_POWER, Range, bound_of, bounded

LOOPS = Range(1, 100, why="loops of ~37 simulated s each at power 0.2")
APPROACH_ANGLE = Range(-90.0, 90.0, low_open=True, high_open=True, unit="deg",
                       why="from the box face's normal")
_TYPES = {float: "a number", int: "an integer", str: "text"}


def check_fields(program) -> str | None:
    """What is wrong with a program's fields (a grid value included): the first of a wrong
    type or out of its bound (`bounded` beside the field), or None."""
    for field in dc.fields(program):
        value = getattr(program, field.name)
        wanted = int | float if field.type is float else field.type  # an int is a float
        if isinstance(value, bool) or not isinstance(value, wanted):
            shown = "null" if value is None else repr(value)  # (a study's grid value)
            return f"{field.name}: expected {_TYPES[field.type]}, got {shown}"
        bound = bound_of(field)
        if bound is not None and (problem := bound.problem(value)):
            return f"{field.name}: {problem}"
    return None


def _robot(scenario: Scenario, field: str, name: str):
    robot = scenario.robots.get(name)
    if robot is None:
        raise ValueError(f"{field}: the scenario has no robot {name!r}")
    return robot


@dc.dataclass
class DriveTest:
    """The book's drive test: each loop rotates a random angle in [-45, 45] deg, drives a
    random 0.5-1.5 m, rotates 180 deg, drives back the same distance and rotates
    180 deg - angle, all at `power`. The legs are drawn as `lab.drive_test` draws them
    (numpy's default_rng(seed)), so a seed gives the same legs in both."""

    loops: int = bounded(3, LOOPS)
    power: float = bounded(0.2, DRIVE_POWER)
    robot: str = "corobot"

    def commands(self, seed: int) -> list:
        rng = np.random.default_rng(seed)
        commands = []
        for _ in range(self.loops):
            angle = float(rng.uniform(-45.0, 45.0))
            distance = float(rng.uniform(0.5, 1.5))
            commands += [RotateDegrees(angle, self.power), DriveDistance(distance, self.power),
                         RotateDegrees(180.0, self.power), DriveDistance(distance, self.power),
                         RotateDegrees(180.0 - angle, self.power)]
        return commands

    def check(self) -> str | None:
        """What is wrong with the fields, or None."""
        return check_fields(self)

    def apply(self, scenario: Scenario, seed: int) -> None:
        _robot(scenario, "drive_test", self.robot).commands = self.commands(seed)


COMMANDS_PER_LOOP = 5

DIRECTIONS = ("backwards", "forwards")


@dc.dataclass
class BoxApproach:
    """Drive at constant `power` into whatever is behind the robot's start (the giant box in
    the default scene), for the whole run: `backwards` as the robot starts, or `forwards`
    (turned 180 deg about its start position first), meeting the box's face square
    (`angle_deg` 0) or obliquely (the robot turned by `angle_deg` more, so it drives into the
    face at that angle from its normal)."""

    direction: str = "backwards"
    angle_deg: float = bounded(0.0, APPROACH_ANGLE)
    power: float = bounded(1.0, DRIVE_POWER)
    """In (0, 1]: the approach speed is power x top speed (0.61 m/s at 1)."""
    robot: str = "corobot"

    def check(self) -> str | None:
        if problem := check_fields(self):
            return problem
        if self.direction not in DIRECTIONS:
            return f"direction {self.direction!r} is not one of {', '.join(DIRECTIONS)}"
        return None

    def apply(self, scenario: Scenario, seed: int) -> None:
        robot = _robot(scenario, "box_approach", self.robot)
        turn = self.angle_deg + (180.0 if self.direction == "forwards" else 0.0)
        X_WB = robot.pose.GetDeterministicValue()
        turned = RigidTransform(RotationMatrix.MakeZRotation(math.radians(turn)))
        # About the start position: rotate the orientation, keep the translation.
        robot.pose = Transform(RigidTransform(
            turned.rotation() @ X_WB.rotation(), X_WB.translation()))
        power = self.power if self.direction == "forwards" else -self.power
        robot.commands = [SetPower(power, power)]


PROGRAMS = {"drive_test": DriveTest, "box_approach": BoxApproach}
"""Study field name -> its program's class."""
