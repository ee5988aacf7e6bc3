"""The parsed plant matches the SPEC's figures (written out here, independently of the code)."""

import subprocess
import sys

import numpy as np
import pytest
from pydrake.geometry import Box, Cylinder, Role
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.multibody.tree import JointActuatorIndex
from pydrake.systems.framework import DiagramBuilder

from conftest import REPO

SPEC_TOL = 1e-9  # the SPEC's figures are exact conversions from inches


@pytest.fixture(scope="module")
def parsed():
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.005)
    parser = Parser(plant)
    parser.package_map().AddPackageXml(str(REPO / "models" / "package.xml"))
    parser.AddModels(str(REPO / "models" / "corobot.sdf"))
    plant.Finalize()
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    return plant, scene_graph, plant.GetMyContextFromRoot(context), \
        scene_graph.GetMyContextFromRoot(context)


def test_model_file_is_generated_from_dimensions():
    result = subprocess.run([sys.executable, str(REPO / "tools" / "make_model.py"), "--check"],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr


def test_masses(parsed):
    plant, _, context, _ = parsed
    assert plant.GetBodyByName("chassis").default_mass() == pytest.approx(3.63, abs=SPEC_TOL)
    for wheel in ("front_left", "front_right", "rear_left", "rear_right"):
        assert plant.GetBodyByName(f"{wheel}_wheel").default_mass() == pytest.approx(0.1)
    assert plant.CalcTotalMass(context) == pytest.approx(4.03)


def _shapes(plant, scene_graph, sg_context, body_name, role):
    inspector = scene_graph.get_query_output_port().Eval(sg_context).inspector()
    frame = plant.GetBodyFrameIdOrThrow(plant.GetBodyByName(body_name).index())
    return [(inspector.GetShape(g), inspector.GetPoseInFrame(g))
            for g in inspector.GetGeometries(frame, role)]


def test_boxes(parsed):
    plant, scene_graph, _, sg_context = parsed
    boxes = sorted(((s.size(), X.translation())
                    for s, X in _shapes(plant, scene_graph, sg_context, "chassis",
                                        Role.kProximity) if isinstance(s, Box)),
                   key=lambda sx: sx[1][2])
    (chassis_size, chassis_at), (platform_size, platform_at) = boxes
    np.testing.assert_allclose(chassis_size, [0.2159, 0.14859, 0.0635], atol=SPEC_TOL)
    np.testing.assert_allclose(chassis_at, [0, 0, 0.06985], atol=SPEC_TOL)
    np.testing.assert_allclose(platform_size, [0.2159, 0.2794, 0.0762], atol=SPEC_TOL)
    np.testing.assert_allclose(platform_at, [0, 0, 0.18415], atol=SPEC_TOL)


@pytest.mark.parametrize("wheel,x,y", [("front_left", 1, 1), ("front_right", 1, -1),
                                       ("rear_left", -1, 1), ("rear_right", -1, -1)])
def test_wheels(parsed, wheel, x, y):
    plant, scene_graph, context, sg_context = parsed
    body = plant.GetBodyByName(f"{wheel}_wheel")
    X_CW = plant.CalcRelativeTransform(context, plant.GetFrameByName("chassis"),
                                       body.body_frame())
    np.testing.assert_allclose(X_CW.translation(), [x * 0.092075, y * 0.11176, 0.060325],
                               atol=SPEC_TOL)
    ((shape, X_WG),) = _shapes(plant, scene_graph, sg_context, f"{wheel}_wheel",
                               Role.kProximity)
    assert isinstance(shape, Cylinder)
    assert shape.radius() == pytest.approx(0.060325, abs=SPEC_TOL)
    assert shape.length() == pytest.approx(0.05588, abs=SPEC_TOL)
    # The cylinder's axis (its z) lies along the axle, +-y of the chassis.
    assert abs(X_WG.rotation().matrix()[1, 2]) == pytest.approx(1.0)
    joint = plant.GetJointByName(f"{wheel}_axle")
    np.testing.assert_allclose(np.abs(joint.revolute_axis()), [0, 1, 0])


def test_axle_servos(parsed):
    plant, *_ = parsed
    assert plant.num_actuators() == 4
    for i in range(4):
        actuator = plant.get_joint_actuator(JointActuatorIndex(i))
        gains = actuator.get_controller_gains()
        assert gains.p == 0 and gains.d > 0
        assert 0 < actuator.effort_limit() < 1.0  # a motor's stall torque, N m


def test_robot_does_not_collide_with_itself(parsed):
    _, scene_graph, _, sg_context = parsed
    inspector = scene_graph.get_query_output_port().Eval(sg_context).inspector()
    ids = inspector.GetAllGeometryIds(Role.kProximity)
    for i, a in enumerate(ids):
        for b in ids[i + 1:]:
            assert inspector.CollisionFiltered(a, b)


def test_default_scene_matches_the_spec():
    """World objects come from the scenario file; they must be the chapter's (SPEC "The world")."""
    from conftest import DEFAULT_SCENARIO
    from corobot_drake.config.scenario import Box as BoxShape
    from corobot_drake.config.scenario import load_scenario

    scenario = load_scenario(DEFAULT_SCENARIO)
    box = scenario.world.bodies["giant_box"]
    assert isinstance(box.shape, BoxShape) and box.shape.size == [2.0, 2.0, 2.0]
    assert box.mass == 100.0 and not box.fixed
    X_WB = box.pose.GetDeterministicValue()
    assert X_WB.translation() == pytest.approx([-(29 * 0.0254 + 1.0), 0.0, 1.0])
    assert X_WB.rotation().IsExactlyIdentity()
    # The near face 29 in behind the origin, so the rear IR reads 0.62865 m (SPEC).
    assert X_WB.translation()[0] + 1.0 == pytest.approx(-0.7366, abs=1e-12)
    assert scenario.world.ground.friction == 0.5
    (robot,) = scenario.robots.values()
    assert robot.pose.GetDeterministicValue().IsExactlyIdentity()  # at the origin, facing +x
    assert robot.drive.motor_torque_scaling == 10.16
