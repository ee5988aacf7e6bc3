"""How the robot looks while it runs: turning wheels, the collision-shape view, rendering."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.geometry import Role

from conftest import make_sim
from corobot_drake.config.sensors import default_camera_config
from corobot_drake.robots import robot_spec
from corobot_drake.sensors import render

SPEC = robot_spec("corobot")
CAMERA = default_camera_config()
"""The Corobot's camera, as its robot file says."""


def wheel_visual_ids(sim, wheel: str) -> list:
    """Geometry ids of the wheel body's illustration (visual) geometry."""
    station = sim.station
    inspector = station.scene_graph.model_inspector()
    parts = sim.robot()._parts
    body = station.plant.GetBodyByName(f"{wheel}_wheel", parts.model_instance)
    frame_id = station.plant.GetBodyFrameIdOrThrow(body.index())
    return list(inspector.GetGeometries(frame_id, Role.kIllustration))


def wheel_angle(sim, geometry_id) -> float:
    """Rotation of a wheel's visual geometry about its axle (chassis +y) from where it was
    registered on the wheel, radians in (-pi, pi]."""
    query = sim.station.diagram.GetOutputPort("query_object").Eval(sim.context)
    X_WG = query.GetPoseInWorld(geometry_id)
    X_FG = sim.station.scene_graph.model_inspector().GetPoseInFrame(geometry_id)
    X_WB = render.chassis_pose(sim)
    R_BG = (X_WB.rotation().inverse() @ X_WG.rotation() @ X_FG.rotation().inverse()).matrix()
    # Rotation about y: R = [[c, 0, s], [0, 1, 0], [-s, 0, c]].
    return math.atan2(R_BG[0, 2], R_BG[0, 0])


@pytest.mark.parametrize("visual", ["meshes", "boxes"])
def test_wheels_visibly_turn_by_distance_over_radius(visual):
    sim = make_sim(f"robots: {{corobot: {{visual: {visual}}}}}")
    ids = {w: wheel_visual_ids(sim, w) for w in SPEC.wheel_names}
    assert all(ids.values()), "every wheel body carries visual geometry"
    sim.advance(0.3)  # settle
    robot = sim.robot()
    robot.set_speed(0.3, 0.3)
    start = robot.pose()
    last = {w: wheel_angle(sim, ids[w][0]) for w in SPEC.wheel_names}
    turned = dict.fromkeys(SPEC.wheel_names, 0.0)
    for _ in range(60):  # 1.5 s in steps far shorter than a half turn (~0.12 rad at 0.3 m/s)
        sim.advance(0.025)
        for w in SPEC.wheel_names:
            now = wheel_angle(sim, ids[w][0])
            turned[w] += math.remainder(now - last[w], 2 * math.pi)
            last[w] = now
            # All of a wheel's visual pieces turn together (they ride on one body).
            for other in ids[w][1:]:
                assert math.remainder(wheel_angle(sim, other) - now, 2 * math.pi) == \
                    pytest.approx(0.0, abs=1e-9)
    end = robot.pose()
    distance = math.hypot(end.x - start.x, end.y - start.y)
    assert distance > 0.3
    for w in SPEC.wheel_names:
        # Forward motion turns the wheel positively about +y (axle to the left); the
        # compliant tyre rolls on a slightly smaller radius (measured ~0.9% more turn).
        assert turned[w] == pytest.approx(distance / SPEC.wheel_radius, rel=0.02), w


