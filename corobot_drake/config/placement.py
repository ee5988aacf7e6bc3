"""Where a robot may stand: on or above the ground and clear of the world's bodies (the
scenario's and the directives' models) and of the other robots; each free body out of the
ground. One check (`overlap_problems`) for

- the scenario's start poses, by the loader (`config/validate.py`: `problems`), on the
  scenario's collision shapes alone, in a SceneGraph of their own (no plant is built): a robot
  started inside the giant box stayed embedded, one below the ground fell through it;
- the directives' models, the same way (their shapes: `directives.ModelShape`);
- a SetPose (`Robot.obstacle_at`), on the built plant's shapes with the robot set there.

Each says what overlaps what, how deep, and the bound, in the same words.
"""

import dataclasses as dc
import logging
import math

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
    ProximityProperties,
    SceneGraph,
    Sphere,
)
from pydrake.math import RigidTransform

from corobot_drake.config import schema as sc
from corobot_drake.robots import robot_spec

GRAVITY = 9.81
"""m/s^2: Drake's default gravity."""

OVERLAP_TOLERANCE = 0.005
"""m: the deepest a start pose may overlap the ground or a body, so that a scene saved mid-run
loads again: its tyres sink up to 2.2 mm into the ground (at the largest plant step: the
table in docs/tuning.md), and a robot reversing into the giant box at full power pressed 1 mm
into it (saved every 0.25 s for 5 s at 10 and 20 ms steps).
A SetPose (`Robot.obstacle_at`) allows the same overlap with a body: a pose the loader takes
is a pose the robot can be set to, and back to where a saved scene had it."""


@dc.dataclass(frozen=True)
class Problem:
    """A start pose in something: `paths` are the poses at fault, the robot's first."""

    paths: tuple[str, ...]
    message: str
    subject: "Owner | None" = None
    """The robot (or free body) at fault."""
    obstacle: "Owner | None" = None
    """What it overlaps."""


def robot_shapes(spec=None) -> list[tuple[str, object, RigidTransform]]:
    """A robot's collision shapes (name, shape, pose in its base frame) as measured from its
    model (`robots.RobotSpec.shapes`): `spec`'s, or the Corobot's (None)."""
    return list((spec or robot_spec()).shapes)


def body_shape(shape):
    """Drake's shape of a world body's scenario shape."""
    kind = type(shape)
    if kind is sc.Box:
        return Box(*shape.size)
    if kind is sc.Sphere:
        return Sphere(shape.radius)
    if kind is sc.Cylinder:
        return Cylinder(shape.radius, shape.length)
    if kind is sc.Capsule:
        return Capsule(shape.radius, shape.length)
    if kind is sc.Ellipsoid:
        return Ellipsoid(shape.a, shape.b, shape.c)
    if kind is sc.Mesh:  # its convex hull (the file was checked before: `mesh_files`)
        from corobot_drake.config.mesh_files import mesh_source

        return Convex(mesh_source(shape.filename), shape.scale)
    return None  # a shape this check does not know: not checked


def static_sink(body, max_sink: float) -> tuple[float, float, float]:
    """How deep a free compliant world body sinks into the rigid ground under its weight at
    rest, m (an estimate), its thickness, m, and the modulus, Pa, that would hold it within
    `max_sink` of that. A hydroelastic pressure field grows from 0 at the surface to the modulus E
    at the body's inner-most point, its half-thickness h in: a flat face of area A sinks
    d = m g h / (E A); a round one (a sphere's cap) d = sqrt(m g / (pi E))."""
    weight, shape, E = body.mass * GRAVITY, body.shape, body.hydroelastic_modulus
    if isinstance(shape, sc.Box | sc.Mesh):
        extents = sorted(_extents(shape))
        h, area = extents[0] / 2, extents[0] * extents[1]
        sink, thickness = weight * h / (E * area), 2 * h
        return sink, thickness, weight * h / (area * max_sink * thickness)
    thickness = (2 * min(shape.a, shape.b, shape.c) if isinstance(shape, sc.Ellipsoid)
                 else 2 * shape.radius)
    return (math.sqrt(weight / (math.pi * E)), thickness,
            weight / (math.pi * (max_sink * thickness) ** 2))


def _extents(shape) -> list[float]:
    from corobot_drake.config.mesh_files import check_mesh_file
    from corobot_drake.resources import resolve_file

    if isinstance(shape, sc.Box):
        return list(shape.size)
    info = check_mesh_file(resolve_file(shape.filename))  # checked before: a small file
    return list((info.high - info.low) * shape.scale)


