"""Builds the simulation diagram from a Scenario: world, robots, their drives, visualization.

One function, `build_station`, in the style of Drake's hardware_sim and the manipulation
station: every robot's systems are named `<robot>.<system>` and its ports are exported as
`<robot>.<port>`. Each robot is built from its `robots.RobotSpec` (its model, wheels, drive
and tyres: the Corobot's generated model, any other parsed from its robot file's model by
`robots.build`). It builds in phases (the plant, with each sensor's own geometry; each
robot's drive, telemetry and sensors, every sensor through its kind in `sensors.registry`;
then the hooks; then Meshcat's own visualizers), and knows no front end: the Meshcat
markers, the Foxglove and MCAP topics and the ROS 2 topics attach through its `extras` hooks,
which their callers pass.
"""

import dataclasses as dc
import functools
import math
from collections.abc import Callable, Iterable

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
    RoleAssign,
    Sphere,
)
from pydrake.math import RigidTransform
from pydrake.multibody.parsing import ModelDirectives, ProcessModelDirectives
from pydrake.multibody.plant import (
    AddMultibodyPlant,
    CoulombFriction,
    MultibodyPlant,
    MultibodyPlantConfig,
)
from pydrake.multibody.tree import CalcSpatialInertia, SpatialInertia, UnitInertia
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import MatrixGain

from corobot_drake import signals
from corobot_drake.config import scenario as sc
from corobot_drake.config.mesh_files import mesh_source
from corobot_drake.model.sdf import corobot_sdf
from corobot_drake.resources import make_parser
from corobot_drake.robots import RobotSpec, robot_spec
from corobot_drake.robots.build import add_robot_model
from corobot_drake.sensors.registry import add_geometry, add_sensors
from corobot_drake.sensors.site import SensorSite
from corobot_drake.systems.contact import add_wheel_contacts
from corobot_drake.systems.dead_reckoning import DeadReckoning
from corobot_drake.systems.drive import CommandSource, DriveController
from corobot_drake.systems.motion import MotionCommands
from corobot_drake.systems.odometry import add_chassis_poses, add_chassis_states, add_odometry
from corobot_drake.systems.runlog import add_contact_states, add_run_log, spec_layout
from corobot_drake.systems.servo import add_servo_sign, servo_velocity_sign
from corobot_drake.systems.stability import add_tip_margin


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
        return Mesh(mesh_source(shape.filename), shape.scale)
    raise TypeError(f"unsupported shape {shape!r}")


def _collision_geometry(shape):
    """What a world body touches with: its shape, or a mesh's convex hull (`Mesh.collision`)."""
    if isinstance(shape, sc.Mesh) and shape.collision == "convex_hull":
        return Convex(mesh_source(shape.filename), shape.scale)
    return _geometry(shape)


_HYDRO_RESOLUTION_FRACTION = 0.1
"""A world body's hydroelastic mesh size as a fraction of its size (boxes ignore it)."""


def _size(shape) -> float:
    """A collision shape's (Drake's) characteristic size, m: its thinnest extent."""
    if isinstance(shape, Box):
        return float(min(shape.size()))
    if isinstance(shape, Ellipsoid):
        return 2 * min(shape.a(), shape.b(), shape.c())
    if isinstance(shape, Mesh | Convex):
        low, high = shape.GetConvexHull().CalcBoundingBox()
        return float(min(high - low))
    return 2 * shape.radius()


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
            resolution_hint=_HYDRO_RESOLUTION_FRACTION * _size(_collision_geometry(spec.shape)),
            hydroelastic_modulus=spec.hydroelastic_modulus, properties=props)
    elif isinstance(spec.shape, sc.Mesh) and spec.shape.collision == "mesh":
        AddRigidHydroelasticProperties(properties=props)
    return props


