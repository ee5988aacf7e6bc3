"""Shared helpers: build a simulation of the default scene with overrides; each test's tier.

The tests live in four tiers, a folder each, and each test carries its folder's marker:
`unit` (each system, loader and geometry routine alone: the daily tier, under two minutes
on two cores), `simulation` (the robot measured through whole simulations), `service` (the
front ends as a user meets them: HTTP, browser, recording, CLI, studies, ROS 2) and
`packaging` (the wheel, the tools, the hostile corpus, the docs' blocks). `pytest` runs all;
`pytest tests/unit` (or `-m unit`) the fast tier.
"""

from pathlib import Path

import pytest

from corobot_drake.config.scenario import load_scenario
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.simulation import Simulation, quiet_drake_warnings

REPO = Path(__file__).resolve().parent.parent

quiet_drake_warnings()

TIERS = ("unit", "simulation", "service", "packaging")


def pytest_collection_modifyitems(items):
    for item in items:
        tier = item.path.parent.name
        if tier not in TIERS:
            raise pytest.UsageError(f"{item.path}: a test file belongs in one of the tiers' "
                                    f"folders: {', '.join(f'tests/{t}/' for t in TIERS)}")
        item.add_marker(tier)


def make_sim(*overrides: str, scenario: Path = DEFAULT_SCENARIO,
             camera: bool = False) -> Simulation:
    """The default scene (or `scenario`) with YAML overrides merged on top.

    The robots' cameras are off unless `camera` (rendering 30 frames per simulated second
    made the drive tests 3x slower); tests of the camera ask for it.
    """
    scenario = load_scenario(scenario, overrides=list(overrides))
    if not camera:
        for robot in scenario.robots.values():
            for config in robot.cameras.values():
                config.rgb = False
    return Simulation(scenario)


@pytest.fixture
def sim() -> Simulation:
    return make_sim()


class Stepper:
    """A Simulator on one system alone whose periodic events have period `period` from 0:
    `tick()` takes the next of them (the k-th, 1-based, happens at (k - 1) period; the
    context then stands half a period later). Fix the inputs on `context` between ticks."""

    def __init__(self, system, period: float):
        from pydrake.systems.analysis import Simulator

        self.system, self.period, self.ticks = system, period, 0
        self.simulator = Simulator(system)
        self.context = self.simulator.get_mutable_context()

    def fix(self, port_name: str, value) -> None:
        self.system.GetInputPort(port_name).FixValue(self.context, value)

    def output(self, port_name: str):
        return self.system.GetOutputPort(port_name).Eval(self.context)

    def tick(self, n: int = 1) -> None:
        self.ticks += n
        self.simulator.AdvanceTo((self.ticks - 0.5) * self.period)

    @property
    def last_tick_time(self) -> float:
        """s: when the latest tick happened."""
        return (self.ticks - 1) * self.period


TWO_CAMERAS = ("robots: {corobot: {cameras: {"
               "front: {width: 64, height: 48, output_delay: 0}, "
               "rear: {width: 64, height: 48, output_delay: 0, X_PB: {base_frame: chassis, "
               "translation: [0, 0, 0.5], rotation: !Rpy {deg: [-90, 0, 90]}}}}}}")
"""The robot with a second camera, `rear`, 0.5 m above the chassis looking back (the front
one looks forward from the chassis' front): both 64 x 48, cheap to render, each frame
rendered on the plant's steps from initialization (no output delay)."""
