"""Builds the simulation diagram from a Scenario: world, robots, their drives, visualization.

One function, `build_station`, in the style of Drake's hardware_sim and the manipulation
station: every robot's systems are named `<robot>.<system>` and its ports are exported as
`<robot>.<port>`.
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.geometry import (
    AddCompliantHydroelasticProperties,
    AddContactMaterial,
    AddRigidHydroelasticProperties,
    Box,
    Capsule,
    Convex,
    Cylinder,
    Ellipsoid,
    HalfSpace,
    Mesh,
    ProximityProperties,
    Sphere,
)
from pydrake.math import RigidTransform
from pydrake.multibody.parsing import ModelDirectives, ProcessModelDirectives
from pydrake.multibody.plant import AddMultibodyPlant, CoulombFriction, MultibodyPlant
from pydrake.multibody.tree import CalcSpatialInertia, SpatialInertia, UnitInertia
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import MatrixGain

from corobot_drake.config import scenario as sc
from corobot_drake.model import dimensions as dim
from corobot_drake.model.sdf import corobot_sdf
from corobot_drake.resources import make_parser, resolve_file
from corobot_drake.sensors.camera import add_camera
from corobot_drake.sensors.ir_sensor import add_ir_sensors
from corobot_drake.systems.contact import add_wheel_contacts
from corobot_drake.systems.dead_reckoning import DeadReckoning
from corobot_drake.systems.drive import CommandSource, DriveController
from corobot_drake.systems.monitor import TiltMonitor
from corobot_drake.systems.motion import MotionCommands
from corobot_drake.systems.odometry import add_chassis_poses, add_odometry
from corobot_drake.systems.runlog import add_run_log
from corobot_drake.systems.slip_markers import add_slip_markers
from corobot_drake.systems.stability import add_tip_margin

TILT_SAMPLE_PERIOD = 0.01
"""s. Tilt changes over tenths of a second even in a flip; 100 Hz catches its peak."""


def _geometry(shape):
    if isinstance(shape, sc.Box):
        return Box(*shape.size)
    if isinstance(shape, sc.Sphere):
        return Sphere(shape.radius)
    if isinstance(shape, sc.Cylinder):
        return Cylinder(shape.radius, shape.length)
    if isinstance(shape, sc.Capsule):
        return Capsule(shape.radius, shape.length)
    if isinstance(shape, sc.Ellipsoid):
        return Ellipsoid(shape.a, shape.b, shape.c)
    if isinstance(shape, sc.Mesh):
        return Mesh(resolve_file(shape.filename), shape.scale)
    raise TypeError(f"unsupported shape {shape!r}")


def _collision_geometry(shape):
    """What a world body touches with: its shape, or a mesh's convex hull (`Mesh.collision`)."""
    if isinstance(shape, sc.Mesh) and shape.collision == "convex_hull":
        return Convex(resolve_file(shape.filename), shape.scale)
    return _geometry(shape)


_HYDRO_RESOLUTION_FRACTION = 0.1
"""A world body's hydroelastic mesh size as a fraction of its size (boxes ignore it)."""


def _size(shape) -> float:
    """A shape's characteristic size, m."""
    if isinstance(shape, sc.Box):
        return min(shape.size)
    if isinstance(shape, sc.Ellipsoid):
        return 2 * min(shape.a, shape.b, shape.c)
    if isinstance(shape, sc.Mesh):
        low, high = _collision_geometry(shape).GetConvexHull().CalcBoundingBox()
        return float(min(high - low))
    return 2 * shape.radius


def _spatial_inertia(shape, mass: float) -> SpatialInertia:
    """A solid of uniform density: about the body frame's origin (a mesh's centre of mass
    is wherever its file puts it; the primitives' is the origin)."""
    if isinstance(shape, sc.Mesh):
        unit = CalcSpatialInertia(_collision_geometry(shape), 1.0)  # its convex hull's
        return SpatialInertia(mass, unit.get_com(), unit.get_unit_inertia())
    return SpatialInertia(mass, np.zeros(3), _unit_inertia(shape))


def _unit_inertia(shape) -> UnitInertia:
    if isinstance(shape, sc.Box):
        return UnitInertia.SolidBox(*shape.size)
    if isinstance(shape, sc.Sphere):
        return UnitInertia.SolidSphere(shape.radius)
    if isinstance(shape, sc.Cylinder):
        return UnitInertia.SolidCylinder(shape.radius, shape.length, [0, 0, 1])
    if isinstance(shape, sc.Capsule):
        return UnitInertia.SolidCapsule(shape.radius, shape.length, [0, 0, 1])
    return UnitInertia.SolidEllipsoid(shape.a, shape.b, shape.c)