def _add_directives(plant: MultibodyPlant, scene_graph, directives: list,
                    friction: float | None = None) -> dict:
    """The scenario's model directives (Drake's `ProcessModelDirectives`), their collision
    geometries given `friction` unless None (`World.model_friction`); returns {model name:
    model instance} of the models they add."""
    if not directives:
        return {}
    added = ProcessModelDirectives(ModelDirectives(directives=directives), plant,
                                   make_parser(plant))
    models = {info.model_name: info.model_instance for info in added}
    if friction is not None:
        set_model_friction(plant, scene_graph, models.values(), friction)
    for gid in free_point_contact_geometries(plant, scene_graph, models.values()):
        props = ProximityProperties(scene_graph.model_inspector().GetProximityProperties(gid))
        shape = scene_graph.model_inspector().GetShape(gid)
        AddCompliantHydroelasticProperties(
            resolution_hint=_HYDRO_RESOLUTION_FRACTION * _size(shape),
            hydroelastic_modulus=sc.WorldBody.hydroelastic_modulus, properties=props)
        scene_graph.AssignRole(plant.get_source_id(), gid, props, RoleAssign.kReplace)
    return models


def set_model_friction(plant: MultibodyPlant, scene_graph, instances, friction: float) -> None:
    """Gives every collision geometry of the model instances the Coulomb friction `friction`
    (static = dynamic), whatever their files said (before the plant is finalized)."""
    inspector = scene_graph.model_inspector()
    for instance in instances:
        for index in plant.GetBodyIndices(instance):
            for gid in plant.GetCollisionGeometriesForBody(plant.get_body(index)):
                props = ProximityProperties(inspector.GetProximityProperties(gid))
                props.UpdateProperty("material", "coulomb_friction",
                                     CoulombFriction(friction, friction))
                scene_graph.AssignRole(plant.get_source_id(), gid, props, RoleAssign.kReplace)


def free_point_contact_geometries(plant: MultibodyPlant, scene_graph, instances) -> list:
    """The collision geometries of the models' free bodies (not welded to the world) that
    their files give no hydroelastic properties: point contact holds a free body on the rigid
    ground at one point and a face sinks through it (`config/validate.py`, RIGID_ON_GROUND), so
    they touch as a world body does by default, compliant-hydroelastic (half-spaces aside)."""
    inspector = scene_graph.model_inspector()
    anchored = {body.index() for body in plant.GetBodiesWeldedTo(plant.world_body())}
    geometries = []
    for instance in instances:
        for index in plant.GetBodyIndices(instance):
            if index in anchored:
                continue
            for gid in plant.GetCollisionGeometriesForBody(plant.get_body(index)):
                props = inspector.GetProximityProperties(gid)
                if not (props.HasProperty("hydroelastic", "compliance_type")
                        or isinstance(inspector.GetShape(gid), HalfSpace)):
                    geometries.append(gid)
    return geometries


@dc.dataclass
class RobotParts:
    """Handles to one robot's pieces of the diagram."""

    name: str
    model_instance: object
    chassis: object
    """The robot's base body (the Corobot's `chassis`): the body its pose places."""
    wheel_joints: list
    """Its wheels' revolute joints, in wheel order (`spec.wheels`)."""
    command_source: CommandSource
    drive_controller: DriveController
    motion: MotionCommands | None = None
    """DriveDistance / RotateDegrees / SetPose state machine (`motion.py`)."""
    chassis_pose: object = None
    """The output port of its chassis pose (RigidTransform, world frame)."""
    sensors: dict = dc.field(default_factory=dict)
    """{kind field (`sensors.registry.KINDS`): {name: `kind.BuiltSensor`}}: what
    `sensors.registry.add_sensors` returns (sensors turned off left out)."""
    spec: RobotSpec | None = None
    """What the robot is (`robots.RobotSpec`): its wheels, radius, track, drive, links."""

    def all_sensors(self) -> dict:
        """{sensor name: `kind.BuiltSensor`} of every kind (names are unique in a robot)."""
        return {name: s for sensors in self.sensors.values() for name, s in sensors.items()}

    @property
    def ir_sensors(self) -> dict:
        """{sensor name: `ir_sensor.IrSensor`}."""
        return {name: s.system for name, s in self.sensors.get("ir_sensors", {}).items()}

    @property
    def cameras(self) -> dict:
        """{camera name: `camera.Camera`}."""
        return {name: s.extra["camera"] for name, s in self.sensors.get("cameras", {}).items()}


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
    visualization_lcm: object = None
    """With Meshcat: the in-process LCM bus Drake's visualizers publish on (held here: the
    diagram's publishers only point at it)."""
    render_workers: list = dc.field(default_factory=list)
    """The cameras' render workers (`sensors.render_worker`): a thread each, which `close`
    ends (a `Simulation` does when it is freed)."""

    def close(self) -> None:
        """Ends the cameras' render threads: after it the diagram's delayed GL cameras can take
        no frame (simulating on raises), so close a station when done with it (a Simulation
        closes its own when it is freed). Idempotent."""
        for worker in self.render_workers:
            worker.close()


