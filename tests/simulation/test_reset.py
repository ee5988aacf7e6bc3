"""Simulation.reset: a run after a reset is bit for bit the run of a freshly built
simulation, for the same scenario and for one that differs in per-run values only."""

import math

import numpy as np
import pytest

from corobot_drake.config.scenario import load_scenario
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.simulation import Simulation, diagram_key

# The sharp_gp2d12 model draws seeded noise, so the seed reaches the readings; the camera is
# off (it has nothing per-run, and rendering is slow).
BASE = ("robots: {corobot: {cameras: {front: {rgb: false}}, "
        "ir_sensors: {rear: {model: sharp_gp2d12}}, "
        "commands: [!SetPower {left: -0.4, right: -0.3}, !Wait {seconds: 0.5}, "
        "!RotateDegrees {degrees: 30, power: 0.6}]}}")
OTHER_RUN = ["random_seed: 7",
             "robots: {corobot: {pose: {translation: [0.2, 0.3, 0]}, "
             "commands: [!DriveDistance {distance: 0.3, power: 0.8}]}}"]


def scenario(*more: str):
    return load_scenario(DEFAULT_SCENARIO, overrides=[BASE, *more])


def run(sim: Simulation, seconds: float = 1.5):
    sim.advance(seconds)
    robot = sim.robot()
    summary = sim.summary()
    for key in ("realtime_factor", "wall_seconds"):
        summary.pop(key)
    return summary, robot.run_log(), robot.ir("rear")


def assert_same(a, b):
    assert a[0] == b[0]
    np.testing.assert_array_equal(a[1], b[1])
    assert a[2] == b[2]


def test_reset_replays_the_same_run_bit_for_bit():
    sim = Simulation(scenario())
    first = run(sim)
    assert first[0]["robots"]["corobot"]["commands"][-1]["command"] == "RotateDegrees"
    sim.reset()
    assert sim.time == 0.0
    assert_same(run(sim), first)


def test_reset_to_another_run_of_the_diagram_equals_a_fresh_build():
    other = scenario(*OTHER_RUN)
    assert diagram_key(other) == diagram_key(scenario())
    sim = Simulation(scenario())
    run(sim)
    sim.reset(other)
    reset_run = run(sim)
    fresh_run = run(Simulation(other))
    assert_same(reset_run, fresh_run)
    pose = reset_run[0]["robots"]["corobot"]["pose"]
    assert pose["x"] > 0.4  # it started at 0.2 and drove 0.3 m forward: the new run's values


def test_reset_refuses_a_scenario_that_needs_another_diagram():
    sim = Simulation(scenario())
    with pytest.raises(ValueError, match="build a new Simulation"):
        sim.reset(scenario("robots: {corobot: {drive: {motor_torque_scaling: 6.0}}}"))
    # The simulation's own scenario changed in place is refused alike (the diagram would
    # still drive at the built scaling).
    sim.scenario.robots["corobot"].drive.motor_torque_scaling = 6.0
    with pytest.raises(ValueError, match="build a new Simulation"):
        sim.reset()


def test_reset_checks_its_scenario_as_the_constructor_does():
    """A scenario made bad in Python (the robot sunk 0.5 m: a per-run value, so the diagram
    would take it) is refused by `reset` with the constructor's very error, also when changed
    in place in the simulation's own scenario; `check=False` is the same opt-out."""
    from corobot_drake.config.scenario import ScenarioError

    bad = scenario()
    bad.robots["corobot"].pose.translation = [0.0, 0.0, -0.5]
    with pytest.raises(ScenarioError) as built:
        Simulation(bad)
    sim = Simulation(scenario())
    with pytest.raises(ScenarioError) as reset:
        sim.reset(bad)
    assert str(reset.value) == str(built.value)
    assert "robots.corobot.pose" in str(built.value) and "below the ground" in str(built.value)
    sim.scenario.robots["corobot"].velocity[0] = math.nan  # a list, in place
    with pytest.raises(ScenarioError,
                       match=r"robots\.corobot\.velocity\[0\]: must be in .*; got nan$"):
        sim.reset()
    sim.reset(bad, check=False)  # taken as it is: what a tool measuring beyond bounds asks
    assert sim.scenario is bad
    unchecked = Simulation(bad, check=False)
    unchecked.reset()  # built without checks: reset skips them too unless asked
    with pytest.raises(ScenarioError, match="below the ground"):
        unchecked.reset(check=True)