def _add_world(plant: MultibodyPlant, world: sc.World) -> dict:
    """Ground and world bodies; returns {name: body} of the free bodies."""
    ground = ProximityProperties()
    AddContactMaterial(friction=CoulombFriction(world.ground.friction, world.ground.friction),
                       properties=ground)
    # Rigid, so the compliant tyres meet it hydroelastically (compliant-compliant with a
    # half-space would fall back to point contact).
    AddRigidHydroelasticProperties(properties=ground)
    plant.RegisterCollisionGeometry(plant.world_body(), RigidTransform(), HalfSpace(), "ground",
                                    ground)
    plant.RegisterVisualGeometry(plant.world_body(), RigidTransform([0, 0, -0.005]),
                                 Box(40, 40, 0.01), "ground",
                                 np.asarray(world.ground.color, dtype=float))
    bodies = {}
    for name, spec in world.bodies.items():
        instance = plant.AddModelInstance(name)
        if spec.fixed:
            body = plant.AddRigidBody(name, instance, SpatialInertia.Zero())
            plant.WeldFrames(plant.world_frame(), body.body_frame(),
                             spec.pose.GetDeterministicValue())
        else:
            body = plant.AddRigidBody(name, instance, _spatial_inertia(spec.shape, spec.mass))
            plant.SetDefaultFloatingBaseBodyPose(body, spec.pose.GetDeterministicValue())
        plant.RegisterCollisionGeometry(body, RigidTransform(), _collision_geometry(spec.shape),
                                        name, _body_contact(spec))
        plant.RegisterVisualGeometry(body, RigidTransform(), _geometry(spec.shape), name,
                                     np.asarray(spec.color, dtype=float))
        bodies[name] = body
    return bodies


def _body_contact(spec: sc.WorldBody) -> ProximityProperties:
    """A world body's friction and hydroelastic properties: compliant with a modulus; without,
    point contact, except a mesh touching with its own surface (rigid hydroelastic: Drake's
    point contact would use its convex hull)."""
    props = ProximityProperties()
    AddContactMaterial(friction=CoulombFriction(spec.friction, spec.friction), properties=props)
    if spec.hydroelastic_modulus > 0:
        AddCompliantHydroelasticProperties(
            resolution_hint=_HYDRO_RESOLUTION_FRACTION * _size(spec.shape),
            hydroelastic_modulus=spec.hydroelastic_modulus, properties=props)
    elif isinstance(spec.shape, sc.Mesh) and spec.shape.collision == "mesh":
        AddRigidHydroelasticProperties(properties=props)
    return props


def _add_directives(plant: MultibodyPlant, directives: list) -> dict:
    """The scenario's model directives (Drake's `ProcessModelDirectives`); returns {model
    name: model instance} of the models they add."""
    if not directives:
        return {}
    added = ProcessModelDirectives(ModelDirectives(directives=directives), plant,
                                   make_parser(plant))
    return {info.model_name: info.model_instance for info in added}


@dc.dataclass
class RobotParts:
    """Handles to one robot's pieces of the diagram."""

    name: str
    model_instance: object
    chassis: object
    wheel_joints: list
    command_source: CommandSource
    drive_controller: DriveController
    tilt_monitor: TiltMonitor
    camera: object = None
    """The system whose outputs are the latest frame: `RgbdSensorAsync` (the default) or
    `camera.CameraHold`; None without a camera."""
    camera_saver: object = None
    """`camera.CameraFrameSaver` when frames are saved."""
    motion: MotionCommands | None = None
    """DriveDistance / RotateDegrees / SetPose state machine (`motion.py`)."""
    ir_sensors: dict = dc.field(default_factory=dict)
    """{sensor name: `ir_sensor.IrSensor`}."""


@dc.dataclass
class Station:
    """The built diagram and handles into it."""

    diagram: Diagram
    plant: MultibodyPlant
    scene_graph: object
    robots: dict[str, RobotParts]
    bodies: dict
    """{name: body} of the world's bodies (`world.bodies`)."""
    models: dict = dc.field(default_factory=dict)
    """{model name: model instance} of the models the scenario's directives add."""
    meshcat: object = None
    renderers: dict = dc.field(default_factory=dict)
    """The cameras' render engines: renderer name -> "RenderEngineGl" or "RenderEngineVtk"."""


def _add_robot(plant: MultibodyPlant, name: str, robot: sc.Robot):
    sdf = corobot_sdf(name, robot.contact, robot.visual)
    (instance,) = make_parser(plant).AddModelsFromString(sdf, "sdf")
    chassis = plant.GetBodyByName("chassis", instance)
    plant.SetDefaultFloatingBaseBodyPose(chassis, robot.pose.GetDeterministicValue())
    joints = [plant.GetJointByName(f"{w}_axle", instance) for w in dim.WHEEL_NAMES]
    return instance, chassis, joints


