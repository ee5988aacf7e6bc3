"""The friction of the directives' models: Drake's parsers give 1.0 to a geometry whose file
sets none; `world.model_friction` sets it from the scenario, checked against its range at load."""

import numpy as np
import pytest
from pydrake.multibody.math import SpatialVelocity

from conftest import DEFAULT_SCENARIO, make_sim
from corobot_drake.config.scenario import ScenarioError, load_scenario

CRATE_URDF = """<?xml version="1.0"?>
<robot name="crate">
  <link name="crate">
    <inertial><mass value="2.0"/>
      <inertia ixx="0.0133" ixy="0" ixz="0" iyy="0.0133" iyz="0" izz="0.0133"/></inertial>
    <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
  </link>
</robot>
"""
"""A 0.2 m, 2 kg crate whose file sets no friction."""
LAUNCH = 1.0
"""m/s: the crate's initial speed along +x."""


def crate_sim(tmp_path, *overrides: str):
    path = tmp_path / "crate.urdf"
    path.write_text(CRATE_URDF)
    sim = make_sim(f"directives: [{{add_model: {{name: crate, file: 'file://{path}', "
                   "default_free_body_pose: {crate: {translation: [1.0, 1.5, 0.1]}}}}]",
                   *overrides)
    return sim, sim.station.plant.GetBodyByName("crate", sim.station.models["crate"])


def friction_of(sim, body) -> tuple[float, float]:
    """(static, dynamic) friction of the body's collision geometry, as SceneGraph holds it."""
    plant, inspector = sim.station.plant, sim.station.scene_graph.model_inspector()
    (gid,) = plant.GetCollisionGeometriesForBody(body)
    friction = inspector.GetProximityProperties(gid).GetProperty("material", "coulomb_friction")
    return friction.static_friction(), friction.dynamic_friction()


def slide(sim, body) -> float:
    """m: how far the crate slides from LAUNCH m/s until it stops (1.5 s)."""
    plant = sim.station.plant
    context = plant.GetMyMutableContextFromRoot(sim.context)
    sim.advance(0.2)  # settled on the ground
    x0 = plant.EvalBodyPoseInWorld(context, body).translation()[0]
    plant.SetFreeBodySpatialVelocity(context, body,
                                     SpatialVelocity(np.zeros(3), [LAUNCH, 0.0, 0.0]))
    sim.advance(1.5)
    assert np.linalg.norm(plant.EvalBodySpatialVelocityInWorld(context, body).translational()) \
        < 1e-2  # stopped
    return plant.EvalBodyPoseInWorld(context, body).translation()[0] - x0


def expected_slide(mu_model: float) -> float:
    """m: v^2 / (2 mu g) with Drake's combined friction against the ground's."""
    mu_ground = load_scenario(DEFAULT_SCENARIO).world.ground.friction
    mu = 2 * mu_model * mu_ground / (mu_model + mu_ground)
    return LAUNCH ** 2 / (2 * mu * 9.81)


def test_the_models_friction_is_drakes_default_or_the_scenarios(tmp_path):
    """Read back from the plant's proximity properties, and felt: a crate launched at 1 m/s
    slides v^2 / (2 mu g) on the ground with the scenario's 0.1 (31 cm; measured 30.1 cm);
    with its file's default 1.0 it stops within 3 cm (it catches its front edge and rocks,
    measured 2.2 cm, where v^2 / (2 mu g) would be 7.6 cm)."""
    sim, body = crate_sim(tmp_path)
    assert friction_of(sim, body) == (1.0, 1.0)
    assert slide(sim, body) < 0.03
    sim, body = crate_sim(tmp_path, "world: {model_friction: 0.1}")
    assert friction_of(sim, body) == (0.1, 0.1)
    assert slide(sim, body) == pytest.approx(expected_slide(0.1), rel=0.05)


def test_the_scenarios_friction_overrides_the_files_own():
    """The maze's walls say 0.5 in their SDFormat file; the scenario's value replaces it."""
    from corobot_drake.resources import SCENARIOS_DIR

    maze = SCENARIOS_DIR / "maze.yaml"
    for overrides, mu in (((), 0.5), (("world: {model_friction: 0.8}",), 0.8)):
        sim = make_sim(*overrides, scenario=maze)
        walls = sim.station.plant.GetBodyByName("walls", sim.station.models["maze"])
        inspector = sim.station.scene_graph.model_inspector()
        for gid in sim.station.plant.GetCollisionGeometriesForBody(walls):
            f = inspector.GetProximityProperties(gid).GetProperty("material", "coulomb_friction")
            assert (f.static_friction(), f.dynamic_friction()) == (mu, mu)


@pytest.mark.parametrize("value, message", [
    ("-0.5", "must be in [0, 10] (Coulomb friction; Drake needs >= 0); got -0.5"),
    ("11", "must be in [0, 10] (Coulomb friction; Drake needs >= 0); got 11"),
    ("grippy", "expected a number, got 'grippy'"),
    (".nan", "NaN is not allowed"),
])
def test_a_bad_model_friction_is_refused_in_one_line(tmp_path, value, message):
    path = tmp_path / "s.yaml"
    text = DEFAULT_SCENARIO.read_text().replace(
        "  sky_color:", f"  model_friction: {value}\n  sky_color:")
    path.write_text(text)
    line = 1 + text.splitlines().index(f"  model_friction: {value}")
    with pytest.raises(ScenarioError) as e:
        load_scenario(path)
    assert str(e.value) == f"{path}:{line}: world.model_friction: {message}"
