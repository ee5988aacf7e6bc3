"""The planar lidar against meshes: a mesh that touches with its own surface (`collision:
mesh`, Drake's rigid hydroelastic mesh) is read exactly, concave or not, by slicing its
triangles with the scan plane; a `convex_hull` mesh (Drake's `Convex`) and a mesh Drake hulls
for contact keep their convex hull, bit for bit as before."""

import math

import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.geometry import (
    AddRigidHydroelasticProperties,
    Box,
    Convex,
    Mesh,
    ProximityProperties,
)
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.multibody.tree import SpatialInertia
from pydrake.systems.framework import DiagramBuilder

from corobot_drake.config.poses import mount
from corobot_drake.config.scenario import load_scenario
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.sensors.lidar import POSE, Lidar, LidarConfig
from corobot_drake.sensors.raycast import RayCaster, RayFan, model_instance_geometry_ids
from corobot_drake.simulation import Simulation

EXACT = 1e-9
"""m: a ray's closed-form intersection in doubles, a few ulps of metres."""
HEIGHT = 0.5
"""m: the scan plane's height above the ground in these scenes (the meshes stand 1 m tall)."""

U_OUTLINE = [(0.5, -1.0), (2.7, -1.0), (2.7, 1.0), (0.5, 1.0), (0.5, 0.8), (2.5, 0.8),
             (2.5, -0.8), (0.5, -0.8)]
"""m: a U open towards -x, walls 0.2 m thick: its back wall's inner face at x = 2.5, its side
walls' at y = +-0.8, its convex hull's near face at x = 0.5."""
U_CAPS = [(0, 1, 6), (0, 6, 7), (1, 2, 5), (1, 5, 6), (2, 3, 4), (2, 4, 5)]
"""Triangles of the U's outline (three rectangles): its top and bottom."""
L_OUTLINE = [(-1.0, -1.0), (3.0, -1.0), (3.0, 1.0), (1.0, 1.0), (1.0, 3.0), (-1.0, 3.0)]
"""m: an L-shaped room's floor plan (its inner faces), the robot in its corner square."""
L_CAPS = [(0, 1, 2), (0, 2, 3), (0, 3, 4), (0, 4, 5)]
OCTAGON = [(1.0 + 0.5 * math.cos(k * math.pi / 4), 0.5 * math.sin(k * math.pi / 4))
           for k in range(8)]
"""m: a convex octagonal prism of circumradius 0.5 centred at (1, 0)."""
OCTAGON_CAPS = [(0, k, k + 1) for k in range(1, 7)]


def prism_obj(path, outline, caps, height: float = 1.0) -> str:
    """Writes the closed prism over a CCW floor plan `outline` (z from 0 to height), its caps
    triangulated as `caps`, to `path`, faces counter-clockwise from outside, a normal each (the
    loader's cameras need them). Returns the path."""
    n = len(outline)
    vertices = np.array([(x, y, z) for z in (0.0, height) for x, y in outline])
    faces = []
    for i in range(n):  # the walls: bottom i, i+1 and top i+1, i
        j = (i + 1) % n
        faces += [(i, j, n + j), (i, n + j, n + i)]
    faces += [(a, c, b) for a, b, c in caps] + [(n + a, n + b, n + c) for a, b, c in caps]
    f = np.array(faces)
    normals = np.cross(vertices[f[:, 1]] - vertices[f[:, 0]], vertices[f[:, 2]] - vertices[f[:, 0]])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in vertices.tolist()]
    lines += [f"vn {x!r} {y!r} {z!r}" for x, y, z in normals.tolist()]
    lines += [f"f {a + 1}//{k} {b + 1}//{k} {c + 1}//{k}"
              for k, (a, b, c) in enumerate(faces, start=1)]
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def rigid() -> ProximityProperties:
    """A mesh that touches with its own surface (the loader's `collision: mesh`)."""
    props = ProximityProperties()
    AddRigidHydroelasticProperties(properties=props)
    return props


