"""The shipped robots' models beside the Corobot's (models/burger, models/pioneer): Drake's
Parser reads each, and the parsed plant has the public figures their comments cite (written
out again here, independently of the files): mass, wheel radius, track and wheelbase, every
wheel and caster on the ground, and each link's inertia that of its solid shapes."""

import numpy as np
import pytest
from pydrake.geometry import Box, Cylinder, Role, Sphere
from pydrake.math import RigidTransform
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.multibody.tree import (
    RevoluteJoint,
    SpatialInertia,
    UnitInertia,
    WeldJoint,
)
from pydrake.systems.framework import DiagramBuilder

from corobot_drake.resources import MODELS_DIR

EXACT = 1e-9
"""m, kg: the files state these figures to the digit."""
INERTIA = 1e-8
"""kg m^2: the files' inertias are printed to 9 significant digits."""

ROBOTS = {
    # name: base link, {side: [wheel joints]}, mass kg, wheel radius m, track m, wheelbase m,
    # {link: {collision shape: kg}} (a shape not named carries no mass: the caster ball)
    "burger": ("base", {"left": ["left_axle"], "right": ["right_axle"]}, 1.0, 0.033, 0.160, 0.0,
               {"base": {"body": 0.825}, "lidar": {"housing": 0.125},
                "left_wheel": {"tyre": 0.025}, "right_wheel": {"tyre": 0.025}}),
    "pioneer": ("body", {"left": ["front_left_axle", "rear_left_axle"],
                         "right": ["front_right_axle", "rear_right_axle"]},
                12.0, 0.1075, 0.40, 0.26,
                {"body": {"body": 8.6, "deck": 1.0},
                 **{f"{w}_wheel": {"tyre": 0.6}
                    for w in ("front_left", "rear_left", "front_right", "rear_right")}}),
}