def _add_robot(plant: MultibodyPlant, scene_graph, name: str, robot: sc.Robot):
    """One robot from its RobotSpec: the model (the Corobot's generated with the scenario's
    tyres and look; any other parsed from its file and given the tyres, the casters'
    friction and one velocity servo per wheel: `robots.build`), named `name`, its base at the
    scenario's pose. Returns (instance, base body, wheel joints in wheel order)."""
    spec = robot_spec(robot.robot)
    if spec.generated:
        sdf = corobot_sdf(name, robot.contact, robot.visual)
        (instance,) = make_parser(plant).AddModelsFromString(sdf, "sdf")
    else:
        instance = add_robot_model(plant, scene_graph, name, spec, robot.contact,
                                   robot.visual)
    chassis = plant.GetBodyByName(spec.base, instance)
    plant.SetDefaultFloatingBaseBodyPose(chassis, robot.pose.GetDeterministicValue())
    joints = [plant.GetJointByName(j, instance) for j in spec.wheel_joints]
    return instance, chassis, joints


def _connect_servos(builder, plant, instance, name: str, desired_state, sign: float) -> None:
    """The drive's desired state to the robot's wheel servos, through `<name>.servo_sign` when
    the integrator turns the servos' desired velocity around (`systems/servo.py`)."""
    if sign != 1.0:
        fix = add_servo_sign(builder, f"{name}.servo_sign", sign, desired_state.size())
        builder.Connect(desired_state, fix.get_input_port())
        desired_state = fix.get_output_port()
    builder.Connect(desired_state, plant.get_desired_state_input_port(instance))


StationHook = Callable[[DiagramBuilder, MultibodyPlant, object, dict, sc.Scenario], None]
"""A front end's systems, added by `build_station` before it builds the diagram: called as
`hook(builder, plant, scene_graph, robots, scenario)`, `robots` {name: RobotParts} (their
sensors built, `RobotParts.sensors`); e.g. `markers.add_meshcat_markers`,
`recording.publishers.add_foxglove_topics`, `ros2.publishers.add_ros2_topics`, each bound to
its sink with `functools.partial`."""


def add_scene(builder, scenario: sc.Scenario, plant_config=None):
    """The station's first phase: the scenario's plant (`plant_config`, default the
    scenario's) and scene graph with the world, the directives' models and the robots with
    their sensors' own geometry and frames (each kind's `add_geometry`), finalized. Returns
    (plant, scene_graph, {world body name: body}, {model name: instance}, {robot name:
    (instance, chassis, wheel joints)})."""
    plant, scene_graph = AddMultibodyPlant(plant_config or scenario.plant_config, builder)
    bodies = _add_world(plant, scenario.world)
    models = _add_directives(plant, scene_graph, scenario.directives,
                             scenario.world.model_friction)
    added = {name: _add_robot(plant, scene_graph, name, robot)
             for name, robot in scenario.robots.items()}
    for name, robot in scenario.robots.items():
        add_geometry(plant, added[name][0], name, robot)
    plant.Finalize()
    return plant, scene_graph, bodies, models, added


RENDER_COPY = MultibodyPlantConfig(time_step=1e9)
"""The plant of a camera's render copy (`sensors.render_worker`): only its state is set, and
its own update (a SAP step, every 1e9 s of the copy's clock, which advances 1 s a frame)
never comes to change it."""