def lidar_among(*bodies, at=(0.0, 0.0), samples: int = 360, range_max: float = 6.0):
    """A Lidar alone (query_object fixed, initialized: one scan taken) at HEIGHT on a 0.2 m
    `chassis` box welded at `at` (x, y), its own geometry unseen, among `bodies`, each
    (shape, X_WG, ProximityProperties) anchored; (ranges, bearings)."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.01)
    bot = plant.AddModelInstance("bot")
    chassis = plant.AddRigidBody("chassis", bot, SpatialInertia.SolidBoxWithMass(
        1.0, 0.2, 0.2, 0.2))
    plant.WeldFrames(plant.world_frame(), chassis.body_frame(), RigidTransform([*at, 0.0]))
    plant.RegisterCollisionGeometry(chassis, RigidTransform(), Box(0.2, 0.2, 0.2), "chassis",
                                    ProximityProperties())
    for i, (shape, X_WG, props) in enumerate(bodies):
        plant.RegisterCollisionGeometry(plant.world_body(), X_WG, shape, f"body{i}", props)
    plant.Finalize()
    diagram = builder.Build()
    root = diagram.CreateDefaultContext()
    query = scene_graph.get_query_output_port().Eval(scene_graph.GetMyContextFromRoot(root))
    lidar = Lidar(LidarConfig(X_PB=mount((0.0, 0.0, HEIGHT), (0.0, 0.0, 0.0)),
                              samples=samples, range_min=0.0, range_max=range_max),
                  plant.GetBodyFrameIdOrThrow(chassis.index()),
                  model_instance_geometry_ids(plant, bot))
    context = lidar.CreateDefaultContext()
    lidar.get_input_port(0).FixValue(context, AbstractValue.Make(query))
    lidar.ExecuteInitializationEvents(context)
    reading = lidar.GetOutputPort("reading").Eval(context)
    return np.asarray(reading.ranges), reading.bearings()


def outline_range(a: np.ndarray, origin, *outlines) -> np.ndarray:
    """The reference: distance along each bearing a from `origin` (x, y) to the nearest edge
    of the closed polygons `outlines`, inf for a miss (a ray and a segment in closed form)."""
    o = np.asarray(origin, dtype=float)
    best = np.full(len(a), np.inf)
    for outline in outlines:
        p = np.asarray(outline, dtype=float)
        for start, end in zip(p, np.roll(p, -1, axis=0), strict=True):
            for i, (dx, dy) in enumerate(zip(np.cos(a), np.sin(a), strict=True)):
                (ax, ay), (ex, ey) = start - o, end - start
                den = dx * ey - dy * ex
                if den == 0.0:
                    continue
                t, s = (ax * ey - ay * ex) / den, (ax * dy - ay * dx) / den
                if t >= 0.0 and 0.0 <= s <= 1.0:
                    best[i] = min(best[i], t)
    return best


def test_a_u_reads_its_back_wall_through_its_open_end_not_its_hull(tmp_path):
    """From outside, looking into the U's open end: the back wall at 2.5 m straight ahead
    (its convex hull, as Drake's point contact sees it, would read 0.5 m), the arms' ends and
    inner faces at their closed forms, every ray to within EXACT."""
    u = prism_obj(tmp_path / "u.obj", U_OUTLINE, U_CAPS)
    ranges, a = lidar_among((Mesh(u), RigidTransform(), rigid()))
    expected = outline_range(a, (0.0, 0.0), U_OUTLINE)
    assert ranges[np.argmin(np.abs(a))] == pytest.approx(2.5, abs=EXACT)
    assert np.array_equal(np.isinf(ranges), np.isinf(expected))
    assert np.isfinite(expected).sum() > 100
    np.testing.assert_allclose(ranges[np.isfinite(expected)], expected[np.isfinite(expected)],
                               rtol=0, atol=EXACT)


def test_from_inside_the_u_reads_its_side_walls_and_back_wall_and_nothing_out_the_open_end(
        tmp_path):
    """Standing in the U at (1.5, 0): the side walls at 0.8 m abeam, the back wall 1 m ahead,
    the open end behind reads inf (nothing else within range)."""
    u = prism_obj(tmp_path / "u.obj", U_OUTLINE, U_CAPS)
    ranges, a = lidar_among((Mesh(u), RigidTransform(), rigid()), at=(1.5, 0.0))
    expected = outline_range(a, (1.5, 0.0), U_OUTLINE)
    for bearing, distance in ((0.0, 1.0), (math.pi / 2, 0.8), (-math.pi / 2, 0.8)):
        assert ranges[np.argmin(np.abs(a - bearing))] == pytest.approx(distance, abs=EXACT)
    assert np.isinf(ranges[np.argmin(np.abs(np.abs(a) - math.pi))])
    assert np.array_equal(np.isinf(ranges), np.isinf(expected))
    np.testing.assert_allclose(ranges[np.isfinite(expected)], expected[np.isfinite(expected)],
                               rtol=0, atol=EXACT)


def ring_obj(path, inner, height: float = 1.0, thickness: float = 0.2) -> str:
    """Walls `thickness` thick around the CCW floor plan `inner` (an axis-aligned rectilinear
    polygon), z from 0 to height, written to `path` as a closed OBJ surface."""
    n = len(inner)
    p = np.asarray(inner, dtype=float)
    # Each corner moved out along both of its edges' outward normals (for right angles).
    edge = np.roll(p, -1, axis=0) - p
    out = np.column_stack([edge[:, 1], -edge[:, 0]]) / np.linalg.norm(edge, axis=1)[:, None]
    outer = p + thickness * (out + np.roll(out, 1, axis=0))
    rings = [p, outer]
    lines = [f"v {float(x)!r} {float(y)!r} {z!r}" for z in (0.0, height) for ring in rings
             for x, y in ring]
    index = {(z, r, i): (2 * z + r) * n + i + 1 for z in (0, 1) for r in (0, 1)
             for i in range(n)}
    faces = []
    for i in range(n):
        j = (i + 1) % n
        bi, bj, ti, tj = (index[z, 0, k] for z, k in ((0, i), (0, j), (1, i), (1, j)))
        faces += [(bi, tj, bj), (bi, ti, tj)]  # inner walls face the room
        bi, bj, ti, tj = (index[z, 1, k] for z, k in ((0, i), (0, j), (1, i), (1, j)))
        faces += [(bi, bj, tj), (bi, tj, ti)]  # outer walls face out
        for z, flip in ((0, True), (1, False)):  # the walls' bottom and top
            quad = (index[z, 0, i], index[z, 0, j], index[z, 1, j], index[z, 1, i])
            a, b, c, d = quad[::-1] if flip else quad
            faces += [(a, b, c), (a, c, d)]
    lines += [f"f {a} {b} {c}" for a, b, c in faces]
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def test_a_concave_l_shaped_room_reads_its_walls_round_the_corner(tmp_path):
    """In the corner square of an L-shaped room of 0.2 m walls (its inner floor plan
    L_OUTLINE): every bearing reads the nearest inner wall, including those down each arm
    (3 m along +x, 3 m along +y), which the room's hull (the robot inside it) would read 0."""
    room = ring_obj(tmp_path / "room.obj", L_OUTLINE)
    ranges, a = lidar_among((Mesh(room), RigidTransform(), rigid()))
    expected = outline_range(a, (0.0, 0.0), L_OUTLINE)
    assert np.isfinite(expected).all()
    assert ranges[np.argmin(np.abs(a))] == pytest.approx(3.0, abs=EXACT)
    assert ranges[np.argmin(np.abs(a - math.pi / 2))] == pytest.approx(3.0, abs=EXACT)
    np.testing.assert_allclose(ranges, expected, rtol=0, atol=EXACT)


CONVEX_BEARINGS = [153, 160, 170, 178, 180, 185, 195, 207]
"""Rays of a 360-ray full circle that meet the octagon (152 to 208)."""
CONVEX_RANGES = ['0x1.6c2cf6e980577p-1', '0x1.40caebf82442cp-1', '0x1.186e5a31f5df1p-1',
                 '0x1.03ea66f7a2705p-1', '0x1.0000000000000p-1', '0x1.0aa402c310855p-1',
                 '0x1.2a1e49d5d6bdap-1', '0x1.6c2cf6e980578p-1']
"""The octagon's ranges at CONVEX_BEARINGS as its convex hull reads them, recorded before
meshes touching with their own surface were sliced: a hull's cast must not change a bit."""


@pytest.mark.parametrize("shape", [Convex, Mesh])
def test_a_hulled_mesh_reads_as_before_bit_for_bit(tmp_path, shape):
    """A `convex_hull` mesh (Convex) and a mesh Drake hulls for contact (a Mesh in point
    contact) keep the hull's polytope cast: the recorded numbers, exactly."""
    octagon = prism_obj(tmp_path / "octagon.obj", OCTAGON, OCTAGON_CAPS)
    ranges, _ = lidar_among((shape(octagon), RigidTransform(), ProximityProperties()))
    assert [float(r).hex() for r in ranges[CONVEX_BEARINGS]] == CONVEX_RANGES
    assert np.flatnonzero(np.isfinite(ranges)).tolist() == list(range(152, 209))


def test_a_convex_mesh_touching_with_its_surface_reads_as_its_hull_within_rounding(tmp_path):
    """The same octagon as `collision: mesh` is sliced, not hulled: the same rays hit, each
    range within EXACT of the hull's."""
    octagon = prism_obj(tmp_path / "octagon.obj", OCTAGON, OCTAGON_CAPS)
    sliced, _ = lidar_among((Mesh(octagon), RigidTransform(), rigid()))
    hulled, _ = lidar_among((Convex(octagon), RigidTransform(), ProximityProperties()))
    assert np.array_equal(np.isinf(sliced), np.isinf(hulled))
    np.testing.assert_allclose(sliced[np.isfinite(hulled)], hulled[np.isfinite(hulled)],
                               rtol=0, atol=EXACT)


def test_a_lidar_inside_the_solid_reads_0_on_every_ray(tmp_path):
    """Inside one of the U's arms (0.2 m thick, at y = 0.9): every ray's first hit leaves the
    solid, so it reads 0 (solids are closed sets, as for every other shape)."""
    u = prism_obj(tmp_path / "u.obj", U_OUTLINE, U_CAPS)
    ranges, _ = lidar_among((Mesh(u), RigidTransform(), rigid()), at=(1.6, 0.9))
    assert (ranges == 0.0).all()


def test_a_turned_and_moved_u_reads_as_its_posed_outline(tmp_path):
    """The U posed at (0.3, -0.4) turned 30 degrees about z: the scan reads the posed
    outline's closed forms (the slicing works in the geometry's frame)."""
    u = prism_obj(tmp_path / "u.obj", U_OUTLINE, U_CAPS)
    X_WG = RigidTransform(RollPitchYaw(0.0, 0.0, math.radians(30.0)), [0.3, -0.4, 0.0])
    ranges, a = lidar_among((Mesh(u), X_WG, rigid()))
    posed = [tuple((X_WG @ np.array([x, y, 0.0]))[:2]) for x, y in U_OUTLINE]
    expected = outline_range(a, (0.0, 0.0), posed)
    assert np.array_equal(np.isinf(ranges), np.isinf(expected))
    assert np.isfinite(expected).sum() > 100
    np.testing.assert_allclose(ranges[np.isfinite(expected)], expected[np.isfinite(expected)],
                               rtol=0, atol=EXACT)


def test_the_ir_fan_still_reads_a_concave_surface_mesh_as_its_hull(tmp_path):
    """The IR sensors' cast (`RayCaster.cast_fan`, 3D fans) keeps the hull for every mesh
    (docs/sensors.md says so): a fan from the origin into the U's open end reads the hull's
    face at 0.5 m where the lidar reads the back wall at 2.5 m."""
    u = prism_obj(tmp_path / "u.obj", U_OUTLINE, U_CAPS)
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.01)
    plant.RegisterCollisionGeometry(plant.world_body(), RigidTransform(), Mesh(u), "u", rigid())
    plant.Finalize()
    diagram = builder.Build()
    query = scene_graph.get_query_output_port().Eval(
        scene_graph.GetMyContextFromRoot(diagram.CreateDefaultContext()))
    caster = RayCaster(query.inspector())
    fan = RayFan.cross_of_rays(RigidTransform([0.0, 0.0, HEIGHT]))
    origin, directions, cone = fan.in_world(np.eye(3, 4).tolist())
    ranges = caster.cast_fan(query, origin, directions, 6.0, cone)
    assert min(ranges) == pytest.approx(0.5, abs=EXACT)
    planar = caster.cast_plane(query, np.array(origin), np.array([[1.0, 0.0, 0.0]]), 6.0,
                               np.array([0.0, 0.0, 1.0]))
    assert planar[0] == pytest.approx(2.5, abs=EXACT)


