"""Loads a robot file and measures its model: `load_spec(path) -> RobotSpec`.

Every problem is one `ScenarioError` line naming the robot file, the line and the field
(`RobotFile` schema walk and bounds, then what the model contradicts)."""

from __future__ import annotations

import logging
import math
import os
from pathlib import Path

import numpy as np

from corobot_drake.config import schema as sc
from corobot_drake.config.validate import load_layer
from corobot_drake.robots import spec as sp
from corobot_drake.robots.file import RobotFile
from corobot_drake.robots.model_files import mib, model_problem
from corobot_drake.sensors.registry import KINDS

MODEL_SUFFIXES = (".urdf", ".sdf", ".xml")
"""A model file: URDF, SDFormat or MJCF (`.xml`), as Drake's parser reads them."""


def load_robot_file(path: str | Path):
    """(RobotFile, its `LayerChecks`): the file's fields checked against the schema and their
    bounds (one line per problem)."""
    text = sc.read_text(path, kind="a robot file is a YAML file")
    robot_file, checks = load_layer(str(path), text, RobotFile)
    checks.validate(robot_file)
    return robot_file, checks


def model_path(robot_file: RobotFile, path: Path, checks) -> Path:
    """The model file the robot file names, resolved and checked to be a readable model."""
    from corobot_drake.resources import resolve_file

    if not robot_file.model:
        checks.fail("model", "names the robot's URDF, SDFormat or MJCF file (relative to "
                    "the robot file)")
    try:
        model = Path(resolve_file(robot_file.model))
    except Exception as e:
        checks.fail("model", sc.one_line(e))
    model = (path.parent / model).resolve()
    if model.suffix.lower() not in MODEL_SUFFIXES:
        checks.fail("model", f"{robot_file.model!r}: a model is a URDF (.urdf), SDFormat "
                    "(.sdf) or MJCF (.xml) file")
    try:
        sc.read_bytes(model, kind="a model is a URDF, SDFormat or MJCF file",
                      max_bytes=sp.MAX_MODEL_BYTES)
    except sc.ScenarioError as e:
        checks.fail("model", f"{robot_file.model}: {e.message}")
    problem = model_problem(model)
    if problem:
        checks.fail("model", f"{robot_file.model}: {problem}")
    return model


def _parse(model: Path, checks):
    """(plant, scene_graph, model instance) of the model alone, finalized."""
    from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
    from pydrake.systems.framework import DiagramBuilder

    from corobot_drake.resources import make_parser

    plant, scene_graph = AddMultibodyPlantSceneGraph(DiagramBuilder(), 0.0)
    with _DrakeWarnings() as warnings:
        try:
            instances = make_parser(plant).AddModels(str(model))
        except Exception as e:  # Drake's parser says what is wrong, file and line
            checks.fail("model", f"Drake's parser cannot read {model.name}: {sc.one_line(e)}")
    for warning in warnings.messages:
        if "inertia" in warning.lower():  # Drake replaced it: refuse what the file says
            lines = warning.splitlines()
            where = lines[0].split(": warning:")[0]
            if "'mass > 0'" in warning:  # Drake's own words are an internal assertion's
                checks.fail("model", f"{where}: {_link_at(where)} has no mass (0 kg or less) "
                            "but an inertia")
            checks.fail("model", f"{where}: a degenerate inertia (not physical: "
                        f"{lines[-1].strip().rstrip('.')})")
    if len(instances) != 1:
        checks.fail("model", f"{model.name} holds {len(instances)} models; a robot is one")
    return plant, scene_graph, instances[0]


def _link_at(where: str) -> str:
    """"link 'name'" for the link whose element holds the model file's line `where`
    (`file:line`, as Drake's warnings say), or "a link" when that is not clear (several
    links on the line)."""
    import re

    file, _, line = where.rpartition(":")
    try:
        rows = Path(file).read_text(errors="replace").splitlines()[:int(line)]
    except (OSError, ValueError):
        return "a link"
    if len(re.findall(r"<link\b", rows[-1] if rows else "")) > 1:
        return "a link"
    names = re.findall(r"<link\s+name\s*=\s*[\"']([^\"']*)", "\n".join(rows))
    return f"link {names[-1]!r}" if names else "a link"


