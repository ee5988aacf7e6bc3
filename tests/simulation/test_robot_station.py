"""The station builds any robot from its robot file beside the Corobot: a user's URDF
two-wheel robot gets its tyres, its caster's low friction and one servo per wheel, drives at
its drive's speed and spins at its differential-drive rate, and its per-wheel telemetry has
its wheel count."""

import math

import pytest
from pydrake.systems.analysis import ApplySimulatorConfig, Simulator
from robot_samples import two_wheel_robot

from corobot_drake.config.scenario import load_scenario
from corobot_drake.station import build_station

TOP = 0.22
"""m/s: the sample robot's rim speed at power 1 (its robot file's `top_speed`)."""


def _run(tmp_path, left: float, right: float, seconds: float):
    path = two_wheel_robot(tmp_path)
    scenario = load_scenario(data=(
        f"robots: {{u: {{robot: {path}, commands: [!SetPower {{left: {left}, right: {right}}}]}}"
        ", c: {pose: {translation: [0, 1, 0]}}}"))
    station = build_station(scenario)
    simulator = Simulator(station.diagram)
    ApplySimulatorConfig(scenario.simulator_config, simulator)
    simulator.AdvanceTo(seconds)
    return station, simulator.get_context()


def test_a_urdf_robot_drives_beside_the_corobot_at_its_own_speed(tmp_path):
    station, context = _run(tmp_path, 1.0, 1.0, 1.5)
    parts = station.robots["u"]
    assert parts.spec.kind == "robot" or parts.spec.wheel_names == ("left", "right")
    assert [j.name() for j in parts.wheel_joints] == ["left_joint", "right_joint"]
    state = station.diagram.GetOutputPort("u.drive_state").Eval(context)
    # At full power the rims turn at TOP; after the 0.22 s slew the robot rolls at it within
    # the tyres' few percent of slip, and keeps straight (the caster slides).
    speed = station.diagram.GetOutputPort("u.axle_speed").Eval(context)
    assert speed == pytest.approx([TOP / 0.033] * 2, rel=1e-3)
    x, y, _ = state.position
    assert 0.8 * TOP * 1.2 < x < TOP * 1.5
    assert abs(y) < 0.01 and abs(state.heading) < 0.02
    loads = station.diagram.GetOutputPort("u.wheel_loads").Eval(context)
    assert len(loads) == 2 and all(load > 2.0 for load in loads)  # the caster takes the rest
    assert len(station.diagram.GetOutputPort("c.wheel_loads").Eval(context)) == 4
    assert set(state.wheels) == {"left", "right"} and state.encoded == ("left", "right")


def test_a_differential_drive_spins_on_the_spot_at_its_analytic_rate(tmp_path):
    station, context = _run(tmp_path, -1.0, 1.0, 1.0)
    compass = station.diagram.GetOutputPort("u.heading")
    state = station.diagram.GetOutputPort("u.drive_state").Eval(context)
    rate = TOP / 0.08  # rad/s: rim speed over half the track
    # From rest: the slew takes 0.22 s to full speed, so 1 s turns (1 - 0.11) s at `rate`;
    # the tyres slip 3% against the caster's drag (measured 3.5% short).
    assert compass.Eval(context)[0] == pytest.approx(rate * 0.89, rel=0.05)
    x, y, _ = state.position
    assert math.hypot(x, y) < 0.01


def test_visual_boxes_draws_a_user_robots_collision_shapes_instead_of_its_visuals(tmp_path):
    path = two_wheel_robot(tmp_path)
    looks = {}
    for visual in ("meshes", "boxes"):
        scenario = load_scenario(data=f"robots: {{u: {{robot: {path}, visual: {visual}}}}}")
        station = build_station(scenario)
        plant, inspector = station.plant, station.scene_graph.model_inspector()
        bodies = plant.GetBodyIndices(station.robots["u"].model_instance)
        looks[visual] = sorted(
            inspector.GetName(g) for b in bodies
            for g in plant.GetVisualGeometriesForBody(plant.get_body(b))
            if inspector.GetIllustrationProperties(g) is not None)
    assert looks["meshes"] == []  # the sample URDF has no visuals of its own
    # One look per collision shape: the base's box and caster, each wheel's tyre.
    assert looks["boxes"] == ["u::base_link_look_0", "u::base_link_look_1",
                              "u::left_wheel_look_0", "u::right_wheel_look_0"]