def build_station(scenario: sc.Scenario, meshcat=None, save_camera=None,
                  extras: Iterable[StationHook] = (), mouse_drag: bool = True) -> Station:
    """Builds the whole diagram for `scenario`, in phases: the plant (world, directives,
    robots), each robot's drive and monitors, its sensors, then the front ends' `extras`
    (`StationHook`s: the systems of a front end the station need not know), then Meshcat. With
    `meshcat`, adds Drake's visualizers (and, with `mouse_drag`, Ctrl-drag of bodies:
    `MESHCAT_DRAG_STIFFNESS`); with `save_camera` (a directory), each robot's camera frames are
    saved there as PNG (`camera.save_directory`)."""
    render_workers = []
    try:
        return _build_station(scenario, meshcat, save_camera, extras, mouse_drag,
                              render_workers)
    except BaseException:
        for worker in render_workers:  # no station will close them
            worker.close()
        raise


def _build_station(scenario: sc.Scenario, meshcat, save_camera, extras, mouse_drag: bool,
                   render_workers: list) -> Station:
    builder = DiagramBuilder()
    plant, scene_graph, bodies, models, added = add_scene(builder, scenario)

    chassis = {name: parts[1] for name, parts in added.items()}
    # One chassis pose per robot (from the plant's body_poses, converted once per step) for
    # its compass, GPS and odometry; and its chassis' state (C++, no pose conversion) for what
    # samples every step: the run log (`<name>.chassis_state`), and from it the largest tilt.
    chassis_poses = add_chassis_poses(builder, plant, chassis)
    add_chassis_states(builder, plant, chassis)
    robots, renderers, renderer_classes = {}, {}, {}
    step = sc.physics_step(scenario.plant_config, scenario.simulator_config)
    for name, robot in scenario.robots.items():
        robots[name] = _add_drive(builder, plant, scenario, name, added[name],
                                  chassis_poses[name])
        robots[name].sensors = add_sensors(SensorSite(
            builder, plant, scene_graph, name, robots[name].model_instance, scenario.world,
            scenario.random_seed, step, save_camera, renderers, renderer_classes,
            functools.partial(_add_render_copy, scenario=scenario, robot=name),
            render_workers), robot)
    for extra in extras:
        extra(builder, plant, scene_graph, robots, scenario)
    continuous = sc.continuous_step(scenario.plant_config, scenario.simulator_config) > 0
    for name in robots:
        _add_signal_outputs(builder, name, continuous,
                            spec_layout(robot_spec(scenario.robots[name].robot),
                                        robots[name].sensors), robots[name].sensors)
    if continuous:
        add_contact_states(builder, plant, robots)
    builder.ExportOutput(plant.get_body_poses_output_port(), "body_poses")
    builder.ExportOutput(scene_graph.get_query_output_port(), "query_object")
    lcm = None
    if meshcat is not None:
        lcm = _add_meshcat(builder, plant, scene_graph, meshcat, scenario.world, mouse_drag,
                           sc.continuous_step(scenario.plant_config, scenario.simulator_config))
    diagram = builder.Build()
    diagram.set_name("corobot_station")
    return Station(diagram, plant, scene_graph, robots, bodies, models, meshcat, renderers,
                   lcm, render_workers)


def _add_render_copy(builder, scenario: sc.Scenario, robot: str):
    """A copy of the scene for a camera's render worker: (plant, scene_graph, the robot's
    model instance)."""
    plant, scene_graph, _, _, added = add_scene(builder, scenario, RENDER_COPY)
    return plant, scene_graph, added[robot][0]