class _DrakeWarnings(logging.Handler):
    """Collects the warnings Drake logs (its `drake` Python logger) while in a `with`."""

    def __init__(self):
        super().__init__(logging.WARNING)
        self.messages: list[str] = []

    def emit(self, record):
        self.messages.append(record.getMessage())

    def __enter__(self):
        logger = logging.getLogger("drake")
        # Every warning reaches this handler alone (one line, not two): the logger's own
        # filters (`simulation.quiet_drake_warnings`) and level are set aside meanwhile.
        self._saved = logger.propagate, logger.level, list(logger.filters)
        logger.propagate, logger.filters = False, []
        logger.setLevel(logging.WARNING)
        logger.addHandler(self)
        return self

    def __exit__(self, *exc):
        logger = logging.getLogger("drake")
        logger.removeHandler(self)
        logger.propagate, level, logger.filters = self._saved
        logger.setLevel(level)


def _wheel_joints(robot_file: RobotFile, plant, instance, checks) -> dict:
    """{joint name: side} of the wheels, checked to be the model's revolute joints."""
    joints = [plant.get_joint(j) for j in plant.GetJointIndices(instance)]
    names = [j.name() for j in joints]
    sides = {}
    for side_name, side in (("left", sp.LEFT), ("right", sp.RIGHT)):
        listed = getattr(robot_file.wheels, side_name)
        if not listed:
            checks.fail(f"wheels.{side_name}", "needs at least one wheel joint on each side "
                        f"(the model's joints: {', '.join(names) or 'none'})")
        for i, name in enumerate(listed):
            where = f"wheels.{side_name}[{i}]"
            if name in sides:
                checks.fail(where, f"{name!r} is listed twice")
            if not plant.HasJointNamed(name, instance):
                checks.fail(where, f"the model has no joint {name!r} (its joints: "
                            f"{', '.join(names) or 'none'})")
            joint = plant.GetJointByName(name, instance)
            if joint.type_name() != "revolute":
                checks.fail(where, f"{name!r} is a {joint.type_name()} joint; a wheel turns on "
                            "a revolute joint")
            sides[name] = side
    return sides


def _shape_problem(shape) -> str | None:
    from pydrake.geometry import Convex, Mesh

    if isinstance(shape, Mesh | Convex):
        source = shape.source()
        if source.is_path():
            size = os.path.getsize(source.path()) if os.path.isfile(source.path()) else 0
            if size > sp.MAX_MESH_BYTES:
                return (f"the mesh {Path(source.path()).name} is {mib(size)}; a robot's "
                        f"collision mesh may be at most {sp.MAX_MESH_BYTES >> 20} MiB")
    return None


def _geometries(plant, scene_graph, instance, X_BW, checks):
    """[(body, geometry id, shape, X_BG, lowest z)] of the model's collision shapes, posed in
    the base frame at the start pose."""
    context = plant.CreateDefaultContext()
    inspector = scene_graph.model_inspector()
    found = []
    for index in plant.GetBodyIndices(instance):
        body = plant.get_body(index)
        X_BL = X_BW @ plant.EvalBodyPoseInWorld(context, body)
        for gid in plant.GetCollisionGeometriesForBody(body):
            shape = inspector.GetShape(gid)
            problem = _shape_problem(shape)
            if problem:
                checks.fail("model", problem)
            X_BG = X_BL @ inspector.GetPoseInFrame(gid)
            try:
                low = sp.lowest_point(shape, X_BG)
            except Exception as e:  # a mesh Drake cannot read
                checks.fail("model", f"{inspector.GetName(gid)}: {sc.one_line(e)}")
            found.append((body, gid, shape, X_BG, low))
    return found


def _wheel(name: str, side: int, plant, instance, geometries, checks, where: str) -> sp.Wheel:
    """A wheel measured from its link's collision cylinder (axis along the joint's) or
    sphere, checked to touch the ground."""
    from pydrake.geometry import Cylinder, Sphere

    joint = plant.GetJointByName(name, instance)
    body = joint.child_body()
    own = [g for g in geometries if g[0].index() == body.index()]
    shapes = [g for g in own if isinstance(g[2], Cylinder | Sphere)]
    if not shapes:
        checks.fail(where, f"{name!r}'s link {body.name()!r} has no collision cylinder or "
                    "sphere (a wheel's tyre)")
    _, _, shape, X_BG, low = min(shapes, key=lambda g: g[4])
    if abs(low) > sp.GROUND_TOLERANCE:
        checks.fail(where, f"{name!r}'s tyre does not touch the ground at the start pose: its "
                    f"lowest point is {low * 1000:+.1f} mm from the base link's origin height "
                    "(the base link's origin is on the ground)")
    if isinstance(shape, Cylinder):
        axis_B = X_BG.rotation().matrix()[:, 2]
        if abs(axis_B[1]) < 0.99:
            checks.fail(where, f"{name!r}'s tyre cylinder must lie along the robot's y axis "
                        f"(its axis in the base frame: {np.round(axis_B, 3).tolist()})")
        radius, width = shape.radius(), shape.length()
    else:
        radius, width = shape.radius(), 0.0
    inertia = body.default_rotational_inertia().CopyToFullMatrix3()
    if not body.default_mass() > 0 or not np.all(np.linalg.eigvalsh(inertia) > 0):
        checks.fail(where, f"{name!r}'s link {body.name()!r} needs a mass and an inertia "
                    f"(got {body.default_mass():g} kg, moments "
                    f"{np.round(np.linalg.eigvalsh(inertia), 9).tolist()} kg m^2)")
    center = tuple(float(v) for v in X_BG.translation())
    return sp.Wheel(name, side, body.name(), float(radius), float(width), center,
                    float(body.default_mass()))


