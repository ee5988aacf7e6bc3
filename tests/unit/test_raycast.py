"""Ray casting against real SceneGraph geometry (QueryObject.GetPoseInWorld path).

The batch cast with hit points (`ReferenceRayCaster.cast`, tests/reference_raycast.py) is
checked against closed forms and Drake's signed distances; the product's `cast_fan` against
closed forms and against the batch cast."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest
from pydrake.geometry import (
    Box,
    Capsule,
    Convex,
    Cylinder,
    Ellipsoid,
    FramePoseVector,
    GeometryFrame,
    GeometryInstance,
    HalfSpace,
    Mesh,
    MeshcatCone,
    ProximityProperties,
    SceneGraph,
    Sphere,
)
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, CoulombFriction
from pydrake.multibody.tree import SpatialInertia
from pydrake.systems.framework import DiagramBuilder

from corobot_drake.sensors.raycast import (
    RayCaster,
    RayFan,
    cross_of_rays_in_sensor_frame,
    model_instance_geometry_ids,
)
from lab import bench_raycast
from reference_raycast import ReferenceRayCaster, cross_of_rays_directions

CUBE_OBJ = """\
v -1 -1 -1
v 1 -1 -1
v 1 1 -1
v -1 1 -1
v -1 -1 1
v 1 -1 1
v 1 1 1
v -1 1 1
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 2 3 7
f 2 7 6
f 3 4 8
f 3 8 7
f 4 1 5
f 4 5 8
"""

OCTAHEDRON_OBJ = """\
v 1 0 0
v -1 0 0
v 0 1 0
v 0 -1 0
v 0 0 1
v 0 0 -1
f 1 3 5
f 3 2 5
f 2 4 5
f 4 1 5
f 3 1 6
f 2 3 6
f 4 2 6
f 1 4 6
"""


class Scene:
    """A SceneGraph with proximity geometries, its context and QueryObject.

    anchored: geometries fixed to the world (the caster precomputes their poses); otherwise
    each sits on its own moving frame F, posed through the source's FramePoseVector input, at
    X_FG = Y (a fixed offset) so that the QueryObject composes X_WF * X_FG = X_WG. Half-spaces
    are always anchored: a half-space on a moving frame crashed (SIGSEGV) when SceneGraph
    cloned its proximity engine for a context, in a few runs depending on memory layout.
    """

    Y = RigidTransform(RollPitchYaw(-0.2, 0.5, 0.3), [0.1, 0.2, -0.3])

    def __init__(self, shapes: list[tuple[str, object, RigidTransform]], anchored: bool = True):
        self.scene_graph = SceneGraph()
        source = self.scene_graph.RegisterSource("test")
        self.ids = {}
        poses = FramePoseVector()
        for name, shape, X_WG in shapes:
            fixed = anchored or isinstance(shape, HalfSpace)
            X_FG = RigidTransform() if fixed else self.Y
            instance = GeometryInstance(X_WG if fixed else X_FG, shape, name)
            instance.set_proximity_properties(ProximityProperties())
            if fixed:
                self.ids[name] = self.scene_graph.RegisterAnchoredGeometry(source, instance)
            else:
                frame = self.scene_graph.RegisterFrame(source, GeometryFrame(name))
                self.ids[name] = self.scene_graph.RegisterGeometry(source, frame, instance)
                poses.set_value(frame, X_WG @ X_FG.inverse())
        self.context = self.scene_graph.CreateDefaultContext()
        if not anchored:
            self.scene_graph.get_source_pose_port(source).FixValue(self.context, poses)
        self.query_object = self.scene_graph.get_query_output_port().Eval(self.context)
        self.inspector = self.scene_graph.model_inspector()

    def caster(self, exclude=()):
        return ReferenceRayCaster(self.inspector, exclude=[self.ids[n] for n in exclude])


@pytest.fixture(scope="module")
def mesh_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("meshes")
    (d / "cube.obj").write_text(CUBE_OBJ)
    (d / "octahedron.obj").write_text(OCTAHEDRON_OBJ)
    return d


def unit(*v):
    v = np.array(v, dtype=float)
    return v / np.linalg.norm(v)


# (shape factory, local origin, local direction, analytic distance).
# The shape factory takes the mesh directory (only meshes use it).
R2 = math.sqrt(2.0)
CASES = {
    "box_x": (lambda m: Box(2, 4, 6), (-5, 0.5, 0.5), (1, 0, 0), 4.0),
    "box_y": (lambda m: Box(2, 4, 6), (0.3, -7, 1), (0, 1, 0), 5.0),
    "box_oblique": (lambda m: Box(2, 4, 6), (-3, -3, 0), unit(1, 1, 0), 2 * R2),
    "sphere_z": (lambda m: Sphere(0.5), (0, 0, -3), (0, 0, 1), 2.5),
    "sphere_offset": (lambda m: Sphere(0.5), (-2, 0.3, 0), (1, 0, 0), 2 - 0.4),
    "cylinder_side": (lambda m: Cylinder(0.5, 2), (-3, 0, 0.2), (1, 0, 0), 2.5),
    "cylinder_cap": (lambda m: Cylinder(0.5, 2), (0.1, 0.2, 5), (0, 0, -1), 4.0),
    "cylinder_oblique": (lambda m: Cylinder(0.5, 2), (-3, 0, 3), unit(1, 0, -1), 2.5 * R2),
    "capsule_side": (lambda m: Capsule(0.5, 2), (-3, 0, 0.5), (1, 0, 0), 2.5),
    "capsule_tip": (lambda m: Capsule(0.5, 2), (0, 0, 5), (0, 0, -1), 3.5),
    "capsule_dome": (lambda m: Capsule(0.5, 2), (0.3, 0, 5), (0, 0, -1), 5 - 1.4),
    "ellipsoid_x": (lambda m: Ellipsoid(1, 2, 3), (-5, 0, 0), (1, 0, 0), 4.0),
    "ellipsoid_y": (lambda m: Ellipsoid(1, 2, 3), (0, -5, 0), (0, 1, 0), 3.0),
    "ellipsoid_z": (lambda m: Ellipsoid(1, 2, 3), (0, 0, 6), (0, 0, -1), 3.0),
    "ellipsoid_off": (lambda m: Ellipsoid(1, 2, 3), (0.5, -5, 0), (0, 1, 0), 5 - math.sqrt(3)),
    "half_space": (lambda m: HalfSpace(), (1, 2, 3), (0, 0, -1), 3.0),
    "half_space_oblique": (lambda m: HalfSpace(), (1, 2, 3), unit(1, 0, -1), 3 * R2),
    "mesh_cube_scaled": (lambda m: Mesh(str(m / "cube.obj"), 0.5), (-3, 0.1, 0.2), (1, 0, 0), 2.5),
    "convex_octahedron": (
        lambda m: Convex(str(m / "octahedron.obj")),
        (-3, 0.25, 0.25),
        (1, 0, 0),
        2.5,
    ),
    "convex_octahedron_z": (
        lambda m: Convex(str(m / "octahedron.obj"), 2.0),
        (0, 0, 4),
        (0, 0, -1),
        2.0,
    ),
}

POSES = {
    "identity": RigidTransform(),
    "translated": RigidTransform([0.4, -1.2, 0.9]),
    "rotated": RigidTransform(RollPitchYaw(0.3, -0.7, 1.1), [0.4, -1.2, 0.9]),
}


def cast_local(mesh_files, shape, X_WG, o_G, d_G, max_range=100.0, anchored=True):
    """Casts one ray given in the shape frame G; returns (distance, hit point in G)."""
    scene = Scene([("target", shape, X_WG)], anchored=anchored)
    o_W = X_WG @ np.asarray(o_G, float)
    d_W = X_WG.rotation() @ np.asarray(d_G, float)
    hits = scene.caster().cast(scene.query_object, o_W[None], d_W[None], max_range)
    point_G = X_WG.inverse() @ hits.point[0] if np.isfinite(hits.distance[0]) else None
    return hits.distance[0], point_G, hits


@pytest.mark.parametrize("anchored", [True, False], ids=["anchored", "moving"])
@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("case", CASES)
def test_hit_at_analytic_distance(mesh_files, case, pose, anchored):
    make, o_G, d_G, expected = CASES[case]
    distance, point_G, hits = cast_local(
        mesh_files, make(mesh_files), POSES[pose], o_G, d_G, anchored=anchored
    )
    assert distance == pytest.approx(expected, abs=1e-9)
    expected_point = np.asarray(o_G, float) + expected * np.asarray(d_G, float)
    np.testing.assert_allclose(point_G, expected_point, atol=1e-9)
    assert hits.geometry_index[0] == 0


@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("case", CASES)
def test_reversed_ray_misses(mesh_files, case, pose):
    make, o_G, d_G, _ = CASES[case]
    distance, _, hits = cast_local(
        mesh_files, make(mesh_files), POSES[pose], o_G, -np.asarray(d_G, float)
    )
    assert distance == math.inf
    assert np.isnan(hits.point).all()
    assert hits.geometry_index[0] == -1


@pytest.mark.parametrize("case", CASES)
def test_max_range_bounds_the_hit(mesh_files, case):
    make, o_G, d_G, expected = CASES[case]
    X = POSES["rotated"]
    short, _, _ = cast_local(mesh_files, make(mesh_files), X, o_G, d_G, expected - 1e-6)
    assert short == math.inf
    exact, _, _ = cast_local(mesh_files, make(mesh_files), X, o_G, d_G, expected + 1e-9)
    assert exact == pytest.approx(expected, abs=1e-9)


PASS_BY = {
    # Rays that pass close to the shape but miss it (local frame).
    "box": (lambda m: Box(2, 4, 6), (-5, 2.01, 0), (1, 0, 0)),
    "sphere": (lambda m: Sphere(0.5), (-2, 0.501, 0), (1, 0, 0)),
    "cylinder_beyond_cap": (lambda m: Cylinder(0.5, 2), (-3, 0, 1.01), (1, 0, 0)),
    "cylinder_along_axis_outside": (lambda m: Cylinder(0.5, 2), (0.51, 0, 5), (0, 0, -1)),
    "capsule": (lambda m: Capsule(0.5, 2), (-3, 0, 1.51), (1, 0, 0)),
    "capsule_dome_corner": (lambda m: Capsule(0.5, 2), (-3, 0.4, 1.31), (1, 0, 0)),
    "ellipsoid": (lambda m: Ellipsoid(1, 2, 3), (-5, 0, 3.01), (1, 0, 0)),
    "octahedron": (lambda m: Convex(str(m / "octahedron.obj")), (-3, 0.5, 0.51), (1, 0, 0)),
    "mesh_cube_parallel_outside": (
        lambda m: Mesh(str(m / "cube.obj"), 0.5),
        (-3, 0.5001, 0),
        (1, 0, 0),
    ),
    "half_space_parallel": (lambda m: HalfSpace(), (0, 0, 1e-9), (1, 0, 0)),
    "half_space_upward": (lambda m: HalfSpace(), (0, 0, 1), unit(0.2, 0.3, 1)),
}


@pytest.mark.parametrize("case", PASS_BY)
def test_near_miss(mesh_files, case):
    make, o_G, d_G = PASS_BY[case]
    for X in POSES.values():
        distance, _, _ = cast_local(mesh_files, make(mesh_files), X, o_G, d_G)
        assert distance == math.inf, X


INSIDE = {
    "box": (lambda m: Box(2, 4, 6), (0.9, -1.9, 2.9)),
    "sphere": (lambda m: Sphere(0.5), (0.1, 0.2, -0.3)),
    "cylinder": (lambda m: Cylinder(0.5, 2), (0.3, 0.3, -0.9)),
    "capsule_dome": (lambda m: Capsule(0.5, 2), (0, 0.1, 1.45)),
    "ellipsoid": (lambda m: Ellipsoid(1, 2, 3), (0.5, 1, 1.5)),
    "half_space": (lambda m: HalfSpace(), (3, -4, -0.5)),
    "mesh": (lambda m: Mesh(str(m / "cube.obj"), 0.5), (0.4, -0.4, 0.4)),
}

ON_SURFACE = {
    "box_face": (lambda m: Box(2, 4, 6), (1, 0, 0)),
    "box_corner": (lambda m: Box(2, 4, 6), (1, -2, 3)),
    "half_space_boundary": (lambda m: HalfSpace(), (3, -4, 0)),
    "sphere": (lambda m: Sphere(0.5), (0, 0.5, 0)),
    "cylinder_rim": (lambda m: Cylinder(0.5, 2), (0.5, 0, 1)),
    "octahedron_vertex": (lambda m: Convex(str(m / "octahedron.obj")), (0, 0, 1)),
}


@pytest.mark.parametrize("case", INSIDE)
def test_origin_inside_is_a_hit_at_zero(mesh_files, case):
    """Documented convention: a ray starting inside (or on) a solid hits it at distance 0."""
    make, o_G = INSIDE[case]
    for d_G in [(1, 0, 0), (0, 0, -1), unit(-1, 2, 0.5)]:
        distance, point_G, _ = cast_local(mesh_files, make(mesh_files), POSES["rotated"], o_G, d_G)
        assert distance == 0.0
        np.testing.assert_allclose(point_G, o_G, atol=1e-12)


@pytest.mark.parametrize("case", ON_SURFACE)
def test_origin_on_the_surface_is_a_hit_at_zero(mesh_files, case):
    """Solids are closed. (Exact only where the pose maps the origin exactly: under a general
    rotation, rounding puts a surface point inside or outside by ~1e-16 m.)"""
    make, o_G = ON_SURFACE[case]
    for d_G in [(1, 0, 0), (0, 1, 0), (0, 0, 1), (-1, 0, 0), (0, -1, 0), (0, 0, -1)]:
        distance, _, _ = cast_local(mesh_files, make(mesh_files), POSES["identity"], o_G, d_G)
        assert distance == 0.0, d_G


def test_ray_parallel_to_half_space_misses():
    X_WG = HalfSpace.MakePose(unit(0.1, -0.2, 1.0), [0, 0, 0.3])
    scene = Scene([("ground", HalfSpace(), X_WG)])
    normal = X_WG.rotation().col(2)
    origin = X_WG.translation() + 0.5 * normal
    along = np.cross(normal, [1.0, 0.0, 0.0])
    hits = scene.caster().cast(scene.query_object, [origin], [along], 1e6)
    assert hits.distance[0] == math.inf


def test_batch_reports_nearest_of_several_geometries_per_ray():
    scene = Scene(
        [
            ("ground", HalfSpace(), RigidTransform()),
            ("near_box", Box(1, 1, 1), RigidTransform([2.5, 0, 0.5])),
            ("far_box", Box(1, 1, 1), RigidTransform([5.5, 0, 0.5])),
            ("ball", Sphere(0.25), RigidTransform([0, 3, 0.5])),
        ]
    )
    caster = scene.caster()
    origins = np.array([[0, 0, 0.5], [0, 0, 1.2], [0, 0, 0.5], [0, 0, 0.5], [4, 0, 0.5]])
    directions = np.array([[1, 0, 0], [1, 0, 0], unit(1, 0, -1), [0, 1, 0], [1, 0, 0]])
    hits = caster.cast(scene.query_object, origins, directions, 10.0)
    np.testing.assert_allclose(hits.distance, [2.0, math.inf, 0.5 * R2, 2.75, 1.0])
    names = [caster.geometry_name(i) for i in hits.geometry_index]
    assert names == ["near_box", "", "ground", "ball", "far_box"]
    np.testing.assert_allclose(hits.point[0], [2, 0, 0.5])
    np.testing.assert_allclose(hits.point[2], [0.5, 0, 0], atol=1e-12)
    assert np.isnan(hits.point[1]).all()


def test_excluded_geometry_ids_are_ignored():
    scene = Scene(
        [
            ("own", Box(0.2, 0.2, 0.2), RigidTransform([0, 0, 0])),
            ("wall", Box(0.1, 2, 2), RigidTransform([1.05, 0, 0])),
        ]
    )
    ray = ([[0, 0, 0]], [[1, 0, 0]])
    assert scene.caster().cast(scene.query_object, *ray, 5.0).distance[0] == 0.0
    caster = scene.caster(exclude=["own"])
    assert scene.ids["own"] not in caster.geometry_ids
    assert caster.cast(scene.query_object, *ray, 5.0).distance[0] == pytest.approx(1.0)


def test_multibody_plant_scene_moving_robot_excluded():
    """The real diagram path: MbP collision geometry, a free robot body posed in the context."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.001)
    friction = CoulombFriction(0.5, 0.5)
    world = plant.world_body()
    plant.RegisterCollisionGeometry(world, RigidTransform(), HalfSpace(), "ground", friction)
    plant.RegisterCollisionGeometry(
        world, RigidTransform([-1.7366, 0, 1]), Box(2, 2, 2), "giant_box", friction
    )
    robot = plant.AddModelInstance("robot")
    chassis = plant.AddRigidBody(
        "chassis", robot, SpatialInertia.SolidBoxWithMass(1, 0.2, 0.15, 0.06)
    )
    plant.RegisterCollisionGeometry(
        chassis, RigidTransform(), Box(0.2, 0.15, 0.06), "chassis", friction
    )
    plant.Finalize()
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    X_WB = RigidTransform(RotationMatrix.MakeZRotation(math.pi), [0, 0, 0.07])
    plant.SetFreeBodyPose(plant_context, chassis, X_WB)
    query_object = scene_graph.get_query_output_port().Eval(
        scene_graph.GetMyContextFromRoot(context)
    )
    own = model_instance_geometry_ids(plant, robot)
    assert len(own) == 1
    caster = ReferenceRayCaster(scene_graph.model_inspector(), exclude=own)
    assert len(caster.geometry_ids) == 2
    # Rear-looking sensor at the chassis' rear face (robot turned around: looks along world +x).
    X_WS = X_WB @ RigidTransform([-0.1, 0, 0])
    directions = cross_of_rays_directions(X_WS, samples=3)
    origins = np.tile(X_WS.translation(), (len(directions), 1))
    hits = caster.cast(query_object, origins, directions, 0.762)
    assert np.all(hits.distance == math.inf)  # looking along +x, nothing there
    # Move the robot so it faces the giant box (box face at x = -0.7366).
    plant.SetFreeBodyPose(plant_context, chassis, RigidTransform([0, 0, 0.07]))
    query_object = scene_graph.get_query_output_port().Eval(
        scene_graph.GetMyContextFromRoot(context)
    )
    X_WS = RigidTransform(RotationMatrix.MakeZRotation(math.pi), [-0.1, 0, 0.07])
    directions = cross_of_rays_directions(X_WS, samples=3)
    origins = np.tile(X_WS.translation(), (len(directions), 1))
    hits = caster.cast(query_object, origins, directions, 0.762)
    assert hits.distance.min() == pytest.approx(0.6366)
    # Without the exclusion the sensor, sitting on the chassis surface, sees itself at 0.
    all_caster = ReferenceRayCaster(scene_graph.model_inspector())
    assert all_caster.cast(query_object, origins, directions, 0.762).distance.max() == 0.0