def parse(name: str):
    """(plant, its context, the model's collision shapes by (link, name): (shape, X_WG))."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.001)
    (model,) = Parser(plant).AddModels(str(MODELS_DIR / name / f"{name}.sdf"))
    plant.Finalize()
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    plant_context = plant.GetMyContextFromRoot(context)
    inspector = scene_graph.model_inspector()
    shapes = {}
    for index in plant.GetBodyIndices(model):
        body = plant.get_body(index)
        X_WB = plant.EvalBodyPoseInWorld(plant_context, body)
        for g in inspector.GetGeometries(plant.GetBodyFrameIdOrThrow(index), Role.kProximity):
            shapes[body.name(), inspector.GetName(g).split("::")[-1]] = (
                inspector.GetShape(g), X_WB @ inspector.GetPoseInFrame(g))
    return plant, plant_context, model, shapes


@pytest.fixture(scope="module", params=sorted(ROBOTS))
def robot(request):
    return request.param, ROBOTS[request.param], parse(request.param)


def lowest_point(shape, X_WG: RigidTransform) -> float:
    """World z (m) of the lowest point of a box, cylinder or sphere posed at X_WG."""
    z = X_WG.translation()[2]
    up = X_WG.rotation().matrix()[2, :]  # the world's z in the shape's axes
    if isinstance(shape, Sphere):
        return z - shape.radius()
    if isinstance(shape, Cylinder):
        return (z - shape.radius() * np.sqrt(max(0.0, 1.0 - up[2] ** 2))
                - shape.length() / 2 * abs(up[2]))
    return z - np.dot(np.abs(up), shape.size()) / 2


def test_it_parses_with_its_wheels_revolute_about_the_axle(robot):
    _, (base, wheels, *_), (plant, _, model, _) = robot
    assert plant.HasBodyNamed(base, model)
    for joint_name in wheels["left"] + wheels["right"]:
        joint = plant.GetJointByName(joint_name, model)
        assert isinstance(joint, RevoluteJoint)
        assert joint.parent_body().name() == base
        np.testing.assert_array_equal(joint.revolute_axis(), [0.0, 1.0, 0.0])
        assert plant.GetJointActuatorByName(joint_name, model).effort_limit() < np.inf
    # every other joint welds a part to the base (the burger's lidar); the base itself is
    # free (the floating joint Drake gives it)
    others = [plant.get_joint(j) for j in plant.GetJointIndices(model)
              if plant.get_joint(j).name() not in wheels["left"] + wheels["right"]
              and plant.get_joint(j).child_body().name() != base]
    assert all(isinstance(j, WeldJoint) for j in others)


def test_mass_as_specified(robot):
    _, (_, _, mass, *_), (plant, context, _, _) = robot
    assert plant.CalcTotalMass(context) == pytest.approx(mass, abs=EXACT)


def test_wheel_radius_track_and_wheelbase_from_the_tyres(robot):
    _, (_, wheels, _, radius, track, wheelbase, _), (plant, _, model, shapes) = robot
    centres = {}
    for side, joints in wheels.items():
        for joint_name in joints:
            link = plant.GetJointByName(joint_name, model).child_body().name()
            shape, X_WG = shapes[link, "tyre"]
            assert isinstance(shape, Cylinder)
            assert shape.radius() == pytest.approx(radius, abs=EXACT)
            centres.setdefault(side, []).append(X_WG.translation())
    left, right = np.array(centres["left"]), np.array(centres["right"])
    assert np.mean(left[:, 1]) - np.mean(right[:, 1]) == pytest.approx(track, abs=EXACT)
    assert np.ptp(left[:, 0]) == pytest.approx(wheelbase, abs=EXACT)
    assert np.ptp(right[:, 0]) == pytest.approx(wheelbase, abs=EXACT)
    # the base's origin is on the ground midway between the tyres
    both = np.vstack([left, right])
    assert np.mean(both[:, 0]) == pytest.approx(0.0, abs=EXACT)
    assert np.mean(both[:, 1]) == pytest.approx(0.0, abs=EXACT)


def test_every_tyre_and_the_caster_touch_the_ground_and_nothing_else_does(robot):
    _, _, (_, _, _, shapes) = robot
    lowest = {key: lowest_point(shape, X) for key, (shape, X) in shapes.items()}
    on_ground = {key for key, z in lowest.items() if abs(z) < EXACT}
    assert on_ground == {key for key in shapes if key[1] in ("tyre", "caster")}
    assert all(z > 0.01 for key, z in lowest.items() if key not in on_ground), lowest


def solid_inertia(shape, mass: float, X_BG: RigidTransform) -> SpatialInertia:
    """The spatial inertia about the body origin, in the body frame, of a solid `shape` of
    `mass` posed at X_BG."""
    if isinstance(shape, Box):
        M_GGo_G = SpatialInertia.SolidBoxWithMass(mass, *shape.size())
    else:
        M_GGo_G = SpatialInertia.SolidCylinderWithMass(mass, shape.radius(), shape.length(),
                                                        [0.0, 0.0, 1.0])
    return M_GGo_G.ReExpress(X_BG.rotation()).Shift(-X_BG.translation())


def test_each_links_inertia_is_its_solid_shapes(robot):
    _, (*_, masses), (plant, context, model, shapes) = robot
    for link, parts in masses.items():
        body = plant.GetBodyByName(link, model)
        X_BW = plant.EvalBodyPoseInWorld(context, body).inverse()
        expected = SpatialInertia(0.0, np.zeros(3), UnitInertia(0.0, 0.0, 0.0))
        for shape_name, mass in parts.items():
            shape, X_WG = shapes[link, shape_name]
            expected += solid_inertia(shape, mass, X_BW @ X_WG)
        actual = body.default_spatial_inertia()
        assert actual.get_mass() == pytest.approx(expected.get_mass(), abs=EXACT)
        np.testing.assert_allclose(actual.get_com(), expected.get_com(), atol=EXACT)
        np.testing.assert_allclose(actual.CalcRotationalInertia().CopyToFullMatrix3(),
                                   expected.CalcRotationalInertia().CopyToFullMatrix3(),
                                   atol=INERTIA, err_msg=link)


def test_the_burgers_size_and_lidar_height():
    """138 x 178 x 192 mm: the body's length, the width over the tyres, the lidar's top."""
    _, _, _, shapes = parse("burger")
    body, _ = shapes["base", "body"]
    assert body.width() == pytest.approx(0.138, abs=EXACT)
    tyre, X_tyre = shapes["left_wheel", "tyre"]
    assert 2 * (X_tyre.translation()[1] + tyre.length() / 2) == pytest.approx(0.178, abs=EXACT)
    housing, X_lidar = shapes["lidar", "housing"]
    assert X_lidar.translation()[2] + housing.length() / 2 == pytest.approx(0.192, abs=EXACT)
    _, X_caster = shapes["base", "caster"]
    assert X_caster.translation()[0] < -0.05  # behind the axle: the robot rests on three points