def test_wheel_visual_follows_the_wheel_body():
    """The visual geometry is the wheel body's pose: what Meshcat and the camera draw."""
    sim = make_sim("robots: {corobot: {commands: [!SetPower {left: 0.8, right: 0.2}]}}")
    sim.advance(1.0)
    plant = sim.station.plant
    plant_context = plant.GetMyContextFromRoot(sim.context)
    query = sim.station.diagram.GetOutputPort("query_object").Eval(sim.context)
    inspector = sim.station.scene_graph.model_inspector()
    for w in SPEC.wheel_names:
        body = plant.GetBodyByName(f"{w}_wheel", sim.robot()._parts.model_instance)
        X_WW = plant.EvalBodyPoseInWorld(plant_context, body)
        for gid in wheel_visual_ids(sim, w):
            X_WG = query.GetPoseInWorld(gid)
            X_WG_expected = X_WW @ inspector.GetPoseInFrame(gid)
            assert X_WG.IsNearlyEqualTo(X_WG_expected, 1e-9)


def test_meshcat_publishes_collision_shapes_hidden_by_default():
    """The proximity (collision) geometry is in Meshcat's scene tree under /drake/proximity,
    next to the visual meshes under /drake/illustration (Drake adds it invisible: the user
    ticks `proximity` in the Scene panel)."""
    from pydrake.geometry import StartMeshcat

    from corobot_drake.simulation import Simulation
    from corobot_drake.station import visualization_config

    config = visualization_config()
    assert config.publish_proximity and config.publish_illustration
    meshcat = StartMeshcat()
    sim = Simulation(make_sim().scenario, meshcat=meshcat)
    sim.advance(0.05)
    for layer in ("illustration", "proximity"):
        for path in ("corobot/chassis", "corobot/front_left_wheel", "giant_box"):
            assert meshcat.HasPath(f"/drake/{layer}/{path}"), (layer, path)


def test_under_cenic_meshcat_publishes_on_the_plant_s_steps():
    """Drake's 1/64 s between the 10 ms steps would split CENIC's steps whenever Meshcat
    watches: on a continuous plant the visualizers publish every 2^j steps instead, the same
    event times as the plant's, so a run watched in Meshcat is the same run, step for step."""
    from pydrake.geometry import StartMeshcat

    from corobot_drake.config.scenario import CENIC_PLANT
    from corobot_drake.simulation import Simulation
    from corobot_drake.station import publish_period_on_steps

    assert publish_period_on_steps(1 / 64, 0.01) == 0.02
    assert publish_period_on_steps(1 / 64, 0.001) == 0.016
    assert publish_period_on_steps(0.01, 0.01) == 0.01
    assert all(k * 0.02 == (2 * k) * 0.01 for k in range(100_000))  # doubling is exact
    script = "robots: {corobot: {commands: [!SetPower {left: 0.8, right: 0.4}]}}"
    runs = []
    for meshcat in (None, StartMeshcat()):
        sim = Simulation(make_sim(script, CENIC_PLANT % 0.01).scenario, meshcat=meshcat)
        sim.advance(1.0)
        runs.append((sim.simulator.get_num_steps_taken(), sim.robot().pose()))
    assert runs[0] == runs[1]


def test_meshcat_sun_shines_from_the_books_direction():
    """The book's sun, (0.5, -0.75, 0.5) in MRDS's y-up frame, is (-0.5, -0.5, -0.75) here;
    Meshcat's directional light sits up-sun of the origin with the scenario's intensity (a
    property on a path that is no light, as `DirectionalLight` was, only warns in the
    browser: the page-level check is tests/service/test_browser.py)."""
    import msgpack
    from pydrake.geometry import StartMeshcat

    from corobot_drake.config.scenario import BOOK_SUN_DIRECTION, from_mrds_frame
    from corobot_drake.simulation import Simulation
    from corobot_drake.station import MESHCAT_DIRECTIONAL_INTENSITY, MESHCAT_SUN

    assert BOOK_SUN_DIRECTION == [-0.5, -0.5, -0.75]
    assert from_mrds_frame((0, 0, -1)) == [1, 0, 0]  # MRDS's forward is +x
    assert from_mrds_frame((0, 1, 0)) == [0, 0, 1]  # and its up is +z
    sim = make_sim("world: {sun: {intensity: 0.5}}")
    assert sim.scenario.world.sun.direction == BOOK_SUN_DIRECTION  # the shipped scene's
    meshcat = StartMeshcat()
    Simulation(sim.scenario, meshcat=meshcat)

    def sent(prop):
        return msgpack.unpackb(meshcat._GetPackedProperty(MESHCAT_SUN, prop))["value"]

    position = np.array(sent("position"))
    unit = -np.array(BOOK_SUN_DIRECTION) / np.linalg.norm(BOOK_SUN_DIRECTION)
    assert position / np.linalg.norm(position) == pytest.approx(unit, abs=1e-12)
    assert sent("intensity") == pytest.approx(0.5 * MESHCAT_DIRECTIONAL_INTENSITY)
    assert not meshcat.HasPath("/Lights/DirectionalLight")


