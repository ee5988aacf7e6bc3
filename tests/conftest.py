"""Shared helpers: build a simulation of the default scene with overrides."""

from pathlib import Path

import pytest

from corobot_drake.scenario import load_scenario
from corobot_drake.simulation import Simulation, quiet_drake_warnings

REPO = Path(__file__).resolve().parent.parent
DEFAULT_SCENARIO = REPO / "scenarios" / "corobot.yaml"

quiet_drake_warnings()


def make_sim(*overrides: str, scenario: Path = DEFAULT_SCENARIO) -> Simulation:
    """The default scene (or `scenario`) with YAML overrides merged on top."""
    return Simulation(load_scenario(scenario, overrides=list(overrides)))


@pytest.fixture
def sim() -> Simulation:
    return make_sim()