def build_station(scenario: sc.Scenario, meshcat=None, save_camera=None, foxglove=None,
                  extras=()) -> Station:
    """Builds the whole diagram for `scenario`; with `meshcat`, adds its visualizers; with
    `save_camera` (a directory), each robot's camera frames are saved there as PNG; with
    `foxglove` (a `foxglove.Context`), the publishers of the run's Foxglove topics
    (`recording.publishers`). Each of `extras` is called as `extra(builder, plant,
    scene_graph, robots, scenario)` before the diagram is built, to add systems of a front end
    the station need not know (the ROS 2 topics: `ros2.publishers.add_ros2_topics`)."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(scenario.plant_config, builder)
    bodies = _add_world(plant, scenario.world)
    models = _add_directives(plant, scenario.directives)
    added = {name: _add_robot(plant, name, robot) for name, robot in scenario.robots.items()}
    plant.Finalize()

    robots, renderers = {}, {}
    # One chassis pose per robot (from the plant's body_poses, converted once per step) for
    # its compass, GPS, tilt monitor and run log.
    chassis_poses = add_chassis_poses(builder, plant,
                                      {name: parts[1] for name, parts in added.items()})
    for name, robot in scenario.robots.items():
        instance, chassis, joints = added[name]
        source = builder.AddNamedSystem(
            f"{name}.commands", CommandSource(robot.commands, robot.drive.control_period))
        controller = builder.AddNamedSystem(
            f"{name}.drive_controller", DriveController(robot.drive))
        selector = builder.AddNamedSystem(
            f"{name}.wheel_state", MatrixGain(plant.MakeStateSelectorMatrix(
                [j.index() for j in joints])))
        builder.Connect(plant.get_state_output_port(), selector.get_input_port())
        builder.Connect(selector.get_output_port(), controller.GetInputPort("wheel_state"))
        # Command source -> motion commands -> drive controller; status back to the source.
        motion = builder.AddNamedSystem(f"{name}.motion", MotionCommands(robot.drive,
                                                                          robot.motion))
        chassis_pose = chassis_poses[name]
        odometry = add_odometry(
            builder, name, chassis_pose, selector.get_output_port(),
            controller.GetOutputPort("drive_status"), controller.GetOutputPort("axle_speed"),
            robot.drive.motor_torque_scaling)
        dead_reckoning = builder.AddNamedSystem(
            f"{name}.dead_reckoning", DeadReckoning(robot.drive, robot.drive.control_period))
        builder.Connect(odometry.encoder_ticks, dead_reckoning.GetInputPort("encoder_ticks"))
        builder.Connect(chassis_pose, dead_reckoning.GetInputPort("chassis_pose"))
        builder.ExportOutput(dead_reckoning.GetOutputPort("pose"), f"{name}.odometry")
        contacts = add_wheel_contacts(builder, name, plant, [j.child_body() for j in joints],
                                      chassis_pose, selector.get_output_port())
        for port in ("wheel_loads", "wheel_slip_ratio", "wheel_slip_angle"):
            builder.ExportOutput(contacts.GetOutputPort(port), f"{name}.{port}")
        if meshcat is not None:
            add_slip_markers(builder, meshcat, name, chassis_pose, contacts)
        tip_margin = add_tip_margin(
            builder, name, plant, instance, chassis,
            {w: j.child_body() for w, j in zip(dim.WHEEL_NAMES, joints, strict=True)},
            chassis_pose)
        builder.ExportOutput(tip_margin.get_output_port(), f"{name}.tip_margin")
        builder.Connect(source.GetOutputPort("request"), motion.GetInputPort("request"))
        builder.Connect(odometry.position, motion.GetInputPort("position"))
        builder.Connect(odometry.heading, motion.GetInputPort("heading"))
        builder.Connect(motion.GetOutputPort("drive_request"), controller.GetInputPort("request"))
        builder.Connect(motion.GetOutputPort("command_status"),
                        source.GetInputPort("command_status"))
        for port_name, port in (("encoder_ticks", odometry.encoder_ticks),
                                ("heading", odometry.heading), ("position", odometry.position),
                                ("drive_state", odometry.drive_state),
                                ("command_status", motion.GetOutputPort("command_status"))):
            builder.ExportOutput(port, f"{name}.{port_name}")
        builder.Connect(controller.GetOutputPort("desired_state"),
                        plant.get_desired_state_input_port(instance))
        tilt = builder.AddNamedSystem(f"{name}.tilt_monitor", TiltMonitor(TILT_SAMPLE_PERIOD))
        builder.Connect(chassis_pose, tilt.GetInputPort("chassis_pose"))
        add_run_log(builder, name, chassis_pose, controller.GetOutputPort("drive_status"),
                    odometry.encoder_ticks,
                    {"wheel_loads": contacts.GetOutputPort("wheel_loads"),
                     "wheel_slip_ratio": contacts.GetOutputPort("wheel_slip_ratio"),
                     "wheel_slip_angle": contacts.GetOutputPort("wheel_slip_angle"),
                     "tip_margin": tip_margin.GetOutputPort("tip_margin")})
        for port in ("drive_status", "axle_speed_command", "axle_speed"):
            builder.ExportOutput(controller.GetOutputPort(port), f"{name}.{port}")
        builder.ExportOutput(plant.get_state_output_port(instance), f"{name}.state")
        robots[name] = RobotParts(name, instance, chassis, joints, source, controller, tilt,
                                  motion=motion)
        robots[name].camera, robots[name].camera_saver = add_camera(
            builder, plant, scene_graph, name, instance, robot.camera, scenario.world,
            renderers, save_camera)
        robots[name].ir_sensors = add_ir_sensors(
            builder, plant, scene_graph, name, robot.ir_sensors, model_instance=instance,
            random_seed=scenario.random_seed, meshcat=meshcat)

    if foxglove is not None:
        from corobot_drake.recording.publishers import add_foxglove_topics

        add_foxglove_topics(builder, plant, scene_graph, robots, scenario, foxglove)
    for extra in extras:
        extra(builder, plant, scene_graph, robots, scenario)
    builder.ExportOutput(plant.get_body_poses_output_port(), "body_poses")
    builder.ExportOutput(scene_graph.get_query_output_port(), "query_object")
    if meshcat is not None:
        _add_meshcat(builder, plant, scene_graph, meshcat, scenario.world)
    diagram = builder.Build()
    diagram.set_name("corobot_station")
    return Station(diagram, plant, scene_graph, robots, bodies, models, meshcat, renderers)


def visualization_config():
    """Meshcat layers: the visual meshes (`illustration`), contact forces, and the collision
    shapes (`proximity`, translucent red). Drake adds the proximity layer hidden
    (`visible_by_default = false`); tick drake > proximity in Meshcat's Scene panel (and
    untick illustration) for the physics view. (`initial_proximity_alpha` only seeds Drake's
    optional alpha slider, so the translucency is in the colour.)"""
    from pydrake.geometry import Rgba
    from pydrake.visualization import VisualizationConfig

    return VisualizationConfig(publish_contacts=True, publish_proximity=True,
                               default_proximity_color=Rgba(0.8, 0.0, 0.0, 0.6))


def _add_meshcat(builder, plant, scene_graph, meshcat, world: sc.World) -> None:
    from pydrake.visualization import ApplyVisualizationConfig

    ApplyVisualizationConfig(visualization_config(), builder,
                             plant=plant, scene_graph=scene_graph, meshcat=meshcat)
    sky = list(world.sky_color)
    meshcat.SetProperty("/Background", "top_color", sky)
    meshcat.SetProperty("/Background", "bottom_color", [min(1.0, c * 1.15) for c in sky])
    meshcat.SetProperty("/Grid", "visible", False)
    _set_meshcat_sun(meshcat, world.sun)


MESHCAT_SUN = "/Lights/FillLight/<object>"
"""Meshcat's one directional light (its default scene names it FillLight)."""

MESHCAT_SUN_DISTANCE = 10.0
"""m: where the light sits, up-sun of the origin (a three.js directional light shines from
its position towards its target, the origin)."""

MESHCAT_DIRECTIONAL_INTENSITY = 0.4 * math.pi
"""Meshcat's default directional intensity (0.4 in three.js's legacy units, which its
physically based lights scale by pi): the sun's intensity 1."""


def _set_meshcat_sun(meshcat, sun: sc.Sun) -> None:
    """Meshcat's other default lights (ambient, two points) stay; its directional light
    becomes the sun: shining along `sun.direction` at `sun.intensity`."""
    d = np.asarray(sun.direction, dtype=float)
    meshcat.SetProperty(MESHCAT_SUN, "position",
                        list(-d / np.linalg.norm(d) * MESHCAT_SUN_DISTANCE))
    meshcat.SetProperty(MESHCAT_SUN, "intensity",
                        float(sun.intensity) * MESHCAT_DIRECTIONAL_INTENSITY)