def test_a_scenario_s_collision_mesh_u_reads_its_back_wall_end_to_end(tmp_path):
    """Through the loader and the station: the default scene (the Corobot at the origin facing
    +x) with the U as a fixed world body `!Mesh {collision: mesh}` ahead and a lidar on top:
    the ray straight ahead reads the back wall, 2.5 m from the lidar's axis."""
    u = prism_obj(tmp_path / "u.obj", U_OUTLINE, U_CAPS)
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[
        "robots: {corobot: {cameras: {front: {rgb: false}}, lidars: {top: {}}}}",
        f"world: {{bodies: {{u: {{shape: !Mesh {{filename: {u}, collision: mesh}}, "
        "fixed: true, hydroelastic_modulus: 0}}}"]))
    lidar = sim.station.robots["corobot"].sensors["lidars"]["top"].system
    reading = lidar.GetOutputPort("reading").Eval(lidar.GetMyContextFromRoot(sim.context))
    X_WS = np.asarray(lidar.GetOutputPort("scan_state").Eval(
        lidar.GetMyContextFromRoot(sim.context))[POSE]).reshape(3, 4)
    ahead = int(np.argmin(np.abs(reading.bearings())))
    assert abs(X_WS[1, 3]) < 1e-3 and X_WS[0, 0] > 1 - 1e-6  # at y = 0, facing +x
    assert reading.ranges[ahead] == pytest.approx(2.5 - X_WS[0, 3], abs=1e-6)