def _fraction(image, rgb, tol=30) -> float:
    return float(np.mean(np.all(np.abs(image.astype(int) - np.array(rgb)) <= tol, axis=2)))


def test_chase_view_follows_the_driven_robot():
    """Rendered after driving (and after the QueryObject was already evaluated): the robot is
    in the middle of the chase view, lit (its black tyres and silver plates are there)."""
    sim = make_sim("robots: {corobot: {commands: [!SetPower {left: 0.7, right: 0.4}]}}")
    sim.advance(2.0)
    sim.station.diagram.GetOutputPort("query_object").Eval(sim.context)
    render.add_renderer(sim, shadows=False)
    image = render.render(sim, render.chase_view(render.chassis_pose(sim)), 320, 200)
    middle = image[60:180, 100:220]
    sky = np.array(sim.scenario.world.sky_color) * 255
    assert _fraction(image[:4], sky, tol=3) > 0.5, "sky colour behind"
    assert _fraction(middle, (15, 15, 15), tol=25) > 0.03, "tyres in the middle"
    assert image.mean() > 60, "lit, not black"


def test_robot_camera_view_sees_the_box_ahead():
    sim = make_sim("robots: {corobot: {pose: {rotation: !Rpy {deg: [0, 0, 180]}}}}")
    image = render.render(sim, render.robot_camera_view(render.chassis_pose(sim)),
                          CAMERA.width, CAMERA.height, CAMERA.focal.y,
                          name=render.add_renderer(sim, shadows=False))
    assert image.shape == (CAMERA.height, CAMERA.width, 3)
    # 0.74 m from a 2 m box with a 30 deg fov: the box fills the view; its lit face is brown.
    r, g, b = image.reshape(-1, 3).mean(axis=0)
    assert r > g > b and r > 60


def _mouse_springs(sim) -> list[str]:
    return [s.get_name() for s in sim.station.diagram.GetSystems()
            if "mouse_spring" in s.get_name()]


def test_ctrl_drag_in_meshcat_only_where_someone_watches():
    """A Meshcat run gets Drake's MeshcatMouseSpring feeding the plant's applied-force input
    (Ctrl-drag a body); an offline recording (`--headless --record`) and a plain run do not,
    so they stay free of outside forces."""
    from pydrake.geometry import StartMeshcat

    from corobot_drake.simulation import Simulation

    scenario = make_sim().scenario
    watched = Simulation(scenario, meshcat=StartMeshcat())
    assert len(_mouse_springs(watched)) == 1
    offline = Simulation(scenario, record=True)
    assert _mouse_springs(offline) == []
    assert _mouse_springs(Simulation(scenario)) == []


def test_meshcat_runs_publish_no_lcm_multicast():
    """Drake's visualization also publishes LCM for Meldis; the station gives it an
    in-process bus, so a Meshcat run sends nothing to a multicast group."""
    from pydrake.geometry import StartMeshcat

    from corobot_drake.simulation import Simulation

    sim = Simulation(make_sim().scenario, meshcat=StartMeshcat())
    assert sim.station.visualization_lcm.get_lcm_url() == "memq://"
    sim.advance(0.05)