def _add_drive(builder, plant, scenario: sc.Scenario, name: str, added, chassis_pose
               ) -> RobotParts:
    """One robot's command source, motion commands, drive controller and wheel servos, its
    odometry and its monitors (contact telemetry, tip margin)."""
    robot = scenario.robots[name]
    spec = robot_spec(robot.robot)
    instance, chassis, joints = added
    source = builder.AddNamedSystem(
        f"{name}.commands", CommandSource(robot.commands, robot.drive.control_period))
    controller = builder.AddNamedSystem(f"{name}.drive_controller", DriveController(
        robot.drive, spec.sides, spec.wheel_radius))
    selector = builder.AddNamedSystem(f"{name}.wheel_state", MatrixGain(
        plant.MakeStateSelectorMatrix([j.index() for j in joints])))
    builder.Connect(plant.get_state_output_port(), selector.get_input_port())
    builder.Connect(selector.get_output_port(), controller.GetInputPort("wheel_state"))
    motion = builder.AddNamedSystem(f"{name}.motion", MotionCommands(
        robot.drive, robot.motion, spec.wheel_radius, spec.spin_yaw_per_rim_speed))
    odometry = add_odometry(
        builder, name, chassis_pose, selector.get_output_port(),
        controller.GetOutputPort("drive_status"), controller.GetOutputPort("axle_speed"),
        robot.drive.motor_torque_scaling, spec)
    dead_reckoning = builder.AddNamedSystem(
        f"{name}.dead_reckoning", DeadReckoning(robot.drive, robot.drive.control_period,
                                                spec.encoder_ticks_per_revolution))
    builder.Connect(odometry.encoder_ticks, dead_reckoning.GetInputPort("encoder_ticks"))
    builder.Connect(chassis_pose, dead_reckoning.GetInputPort("chassis_pose"))
    builder.ExportOutput(dead_reckoning.GetOutputPort("pose"), f"{name}.odometry")
    # Command source -> motion commands -> drive controller; status back to the source.
    builder.Connect(source.GetOutputPort("request"), motion.GetInputPort("request"))
    builder.Connect(odometry.position, motion.GetInputPort("position"))
    builder.Connect(odometry.heading, motion.GetInputPort("heading"))
    builder.Connect(motion.GetOutputPort("drive_request"), controller.GetInputPort("request"))
    builder.Connect(motion.GetOutputPort("command_status"), source.GetInputPort("command_status"))
    for port_name, port in (("encoder_ticks", odometry.encoder_ticks),
                            ("heading", odometry.heading), ("position", odometry.position),
                            ("drive_state", odometry.drive_state),
                            ("command_status", motion.GetOutputPort("command_status"))):
        builder.ExportOutput(port, f"{name}.{port_name}")
    _connect_servos(builder, plant, instance, name, controller.GetOutputPort("desired_state"),
                    servo_velocity_sign(scenario.simulator_config))
    _add_telemetry(builder, plant, name, added, chassis_pose, selector.get_output_port(),
                   sc.continuous_step(scenario.plant_config, scenario.simulator_config), spec)
    for port in ("drive_status", "axle_speed_command", "axle_speed"):
        builder.ExportOutput(controller.GetOutputPort(port), f"{name}.{port}")
    builder.ExportOutput(plant.get_state_output_port(instance), f"{name}.state")
    return RobotParts(name, instance, chassis, joints, source, controller, motion=motion,
                      chassis_pose=chassis_pose, spec=spec)


def _add_telemetry(builder, plant, name: str, added, chassis_pose, wheel_state,
                   continuous_step: float, spec: RobotSpec) -> None:
    """The wheels' contact telemetry (`<name>.wheel_contacts`; on a continuous plant, step
    `continuous_step` > 0, its loads from the robot's momentum over each step) and the tip
    margin (`<name>.tip_margin`)."""
    instance, chassis, joints = added
    add_wheel_contacts(builder, name, plant, [j.child_body() for j in joints], chassis_pose,
                       wheel_state, chassis, continuous_step, spec.wheel_radius)
    add_tip_margin(builder, name, plant, instance, chassis,
                   {w: j.child_body() for w, j in zip(spec.wheel_names, joints, strict=True)},
                   chassis_pose, spec.wheel_radius, spec.caster_points)


def signal_output(builder, robot: str, spec: signals.Signal):
    """The output port of the signal `spec` (one with a `system`) in a station's builder."""
    return builder.GetSubsystemByName(f"{robot}.{spec.system}").GetOutputPort(spec.port)


