"""Shared helpers: build a simulation of the default scene with overrides."""

from pathlib import Path

import pytest

from corobot_drake.config.scenario import load_scenario
from corobot_drake.simulation import Simulation, quiet_drake_warnings

REPO = Path(__file__).resolve().parent.parent
DEFAULT_SCENARIO = REPO / "scenarios" / "corobot.yaml"

quiet_drake_warnings()


def make_sim(*overrides: str, scenario: Path = DEFAULT_SCENARIO,
             camera: bool = False) -> Simulation:
    """The default scene (or `scenario`) with YAML overrides merged on top.

    The robots' cameras are off unless `camera` (rendering 30 frames per simulated second
    made the drive tests 3x slower); tests of the camera ask for it.
    """
    scenario = load_scenario(scenario, overrides=list(overrides))
    if not camera:
        for robot in scenario.robots.values():
            robot.camera.rgb = False
    return Simulation(scenario)


@pytest.fixture
def sim() -> Simulation:
    return make_sim()