class _InspectorWithCone:
    """Wraps an inspector so that one geometry reports a shape the caster can't intersect
    (SceneGraph itself refuses to give such shapes a proximity role)."""

    def __init__(self, inspector, gid):
        self._inspector, self._gid = inspector, gid

    def __getattr__(self, name):
        return getattr(self._inspector, name)

    def GetShape(self, gid):
        return MeshcatCone(1.0, 0.5, 0.5) if gid == self._gid else self._inspector.GetShape(gid)


def test_unsupported_shape_is_reported_once_by_name(caplog):
    scene = Scene(
        [("cone_like", Sphere(1), RigidTransform()), ("box", Box(1, 1, 1), RigidTransform())]
    )
    inspector = _InspectorWithCone(scene.inspector, scene.ids["cone_like"])
    with caplog.at_level(logging.WARNING, logger="corobot_drake.sensors.raycast"):
        caster = RayCaster(inspector)
        caster.cast_fan(scene.query_object, [5, 0, 0], [[-1, 0, 0]], 10)
        caster.cast_fan(scene.query_object, [5, 0, 0], [[-1, 0, 0]], 10)
    warnings = [r for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1
    assert "cone_like" in warnings[0].getMessage()
    assert "MeshcatCone" in warnings[0].getMessage()
    assert [(name, kind) for _, name, kind in caster.unsupported] == [("cone_like", "MeshcatCone")]
    assert caster.geometry_ids == (scene.ids["box"],)


def test_deformable_geometry_is_reported(caplog):
    scene_graph = SceneGraph()
    source = scene_graph.RegisterSource("test")
    instance = GeometryInstance(RigidTransform([0, 0, 1]), Sphere(0.5), "jelly")
    instance.set_proximity_properties(ProximityProperties())
    scene_graph.RegisterDeformableGeometry(source, scene_graph.world_frame_id(), instance, 0.2)
    with caplog.at_level(logging.WARNING, logger="corobot_drake.sensors.raycast"):
        caster = RayCaster(scene_graph.model_inspector())
    assert caster.geometry_ids == ()
    assert "jelly" in caplog.text and "deformable" in caplog.text


def test_cast_validates_shapes():
    scene = Scene([("box", Box(1, 1, 1), RigidTransform())])
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        scene.caster().cast(scene.query_object, np.zeros((2, 3)), np.ones((3, 3)), 1.0)


# ------------------------------------------------------------------ cross of rays


@pytest.mark.parametrize("samples", [1, 0, -3, 2.5, True])
def test_cross_of_rays_needs_at_least_two_samples(samples):
    with pytest.raises(ValueError, match=r"samples.*>= 2"):
        cross_of_rays_directions(RigidTransform(), samples=samples)


@pytest.mark.parametrize("angle", [-1.0, 180.0, math.nan])
def test_cross_of_rays_rejects_bad_cone_angles(angle):
    with pytest.raises(ValueError, match="dispersion_cone_angle"):
        cross_of_rays_directions(RigidTransform(), samples=3, dispersion_cone_angle=angle)


@pytest.mark.parametrize("samples", [2, 3, 4, 7])
@pytest.mark.parametrize("angle", [8.0, 30.0])
def test_cross_of_rays_spans_exactly_the_cone(samples, angle):
    d = cross_of_rays_in_sensor_frame(samples, angle)
    assert d.shape == (2 * samples, 3)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
    horizontal, vertical = d[:samples], d[samples:]
    assert np.all(horizontal[:, 2] == 0.0) and np.all(vertical[:, 1] == 0.0)
    yaw = np.degrees(np.arctan2(horizontal[:, 1], horizontal[:, 0]))
    pitch = np.degrees(np.arctan2(vertical[:, 2], vertical[:, 0]))
    expected = np.linspace(-angle / 2, angle / 2, samples)
    np.testing.assert_allclose(yaw, expected, atol=1e-12)
    np.testing.assert_allclose(pitch, expected, atol=1e-12)
    # Extreme rays of each fan are exactly the cone angle apart.
    for fan in (horizontal, vertical):
        assert math.degrees(math.acos(fan[0] @ fan[-1])) == pytest.approx(angle)


def test_cross_of_rays_follows_the_sensor_pose():
    X_WS = RigidTransform(RollPitchYaw(0.0, 0.0, math.pi), [-0.108, 0, 0.07])  # rear sensor
    d_W = cross_of_rays_directions(X_WS, samples=3, dispersion_cone_angle=8.0)
    np.testing.assert_allclose(d_W[1], [-1, 0, 0], atol=1e-12)  # centre of the horizontal fan
    np.testing.assert_allclose(d_W[4], [-1, 0, 0], atol=1e-12)  # centre of the vertical fan
    half = math.radians(4.0)
    np.testing.assert_allclose(d_W[0], [-math.cos(half), math.sin(half), 0], atol=1e-12)
    np.testing.assert_allclose(d_W[3], [-math.cos(half), 0, -math.sin(half)], atol=1e-12)


# ------------------------------------------------------------------ independent cross-check


ELLIPSOID_SD_TOLERANCE = 1e-5
"""Drake's signed distance to an ellipsoid is itself approximate (~1e-6 m off the surface; the
analytic tests above show the ray cast is exact)."""


def sphere_trace(query_object, ids, origin, direction, max_range):
    """Reference ray cast by marching with Drake's own ComputeSignedDistanceToPoint."""
    t = 0.0
    for _ in range(20000):
        p = origin + t * direction
        results = query_object.ComputeSignedDistanceToPoint(p, threshold=math.inf)
        sd = min(r.distance for r in results if r.id_G in ids)
        if sd <= 1e-10:
            return t
        t += sd
        if t > max_range:
            return math.inf
    raise AssertionError("sphere tracing did not converge")


def random_shapes(rng, mesh_files, count: int, X_WGround: RigidTransform) -> list:
    """A ground half-space at X_WGround and `count` shapes of every kind in turn, randomly
    sized and posed within 3 m of the origin: (name, shape, X_WG) for `Scene`."""
    makers = [
        lambda: Box(*rng.uniform(0.2, 1.0, 3)),
        lambda: Sphere(rng.uniform(0.1, 0.5)),
        lambda: Cylinder(rng.uniform(0.1, 0.4), rng.uniform(0.2, 1.0)),
        lambda: Capsule(rng.uniform(0.1, 0.3), rng.uniform(0.2, 0.8)),
        lambda: Ellipsoid(*rng.uniform(0.2, 0.6, 3)),
        lambda: Convex(str(mesh_files / "octahedron.obj"), rng.uniform(0.3, 0.7)),
        lambda: Mesh(str(mesh_files / "cube.obj"), rng.uniform(0.2, 0.4)),
    ]
    shapes = [("ground", HalfSpace(), X_WGround)]
    for i in range(count):
        X = RigidTransform(RollPitchYaw(*rng.uniform(-math.pi, math.pi, 3)), rng.uniform(-3, 3, 3))
        shapes.append((f"s{i}", makers[i % len(makers)](), X))
    return shapes


@pytest.mark.parametrize("anchored", [True, False], ids=["anchored", "moving"])
def test_random_scene_matches_drake_signed_distance_marching(mesh_files, anchored):
    rng = np.random.default_rng(7)
    shapes = random_shapes(rng, mesh_files, 14, RigidTransform([0, 0, -1.0]))
    scene = Scene(shapes, anchored=anchored)
    ellipsoids = {name for name, shape, _ in shapes if isinstance(shape, Ellipsoid)}
    caster = scene.caster()
    assert not caster.unsupported
    n = 150
    origins = rng.uniform(-4, 4, (n, 3))
    origins[:, 2] = rng.uniform(-0.5, 3, n)
    targets = np.array([shapes[1 + i % 14][2].translation() for i in range(n)])
    directions = targets + rng.normal(0, 0.3, (n, 3)) - origins
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    max_range = 6.0
    hits = caster.cast(scene.query_object, origins, directions, max_range)
    ids = set(scene.ids.values())
    n_hits = 0
    for i in range(n):
        expected = sphere_trace(scene.query_object, ids, origins[i], directions[i], max_range)
        if math.isinf(expected):
            assert math.isinf(hits.distance[i]), i
        else:
            n_hits += 1
            name = caster.geometry_name(hits.geometry_index[i])
            tolerance = ELLIPSOID_SD_TOLERANCE if name in ellipsoids else 1e-6
            assert hits.distance[i] == pytest.approx(expected, abs=tolerance), (i, name)
    assert n_hits > n // 2  # the test exercises hits, not just misses
    # The reported hit points lie on the surface of the reported geometry.
    hit = np.isfinite(hits.distance) & (hits.distance > 0)
    for i in np.flatnonzero(hit):
        gid = caster.geometry_ids[hits.geometry_index[i]]
        sd = {r.id_G: r.distance for r in scene.query_object.ComputeSignedDistanceToPoint(
            hits.point[i], threshold=math.inf)}[gid]  # fmt: skip
        name = caster.geometry_name(hits.geometry_index[i])
        assert abs(sd) < (ELLIPSOID_SD_TOLERANCE if name in ellipsoids else 1e-6), (i, name)


def test_empty_scene_reports_no_hits():
    scene = Scene([("own", Box(1, 1, 1), RigidTransform())])
    caster = scene.caster(exclude=["own"])
    hits = caster.cast(scene.query_object, np.zeros((3, 3)), np.eye(3), 10.0)
    assert np.all(np.isinf(hits.distance))
    assert np.all(hits.geometry_index == -1)
    assert np.isnan(hits.point).all()


def test_far_geometry_is_rejected_but_near_ones_are_not():
    scene = Scene(
        [
            ("far", Sphere(1.0), RigidTransform([100, 0, 0])),
            ("edge", Sphere(1.0), RigidTransform([5.9, 0, 0])),
        ]
    )
    caster = scene.caster()
    hits = caster.cast(scene.query_object, [[0, 0, 0], [0, 0.5, 0]], [[1, 0, 0], [1, 0, 0]], 5.5)
    assert hits.distance[0] == pytest.approx(4.9)
    assert hits.distance[1] == pytest.approx(5.9 - math.sqrt(0.75))
    assert caster.cast(scene.query_object, [[0, 0, 0]], [[-1, 0, 0]], 200.0).distance[0] == math.inf
    assert caster.cast(scene.query_object, [[0, 0, 0]], [[1, 0, 0]], 4.8).distance[0] == math.inf


def test_ray_fans_in_world():
    """Each sensor's RayFan, posed by the chassis pose, is the sensor's cross of rays from the
    sensor's origin, and its cone holds them."""
    X_BS = [
        RigidTransform([0.108, 0, 0.07]),
        RigidTransform(RotationMatrix.MakeZRotation(math.pi), [-0.108, 0, 0.07]),
    ]
    X_WB = RigidTransform(RollPitchYaw(0.1, -0.2, 2.0), [1.0, -2.0, 0.3])
    for X in X_BS:
        fan = RayFan.cross_of_rays(X, samples=3, dispersion_cone_angle=8.0)
        origin, directions, (axis, half_angle) = fan.in_world(X_WB.GetAsMatrix34().tolist())
        X_WS = X_WB @ X
        np.testing.assert_allclose(origin, X_WS.translation(), atol=1e-15)
        np.testing.assert_allclose(directions, cross_of_rays_directions(X_WS, 3, 8.0),
                                   atol=1e-15)
        np.testing.assert_allclose(axis, X_WS.rotation().col(0), atol=1e-15)
        assert half_angle == pytest.approx(math.radians(4.0))


def test_bench_scene_reads_the_spec_figures():
    """lab.bench_raycast's scene: the rear IR reads the box face at
    0.62865 m (SPEC)."""
    _, context, plant, scene_graph, chassis, robot = bench_raycast.build_scene()
    caster, scan = bench_raycast.make_fan_scan(plant, scene_graph, chassis, robot, context)
    assert len(caster.geometry_ids) == 2  # ground and giant box: the robot's own are excluded
    distances = scan()
    assert np.all(np.isinf(distances[:6]))  # front: nothing within 30 in
    assert min(distances[6:]) == pytest.approx(0.62865, abs=1e-9)
    assert math.isfinite(bench_raycast.scan_cost_seconds(repeats=10))  # value: tools/bench_ir.py


# --- cast_fan: the scalar path for one sensor's fan -----------------------------------------


def fan_distance(scene, o_W, d_W, max_range):
    """cast_fan for one ray (the cone computed by cast_fan itself)."""
    caster = scene.caster()
    return caster.cast_fan(scene.query_object, list(o_W), [list(d_W)], max_range)[0]


@pytest.mark.parametrize("anchored", [True, False], ids=["anchored", "moving"])
@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("case", CASES)
def test_cast_fan_hits_at_analytic_distance(mesh_files, case, pose, anchored):
    make, o_G, d_G, expected = CASES[case]
    X_WG = POSES[pose]
    scene = Scene([("target", make(mesh_files), X_WG)], anchored=anchored)
    o_W = X_WG @ np.asarray(o_G, float)
    d_W = X_WG.rotation() @ np.asarray(d_G, float)
    assert fan_distance(scene, o_W, d_W, 100.0) == pytest.approx(expected, abs=1e-9)
    assert fan_distance(scene, o_W, -d_W, 100.0) == math.inf
    assert fan_distance(scene, o_W, d_W, expected - 1e-6) == math.inf


@pytest.mark.parametrize("case", PASS_BY)
def test_cast_fan_near_miss(mesh_files, case):
    make, o_G, d_G = PASS_BY[case]
    for X in POSES.values():
        scene = Scene([("target", make(mesh_files), X)])
        o_W, d_W = X @ np.asarray(o_G, float), X.rotation() @ np.asarray(d_G, float)
        assert fan_distance(scene, o_W, d_W, 100.0) == math.inf, X


@pytest.mark.parametrize("case", INSIDE)
def test_cast_fan_origin_inside_is_a_hit_at_zero(mesh_files, case):
    make, o_G = INSIDE[case]
    X = POSES["rotated"]
    scene = Scene([("target", make(mesh_files), X)])
    for d_G in [(1, 0, 0), (0, 0, -1), unit(-1, 2, 0.5)]:
        assert fan_distance(scene, X @ np.asarray(o_G, float), X.rotation() @ d_G, 10.0) == 0.0


@pytest.mark.parametrize("case", ON_SURFACE)
def test_cast_fan_origin_on_the_surface_is_a_hit_at_zero(mesh_files, case):
    make, o_G = ON_SURFACE[case]
    scene = Scene([("target", make(mesh_files), RigidTransform())])
    for d_G in [(1, 0, 0), (0, 1, 0), (0, 0, 1), (-1, 0, 0), (0, -1, 0), (0, 0, -1)]:
        assert fan_distance(scene, o_G, d_G, 10.0) == 0.0, d_G


@pytest.mark.parametrize("anchored", [True, False], ids=["anchored", "moving"])
def test_cast_fan_agrees_with_cast_in_a_random_scene(mesh_files, anchored):
    """Fans of rays (each a sensor's cross of rays, with its precomputed cone, and a random
    bundle with the cone cast_fan computes) read what cast() reads for the same rays."""
    rng = np.random.default_rng(11)
    ground = HalfSpace.MakePose(unit(0.05, -0.1, 1.0), [0, 0, -0.5])
    shapes = random_shapes(rng, mesh_files, 21, ground)
    scene = Scene(shapes, anchored=anchored)
    caster = scene.caster()
    n_hits = n_rays = 0
    for trial in range(300):
        origin = rng.uniform(-3.5, 3.5, 3)
        origin[2] = rng.uniform(-0.8, 2.5)
        if trial % 2:
            look = shapes[1 + trial % 21][2].translation() - origin
            X_WS = RigidTransform(
                RotationMatrix.MakeFromOneVector(look, 0)
                @ RotationMatrix.MakeXRotation(rng.uniform(-math.pi, math.pi)),
                origin,
            )
            fan = RayFan.cross_of_rays(X_WS, int(rng.integers(2, 6)), rng.uniform(0, 60))
            o, d, cone = fan.in_world(RigidTransform().GetAsMatrix34().tolist())
        else:
            d = rng.normal(size=(int(rng.integers(1, 9)), 3))
            d = (d / np.linalg.norm(d, axis=1, keepdims=True)).tolist()
            o, cone = origin.tolist(), None
        max_range = rng.uniform(0.5, 6.0)
        expected = caster.cast(scene.query_object, np.tile(o, (len(d), 1)), d, max_range)
        got = caster.cast_fan(scene.query_object, o, d, max_range, cone)
        np.testing.assert_allclose(got, expected.distance, rtol=0, atol=1e-9)
        n_rays += len(d)
        n_hits += int(np.isfinite(expected.distance).sum())
    assert n_rays // 4 < n_hits < n_rays  # both hits and misses are exercised


def test_cast_fan_skips_what_the_cone_cannot_reach():
    """Culling by the fan's cone and range: what lies behind, beside or beyond is not hit; a
    sphere only the outermost ray passes through (its centre outside the cone) is."""
    scene = Scene(
        [
            ("behind", Box(1, 1, 1), RigidTransform([-3, 0, 0])),
            ("aside", Sphere(0.5), RigidTransform([2, 2.5, 0])),
            ("edge", Sphere(0.5), RigidTransform([4, 0.5 + 4 * math.tan(0.1), 0])),
            ("far", Box(1, 1, 1), RigidTransform([9, 0, 0])),
        ]
    )
    caster = scene.caster()
    fan = RayFan((0, 0, 0), [(math.cos(a), math.sin(a), 0.0) for a in (-0.1, 0.0, 0.1)])
    assert fan.half_angle == pytest.approx(0.1)
    o, d, cone = fan.in_world(RigidTransform().GetAsMatrix34().tolist())
    t = caster.cast_fan(scene.query_object, o, d, 8.0, cone)
    assert t[:2] == [math.inf, math.inf]
    assert t[2] < 8.0
    assert caster.cast(scene.query_object, np.tile(o, (3, 1)), d, 8.0).distance[2] == t[2]


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_cast_fan_from_an_undefined_origin_hits_nothing(axis):
    """A NaN coordinate is a miss for every ray, as in cast() (a slab test alone would read
    the ray as starting on the box's face: a hit at 0)."""
    scene = Scene([("box", Box(1.0, 1.0, 1.0), RigidTransform())])
    origin = [0.0, 0.0, 0.0]
    origin[axis] = math.nan
    directions = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    assert scene.caster().cast_fan(scene.query_object, origin, directions, 10.0) == [
        math.inf] * 3
    hits = scene.caster().cast(scene.query_object, np.array([origin] * 3), np.array(directions),
                               10.0)
    assert np.all(np.isinf(hits.distance))


# --- cast_plane: many rays in one plane (a lidar's scan) ------------------------------------


@pytest.mark.parametrize("anchored", [True, False], ids=["anchored", "moving"])
def test_cast_plane_agrees_with_cast_in_a_random_scene(mesh_files, anchored):
    """Planar scans (every shape kind, a tilted ground) read what cast() reads for the same
    rays, though cast_plane skips what lies off the scan's plane or out of its range."""
    rng = np.random.default_rng(13)
    ground = HalfSpace.MakePose(unit(0.05, -0.1, 1.0), [0, 0, -0.5])
    shapes = random_shapes(rng, mesh_files, 21, ground)
    scene = Scene(shapes, anchored=anchored)
    caster = scene.caster()
    n_hits = n_rays = 0
    for _ in range(60):
        origin = rng.uniform(-3.5, 3.5, 3)
        origin[2] = rng.uniform(-0.8, 2.5)
        R = RotationMatrix(RollPitchYaw(*rng.uniform(-math.pi, math.pi, 3))).matrix()
        a = np.linspace(-math.pi, math.pi, int(rng.integers(1, 90)), endpoint=False)
        d = np.column_stack([np.cos(a), np.sin(a), np.zeros_like(a)]) @ R.T
        max_range = rng.uniform(0.5, 6.0)
        expected = caster.cast(scene.query_object, np.tile(origin, (len(d), 1)), d, max_range)
        got = caster.cast_plane(scene.query_object, origin, d, max_range, R[:, 2])
        np.testing.assert_allclose(got, expected.distance, rtol=0, atol=1e-9)
        np.testing.assert_allclose(  # the same but for rounding (another matrix product)
            caster.cast_plane(scene.query_object, origin, d, max_range), got, rtol=0,
            atol=1e-12)
        n_rays += len(d)
        n_hits += int(np.isfinite(expected.distance).sum())
    assert n_rays // 4 < n_hits < n_rays  # both hits and misses are exercised
    assert np.all(np.isinf(caster.cast_plane(scene.query_object, [math.nan, 0.0, 0.0], d, 6.0)))