def problems(scenario, models=()) -> list[Problem]:
    """Every robot's start pose that overlaps the ground, a body, a model's body or another
    robot by more than OVERLAP_TOLERANCE, and every free body's that overlaps the ground (bodies
    may meet each other, and fixed bodies sink into the ground, as a scene is built).
    `models`: the directives' collision shapes (`directives.ModelShape`)."""
    drake_log = logging.getLogger("drake")
    level = drake_log.level
    drake_log.setLevel(logging.ERROR)  # not its warning that half-spaces skip deformable contact
    try:
        return _problems(scenario, models)
    finally:
        drake_log.setLevel(level)


def _problems(scenario, models) -> list[Problem]:
    """`problems` in a SceneGraph of the scenario's shapes and the `models`'."""
    scene_graph = SceneGraph()
    source = scene_graph.RegisterSource("placement")
    props = ProximityProperties()
    owner, poses = {}, {}
    ground = scene_graph.RegisterAnchoredGeometry(
        source, GeometryInstance(RigidTransform(), HalfSpace(), "ground"))
    scene_graph.AssignRole(source, ground, props)
    owner[ground] = Owner("the ground", None, "ground")

    def add(name: str, path: str, X_WF, shapes, kind: str) -> None:
        frame = scene_graph.RegisterFrame(source, GeometryFrame(f"{name} {len(poses)}"))
        poses[frame] = X_WF
        for shape_name, shape, X_FG in shapes:
            geometry = scene_graph.RegisterGeometry(
                source, frame, GeometryInstance(X_FG, shape, f"{name} {shape_name}"))
            scene_graph.AssignRole(source, geometry, props)
            owner[geometry] = Owner(name, path, kind)

    for name, body in scenario.world.bodies.items():
        shape = body_shape(body.shape)
        if shape is not None:
            add(f"world body {name!r}", f"world.bodies.{name}.pose",
                body.pose.GetDeterministicValue(), [("", shape, RigidTransform())],
                "fixed body" if body.fixed else "free body")
    for shape in models:
        add(f"model body {shape.name!r}", shape.path, shape.X_WG, [("", shape.shape,
            RigidTransform())], "fixed body" if shape.anchored else "free body")
    for name, robot in scenario.robots.items():
        add(f"robot {name!r}", f"robots.{name}.pose", robot.pose.GetDeterministicValue(),
            robot_shapes(robot_spec(robot.robot)), "robot")
    context = scene_graph.CreateDefaultContext()
    scene_graph.get_source_pose_port(source).FixValue(context, _frame_poses(poses))
    query = scene_graph.get_query_output_port().Eval(context)
    return overlap_problems(query.ComputePointPairPenetration(), owner.get)


@dc.dataclass(frozen=True)
class Owner:
    """What a collision geometry belongs to, in the problems' words."""

    name: str
    """`robot 'corobot'`, `world body 'box'`, `model body 'crate::crate'`, `the ground`."""
    path: str | None
    """The scenario field of its pose (None: none to name)."""
    kind: str
    """`robot`, `free body`, `fixed body` or `ground`."""


def overlap_problems(pairs, owner_of) -> list[Problem]:
    """The problems of the penetration `pairs` (Drake's `PenetrationAsPointPair`s): each
    robot that overlaps the ground, a body or another robot, each free body that overlaps the
    ground, by more than OVERLAP_TOLERANCE (their deepest pair), sorted by their paths.
    `owner_of`: a geometry id's `Owner` (None: not checked)."""
    deepest = {}  # (owner, owner) -> the deepest overlap of their shapes
    for pair in pairs:
        a, b = owner_of(pair.id_A), owner_of(pair.id_B)
        if a is None or b is None or a == b:
            continue
        if b.kind == "robot" or a.kind == "ground":
            a, b = b, a  # a robot first, else a body before the ground
        if a.kind == "robot" or (a.kind == "free body" and b.kind == "ground"):
            deepest[a, b] = max(deepest.get((a, b), 0.0), pair.depth)
    return sorted((_problem(a, b, depth) for (a, b), depth in deepest.items()
                   if depth > OVERLAP_TOLERANCE), key=lambda p: (p.paths, p.message))


def _problem(a: Owner, b: Owner, depth: float) -> Problem:
    where = "below the ground" if b.kind == "ground" else f"inside {b.name}"
    message = (f"{a.name} starts {depth * 1000:.0f} mm {where} (at most "
               f"{OVERLAP_TOLERANCE * 1000:g} mm allowed); ")
    if b.kind != "ground":
        message += "move it clear"
    elif a.kind == "robot":
        message += "lift it (z = 0 stands an upright robot on the ground)"
    else:
        message += "lift it clear of the ground"
    return Problem(tuple(o.path for o in (a, b) if o.path), message, a, b)


def _frame_poses(poses) -> FramePoseVector:
    vector = FramePoseVector()
    for frame, X_WF in poses.items():
        vector.set_value(frame, X_WF)
    return vector
