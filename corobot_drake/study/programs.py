"""Scripts generated per run from the run's seed, for tests whose commands are random, like
the book's drive test (the study's `drive_test`)."""

import dataclasses as dc

import numpy as np

from corobot_drake.config.scenario import DriveDistance, RotateDegrees


@dc.dataclass
class DriveTest:
    """The book's drive test: each loop rotates a random angle in [-45, 45] deg, drives a
    random 0.5-1.5 m, rotates 180 deg, drives back the same distance and rotates
    180 deg - angle, all at `power`. The legs are drawn as `analysis.drive_test` draws them
    (numpy's default_rng(seed)), so a seed gives the same legs in both."""

    loops: int = 3
    power: float = 0.2
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


COMMANDS_PER_LOOP = 5