def _agree(checks, field: str, stated, measured: float) -> float:
    """`stated` when it agrees with `measured` (`spec.AGREEMENT`), else one line."""
    if stated is None:
        return measured
    if abs(stated - measured) > max(0.001, sp.AGREEMENT * measured):
        checks.fail(field, f"states {stated:g} m but the model's wheels measure "
                    f"{measured:.6g} m")
    return float(stated)


def _geometry_figures(robot_file, wheels, checks) -> tuple[float, float, float]:
    """(radius, track, wheelbase), m: measured, or the robot file's values that agree."""
    for side_name, side in (("left", sp.LEFT), ("right", sp.RIGHT)):
        radii = [w.radius for w in wheels if w.side == side]
        if max(radii) - min(radii) > max(1e-4, 0.01 * max(radii)):
            checks.fail(f"wheels.{side_name}", "the wheels of one side must have one radius "
                        f"(got {', '.join(f'{r:.4g}' for r in radii)} m)")
    y = {side: [w.center[1] for w in wheels if w.side == side] for side in (sp.LEFT, sp.RIGHT)}
    track = math.fsum(y[sp.LEFT]) / len(y[sp.LEFT]) - math.fsum(y[sp.RIGHT]) / len(y[sp.RIGHT])
    if not track > 0:
        checks.fail("wheels.left", "the left wheels must be left of the right ones (+y of the "
                    f"base link, +x forward); the track measures {track:.4g} m")
    x = [w.center[0] for w in wheels]
    mean_x = math.fsum(x) / len(x)
    wheelbase = 2 * math.sqrt(math.fsum((v - mean_x) ** 2 for v in x) / len(x))
    radius = math.fsum(w.radius for w in wheels) / len(wheels)
    return (_agree(checks, "wheels.radius", robot_file.wheels.radius, radius),
            _agree(checks, "wheels.track", robot_file.wheels.track, track),
            _agree(checks, "wheels.wheelbase", robot_file.wheels.wheelbase, wheelbase))


def _touching(geometries, wheel_bodies: set, inspector, checks) -> list:
    """[(body, geometry id, X_BG)] of the shapes other than the wheels' that touch the ground
    at the start pose (the casters); one that goes into it by more than `GROUND_TOLERANCE`
    (as a wheel may not either) is refused: it is a body in the ground, not a caster."""
    touching = []
    for body, gid, _, X_BG, low in geometries:
        if body.index() in wheel_bodies or low > sp.GROUND_TOLERANCE:
            continue
        if low < -sp.GROUND_TOLERANCE:
            depth = f"{-low * 1000:.4g} mm" if low > -1.0 else f"{-low:.4g} m"
            checks.fail("model", f"{body.name()}/{inspector.GetName(gid).split('::')[-1]} "
                        f"goes {depth} into the ground at the start pose (at "
                        f"most {sp.GROUND_TOLERANCE * 1000:g} mm, as a caster touching it; "
                        "the base link's origin is on the ground)")
        touching.append((body, gid, X_BG))
    return touching