def _add_signal_outputs(builder, name: str, continuous: bool, layout, sensors) -> None:
    """Exports each signal's port from its system as `<name>.<port>` (`signals.SIGNALS`
    with a `system`; once every system is in, the front ends' extras too), and adds the run
    log (`runlog.add_run_log`), which samples those of its `layout.sampled` (the robot's
    `runlog.Layout`; on a `continuous` plant, the held ones are made when it is read:
    `runlog.ContactSamples`), then its `sensors`' columns (`SensorKind.log_columns`)."""
    by_port = {}
    for spec in signals.SIGNALS.values():
        if spec.system:
            by_port[spec.port] = signal_output(builder, name, spec)
            builder.ExportOutput(by_port[spec.port], f"{name}.{spec.port}")
    add_run_log(builder, name, builder.GetSubsystemByName(f"{name}.chassis_state")
                .get_output_port(),
                builder.GetSubsystemByName(f"{name}.drive_controller").GetOutputPort(
                    "drive_status"),
                builder.GetSubsystemByName(f"{name}.encoder_ticks").get_output_port(),
                {port: by_port[port] for port, _ in layout.sampled}, held_when_read=continuous,
                layout=layout, sensors=sensors)


MESHCAT_DRAG_STIFFNESS = 100.0
"""1/s^2, mass-normalized: the spring of Drake's `MeshcatMouseSpring` that pulls a body
Ctrl-dragged in Meshcat toward the cursor (10 rad/s, critically damped; a push of the robot
or a box by hand, like a hand in the lab). Only interactive Meshcat runs have it: headless,
served-without-Meshcat and scripted runs stay free of outside forces and reproducible."""


def visualization_config():
    """Meshcat layers: the visual meshes (`illustration`), contact forces, and the collision
    shapes (`proximity`, translucent red). Drake adds the proximity layer hidden
    (`visible_by_default = false`); tick drake > proximity in Meshcat's Scene panel (and
    untick illustration) for the physics view. (`initial_proximity_alpha` only seeds Drake's
    optional alpha slider, so the translucency is in the colour.) Ctrl-drag moves a body
    (`MESHCAT_DRAG_STIFFNESS`)."""
    from pydrake.geometry import Rgba
    from pydrake.visualization import VisualizationConfig

    return VisualizationConfig(publish_contacts=True, publish_proximity=True,
                               default_proximity_color=Rgba(0.8, 0.0, 0.0, 0.6),
                               mouse_interaction_stiffness=MESHCAT_DRAG_STIFFNESS)


def _add_meshcat(builder, plant, scene_graph, meshcat, world: sc.World, mouse_drag: bool,
                 continuous_step: float = 0.0):
    """Adds Drake's Meshcat visualizers and the scene's looks; returns the LCM bus they use.
    On a continuous plant (its step `continuous_step` > 0) they publish on its steps
    (`publish_period_on_steps`)."""
    from pydrake.lcm import DrakeLcm
    from pydrake.visualization import ApplyVisualizationConfig

    config = visualization_config()
    if not mouse_drag:
        config.mouse_interaction_stiffness = None
    config.publish_period = meshcat_publish_period(continuous_step)
    # Meshcat only: Drake's default LCM bus would also publish every frame as UDP multicast
    # for Meldis; an in-process bus keeps the run off the network.
    lcm = DrakeLcm("memq://")
    ApplyVisualizationConfig(config, builder, plant=plant, scene_graph=scene_graph,
                             meshcat=meshcat, lcm=lcm)
    sky = list(world.sky_color)
    # Its <object>: the page warns about a colour set on "/Background" itself.
    meshcat.SetProperty("/Background/<object>", "top_color", sky)
    meshcat.SetProperty("/Background/<object>", "bottom_color",
                        [min(1.0, c * 1.15) for c in sky])
    meshcat.SetProperty("/Grid", "visible", False)
    _set_meshcat_sun(meshcat, world.sun)
    return lcm


def meshcat_publish_period(continuous_step: float) -> float:
    """s: how often the Meshcat visualizers publish: Drake's default (1/64 s), or on a
    continuous plant (its step `continuous_step` > 0) the 2^j steps at least that."""
    period = visualization_config().publish_period
    return publish_period_on_steps(period, continuous_step) if continuous_step > 0 else period


def publish_period_on_steps(period: float, step: float) -> float:
    """s: the shortest 2^j `step` (j >= 0) at least `period`. Its event times k 2^j step are
    the same doubles as the plant's k' step (doubling is exact), so on a continuous plant they
    add no step between its steps; 5 step, say, would not (0.05 x 3 is not 0.01 x 15)."""
    return step * 2.0 ** max(0, math.ceil(math.log2(period / step) - 1e-9))


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
