"""The physics-only decomposition (`tools/bench.py --layers`) measures what the station runs."""

import numpy as np
import pytest

from conftest import SAP
from corobot_drake.simulation import Simulation
from lab import bench_layers as bl

INTEGRATORS = pytest.mark.parametrize("overrides", [(), (SAP,)], ids=["cenic", "sap"])


def _plant_state(simulator) -> np.ndarray:
    plant = simulator.get_system().GetSubsystemByName("plant")
    return plant.GetPositionsAndVelocities(plant.GetMyContextFromRoot(simulator.get_context()))


@INTEGRATORS
def test_all_layers_step_the_station_bit_for_bit(overrides):
    # The layers are wired as the station: with all of them the trajectory is the station's
    # exactly, so the last layer's cost is the station's cost and nothing is missing.
    scenario = bl._scenario(*overrides)
    built = bl.build_layers(scenario, len(bl.LAYERS))
    built.simulator.AdvanceTo(1.0)
    sim = Simulation(scenario)
    sim.advance(1.0)
    plant = sim.station.plant
    expected = plant.GetPositionsAndVelocities(plant.GetMyContextFromRoot(sim.context))
    assert np.array_equal(_plant_state(built.simulator), expected)


@INTEGRATORS
def test_the_plant_alone_steps_the_station_bit_for_bit(overrides):
    # The floor is measured on the station's own driving (the desired state its drive gave
    # the plant at each step, replayed): the same physics, so what the station adds over it
    # is the robot's systems alone, not a different trajectory's contact problem.
    scenario = bl._scenario(*overrides)
    built = bl.build_layers(scenario, 1, 1.0)
    built.simulator.AdvanceTo(1.0)
    sim = Simulation(scenario)
    sim.advance(1.0)
    plant = sim.station.plant
    expected = plant.GetPositionsAndVelocities(plant.GetMyContextFromRoot(sim.context))
    assert np.array_equal(_plant_state(built.simulator), expected)
    assert expected[4] > 0.3  # it drove: 0.49 m/s mean rim speed for most of a second


def test_idle_python_updates_leave_the_plant_alone_s_steps():
    # The floor rows add Python updates that change nothing (reading nothing, or what the
    # station's quiet updates read, or numbers alone): the same steps and trajectory, so what
    # they add over the plant alone is Drake's dispatch of those updates and their reads alone
    # (a read that finds a change raises).
    scenario = bl._scenario()
    runs = []
    for idle, floor in ((0, bl.IDLE), *((bl.IDLE_UPDATES, floor) for floor in bl.FLOORS)):
        built = bl.build_layers(scenario, 1, 1.0, idle_updates=idle, floor=floor)
        built.simulator.AdvanceTo(1.0)
        runs.append((built.simulator.get_num_steps_taken(), _plant_state(built.simulator)))
    assert [steps for steps, _ in runs] == [102] * 4
    for _, state in runs[1:]:
        assert np.array_equal(state, runs[0][1])