def _base(robot_file: RobotFile, plant, instance, checks):
    bodies = [plant.get_body(i) for i in plant.GetBodyIndices(instance)]
    if not robot_file.base:
        checks.fail("base", "names the link the scenario's pose places (its links: "
                    f"{', '.join(b.name() for b in bodies)})")
    if not plant.HasBodyNamed(robot_file.base, instance):
        checks.fail("base", f"the model has no link {robot_file.base!r} (its links: "
                    f"{', '.join(b.name() for b in bodies)})")
    base = plant.GetBodyByName(robot_file.base, instance)
    if any(b.index() == base.index() for b in plant.GetBodiesWeldedTo(plant.world_body())):
        checks.fail("base", f"{robot_file.base!r} is fixed to the world; a robot's links move")
    roots = [b.name() for b in bodies
             if not any(plant.get_joint(j).child_body().index() == b.index()
                        for j in plant.GetJointIndices(instance))]
    if robot_file.base not in roots:
        checks.fail("base", f"{robot_file.base!r} is not the model's root link (its root: "
                    f"{', '.join(roots)}); the base is the link the robot's free joint moves")
    return base


def _mass(plant, instance, base, checks) -> tuple[float, tuple]:
    """(kg, centre of mass in the base frame) of the robot, its inertias checked."""
    masses = []
    for index in plant.GetBodyIndices(instance):
        body = plant.get_body(index)
        M = body.default_spatial_inertia()
        if not M.IsPhysicallyValid():
            checks.fail("model", f"link {body.name()!r} has a degenerate inertia (not a "
                        "physical mass distribution)")
        masses.append(body.default_mass())
    composite = sum(plant.get_body(i).default_mass() for i in
                    [b.index() for b in plant.GetBodiesWeldedTo(base)])
    if not sum(masses) > 0 or not composite > 0:
        checks.fail("model", f"the robot has no mass (links: {sum(masses):g} kg, the base "
                    f"and what is fixed to it: {composite:g} kg)")
    context = plant.CreateDefaultContext()
    _check_base_inertia(plant, context, base, checks)
    com_W = plant.CalcCenterOfMassPositionInWorld(context, [instance])
    X_BW = plant.EvalBodyPoseInWorld(context, base).inverse()
    return float(sum(masses)), tuple(float(v) for v in X_BW @ com_W)


def _check_base_inertia(plant, context, base, checks) -> None:
    """Refuses a base (with what is fixed to it) whose rotational inertia about its centre of
    mass is nil about an axis (a point mass or a rod): the free body the scenario's pose
    places would turn without resistance about it."""
    bodies = [b.index() for b in plant.GetBodiesWeldedTo(base)]
    M = plant.CalcSpatialInertia(context, base.body_frame(), bodies)
    central = M.Shift(M.get_com()).CalcRotationalInertia().CopyToFullMatrix3()
    moments = np.linalg.eigvalsh(central)
    # A 1 kg ball of radius 0.1 mm has 4e-9 kg m^2: anything less is no extent at all.
    if not moments.min() > 1e-9 * M.get_mass():
        checks.fail("model", f"the base link {base.name()!r} (with what is fixed to it) has "
                    f"no rotational inertia about an axis (a point mass; its principal "
                    f"moments {np.round(moments, 9).tolist()} kg m^2)")


def _sensors(robot_file: RobotFile, links, checks) -> dict:
    """{kind field: {name: config}} of the robot file's sensors, each on a link."""
    sensors = {}
    for kind in KINDS:
        configs = getattr(robot_file, kind.field)
        for name, config in configs.items():
            frame = config.X_PB.base_frame or ""
            if frame not in links:
                checks.fail(f"{kind.field}.{name}.X_PB.base_frame",
                            f"{frame!r} is not a link of the robot ({', '.join(links)})")
        sensors[kind.field] = configs
    return sensors


def _drive(robot_file: RobotFile, radius: float, track: float, checks):
    d = robot_file.drive
    if (d.top_speed is None) == (d.motor_torque_scaling is None):
        checks.fail("drive", "needs one of top_speed (m/s at power 1) or "
                    "motor_torque_scaling (axle rad/s at power 1)")
    scaling = d.motor_torque_scaling or d.top_speed / radius
    if scaling > 200.0:
        checks.fail("drive.top_speed", f"gives {scaling:.4g} rad/s at the axle, over "
                    "the 200 rad/s an axle may turn")
    return sc.Drive(motor_torque_scaling=scaling, slew_rate=d.slew_rate,
                    max_axle_speed=d.max_axle_speed or min(200.0, 2 * scaling),
                    control_period=d.control_period, effective_wheel_radius=radius,
                    effective_track_width=track)


def _odometry_test(robot_file: RobotFile, radius: float, track: float, checks):
    """The robot file's measured odometry error as a `DriveTest` (its nominal radius and track
    the measured ones), None when it states none; all four figures or none."""
    from corobot_drake.systems.odometry_error import DRIVE_TEST_PATH, DriveTest

    o = robot_file.odometry
    figures = (o.effective_wheel_radius, o.effective_track_width, o.end_error,
               o.heading_error_deg)
    if all(f is None for f in figures):
        return None
    if any(f is None for f in figures):
        checks.fail("odometry", "needs all of effective_wheel_radius, effective_track_width, "
                    "end_error and heading_error_deg (a drive test's result), or none")
    return DriveTest(o.effective_wheel_radius, o.effective_track_width, *DRIVE_TEST_PATH,
                     o.end_error, math.radians(o.heading_error_deg), radius, track)


def _links(plant, instance) -> tuple[str, ...]:
    """The model's links, then its own frames (not those Drake makes for its joints)."""
    joint_frames = set()
    for i in plant.GetJointIndices(instance):
        joint = plant.get_joint(i)
        joint_frames |= {joint.frame_on_parent().name(), joint.frame_on_child().name()}
    bodies = [plant.get_body(i).name() for i in plant.GetBodyIndices(instance)]
    frames = [plant.get_frame(i).name() for i in plant.GetFrameIndices(instance)]
    return tuple(dict.fromkeys(
        name for name in bodies + frames
        if name and not name.startswith("__")
        and (name in bodies or name not in joint_frames)))


def load_spec(path: str | Path, kind: str | None = None) -> sp.RobotSpec:
    """The RobotSpec of the robot file `path` (`kind`: its shipped name; default its
    stem). ScenarioError (one line) for anything wrong."""
    path = Path(path).resolve()
    robot_file, checks = load_robot_file(path)
    model = model_path(robot_file, path, checks)
    plant, scene_graph, instance = _parse(model, checks)
    sides = _wheel_joints(robot_file, plant, instance, checks)
    base = _base(robot_file, plant, instance, checks)
    try:
        plant.Finalize()
    except Exception as e:
        checks.fail("model", f"Drake cannot build {model.name}: {sc.one_line(e)}")
    context = plant.CreateDefaultContext()
    X_BW = plant.EvalBodyPoseInWorld(context, base).inverse()
    geometries = _geometries(plant, scene_graph, instance, X_BW, checks)
    listed = {name: f"wheels.{'left' if side > 0 else 'right'}"
              f"[{getattr(robot_file.wheels, 'left' if side > 0 else 'right').index(name)}]"
              for name, side in sides.items()}
    order = sorted(sides, key=lambda n: int(plant.GetJointByName(n, instance).index()))
    wheels = tuple(_wheel(n, sides[n], plant, instance, geometries, checks, listed[n])
                   for n in order)
    radius, track, wheelbase = _geometry_figures(robot_file, wheels, checks)
    mass, com = _mass(plant, instance, base, checks)
    wheel_bodies = {plant.GetJointByName(n, instance).child_body().index() for n in sides}
    inspector = scene_graph.model_inspector()
    touching = _touching(geometries, wheel_bodies, inspector, checks)
    casters = tuple(f"{body.name()}/{inspector.GetName(gid).split('::')[-1]}"
                    for body, gid, _ in touching)
    caster_points = tuple((float(X_BG.translation()[0]), float(X_BG.translation()[1]))
                          for _, _, X_BG in touching)
    links = _links(plant, instance)
    drive = _drive(robot_file, radius, track, checks)
    contact = sp.default_contact(radius, mass, len(wheels), robot_file.tyres, robot_file.drive)
    from corobot_drake.robots import GENERATED_MODELS

    return sp.RobotSpec(
        kind=kind or (path.parent.name if path.stem == "robot" else path.stem), file=path,
        model_file=model,
        model_name=plant.GetModelInstanceName(instance), base=robot_file.base, wheels=wheels,
        wheel_radius=radius, track=track, wheelbase=wheelbase, mass=mass, com=com,
        # Clones: a shape the inspector returns keeps the scratch scene graph alive.
        links=links, shapes=tuple((f"{body.name()}/{inspector.GetName(gid).split('::')[-1]}",
                                   shape.Clone(), X_BG) for body, gid, shape, X_BG, _
                                  in geometries),
        casters=casters, caster_points=caster_points,
        caster_friction=robot_file.casters.friction,
        drive=drive, contact=contact,
        encoder_ticks_per_revolution=robot_file.drive.encoder_ticks_per_revolution,
        odometry_test=_odometry_test(robot_file, radius, track, checks),
        sensors=_sensors(robot_file, links, checks), generated=model in GENERATED_MODELS)
