"""The LeafSystems that publish the run's Foxglove topics (`topics.py`) on a `foxglove.Context`.

Each publishes on periodic publish events from its input ports alone: what to publish at time
t is decided from the Context (an event is published by the first look after it), so the
systems keep no memory and a reset or replayed Context publishes the same messages. The
channels are sinks, like a file being written: the Context's sinks (an MCAP file, a live
WebSocket server) get every message. A publish event at t runs before the updates at t, so a
look at t sees what happened in [t - period, t): the event's own time stamps the message and is
its log time. What happens at the last instant of a run (after the last look) is not published.

`add_foxglove_topics` adds them all to a station's builder. The schedules, the robot state's
inputs, the wiring of the signals' own topics and the sensors' publisher are shared with ROS
2's publishers (`recording.looks`). Each sensor's topics, frame and messages are its kind's
(`sensors.kind.SensorKind`): one `looks.SensorPublisher` per sensor hands each new reading
to its `FoxgloveSensorSink`.
"""

import itertools

from foxglove.channels import (
    FrameTransformsChannel,
    JointStatesChannel,
    LogChannel,
    OdometryChannel,
    SceneUpdateChannel,
)
from foxglove.messages import (
    CubePrimitive,
    CylinderPrimitive,
    Duration,
    FrameTransforms,
    JointState,
    JointStates,
    Log,
    LogLevel,
    Odometry,
    SceneEntity,
    SceneUpdate,
    SpherePrimitive,
    TriangleListPrimitive,
)
from pydrake.common.value import AbstractValue, Value
from pydrake.geometry import Box, Convex, Cylinder, Mesh, Rgba, Sphere
from pydrake.math import RigidTransform
from pydrake.multibody.tree import BodyIndex
from pydrake.systems.framework import LeafSystem

from corobot_drake import topics as ros_names
from corobot_drake.config.poses import mount_frame
from corobot_drake.recording import topics as tp
from corobot_drake.recording.looks import (
    STATE_PERIOD,
    TELEMETRY_PERIOD,
    TOLERANCE,
    RobotStateLooks,
    SensorPublisher,
    connect_signal_topics,
    in_window,
)
from corobot_drake.robots import robot_spec

SCENE_PERIOD = 1.0
"""s: /scene (the shapes) again every second, for viewers that connect late."""


class TransformPublisher(LeafSystem):
    """/tf: every body's pose, each in its parent's frame, and the sensors' fixed mounts.

    .. pydrake_system::

        name: TransformPublisher
        input_ports:
        - body_poses

    Input `body_poses` (the plant's, abstract list of X_WB by body index). `bodies`: (body
    index, frame name, parent body index or None for the world); `parents`: {body index:
    frame name} of those parents; `mounts`: (parent frame, child frame, X_PC) fixed
    transforms. Published every `period` s as one foxglove.FrameTransforms."""

    def __init__(self, context, bodies: list, mounts: list, period: float = STATE_PERIOD):
        super().__init__()
        self._bodies = bodies
        self._frames = {index: name for index, name, _ in bodies}
        self._mounts = mounts
        self._poses = self.DeclareAbstractInputPort("body_poses",
                                                    AbstractValue.Make([RigidTransform()]))
        self._channel = FrameTransformsChannel("/tf", context=context)
        self.DeclarePeriodicPublishEvent(period, 0.0, self._publish)

    def _publish(self, context):
        t, X_W = context.get_time(), self._poses.Eval(context)
        transforms = []
        for index, name, parent in self._bodies:
            if parent is None:
                transforms.append(tp.frame_transform(t, "world", name, X_W[index]))
            else:
                transforms.append(tp.frame_transform(
                    t, self._frames[parent], name, X_W[parent].InvertAndCompose(X_W[index])))
        transforms += [tp.frame_transform(t, p, c, X) for p, c, X in self._mounts]
        self._channel.log(FrameTransforms(transforms=transforms),
                          log_time=ros_names.nanoseconds(t))


class ScenePublisher(LeafSystem):
    """/scene: the bodies' shapes as foxglove.SceneUpdate entities, each locked to its body's
    frame (from /tf), published every `period` s. No inputs: the shapes are fixed."""

    def __init__(self, context, entities: list, period: float = SCENE_PERIOD):
        super().__init__()
        self._entities = entities
        self._channel = SceneUpdateChannel("/scene", context=context)
        self.DeclarePeriodicPublishEvent(period, 0.0, self._publish)

    def _publish(self, context):
        t = context.get_time()
        self._channel.log(SceneUpdate(entities=[e(t) for e in self._entities]),
                          log_time=ros_names.nanoseconds(t))


class RobotStatePublisher(RobotStateLooks):
    """One robot's /joint_states, /odom, /drive_state and /commands.

    .. pydrake_system::

        name: RobotStatePublisher
        input_ports:
        - body_poses
        - body_spatial_velocities
        - wheel_state
        - drive_state
        - command_log

    Inputs: `looks.RobotStateLooks`' and `command_log` (abstract tuple of
    `drive.CommandRecord`, the CommandSource's). Every `period` s: the joint states, the
    odometry (pose in the world, velocity in base_link), the drive state, and a
    foxglove.Log line for each command that started or ended since the previous look."""

    def __init__(self, context, names: ros_names.RobotNames, chassis_index: int,
                 period: float = STATE_PERIOD, wheel_joints: tuple[str, ...] | None = None):
        super().__init__(chassis_index, wheel_joints)
        self._names, self._period = names, period
        self._log = self.DeclareAbstractInputPort("command_log", Value(()))
        self._joint_names = [names.frame(joint) for joint in self.wheel_joints]
        self._joint_channel = JointStatesChannel(names.topic("joint_states"), context=context)
        self._odom_channel = OdometryChannel(names.topic("odom"), context=context)
        self._drive_channel = tp.json_channel(names.topic("drive_state"),
                                              tp.DRIVE_STATE_SCHEMA, context)
        self._command_channel = LogChannel(names.topic("commands"), context=context)
        self.DeclarePeriodicPublishEvent(period, 0.0, self._publish)

    def _publish(self, context):
        t = context.get_time()
        ns = ros_names.nanoseconds(t)
        angles, rates = self.wheel_state(context)
        self._joint_channel.log(JointStates(timestamp=tp.stamp(t), joints=[
            JointState(name=name, position=float(q), velocity=float(v))
            for name, q, v in zip(self._joint_names, angles, rates, strict=True)]),
            log_time=ns)
        self._odom_channel.log(self.odometry(context), log_time=ns)
        self._drive_channel.log(tp.drive_state_message(self.drive_state(context)), log_time=ns)
        for when, message, level in self.command_events(context):
            self._command_channel.log(Log(timestamp=tp.stamp(when), level=level,
                                          message=message, name=self._names.robot),
                                      log_time=ros_names.nanoseconds(when))

    def odometry(self, context) -> Odometry:
        """The chassis pose in the world and its velocity in base_link (ROS's nav_msgs/Odometry:
        twist in the child frame)."""
        X_WB, linear, angular = self.chassis(context)
        return Odometry(timestamp=tp.stamp(context.get_time()), frame_id="world",
                        body_frame_id=self._names.base_frame(), pose=tp.pose_of(X_WB),
                        linear_velocity=tp.vector3(linear), angular_velocity=tp.vector3(angular))

    def command_events(self, context) -> list[tuple[float, str, LogLevel]]:
        """(time, line, level) of each command start and end since the previous look, in time
        order (a Wait's end is its scheduled end)."""
        t, events = context.get_time(), []
        for record in self._log.Eval(context):
            if in_window(record.start_time, t, self._period):
                events.append((record.start_time, tp.command_event(record, False),
                               LogLevel.Info))
            if record.end_time is not None and in_window(record.end_time, t, self._period):
                level = LogLevel.Warning if record.status == "failed" else LogLevel.Info
                events.append((record.end_time, tp.command_event(record, True), level))
        return sorted(events, key=lambda e: e[0])


class TelemetryPublisher(LeafSystem):
    """One robot's signals with a message of their own: each of `topics.TELEMETRY_TOPICS`
    (the contact telemetry: /wheel_loads, /wheel_slip, /tip_margin), JSON.

    .. pydrake_system::

        name: TelemetryPublisher
        input_ports:
        - wheel_loads
        - wheel_slip_ratio
        - wheel_slip_angle
        - tip_margin

    Inputs: the robot's ports of its signals (`signals.Signal.port`: the contact telemetry's,
    `contact.WheelContacts`: one per wheel each, N, 1, deg, in the robot's wheel order;
    `stability.TipMargin`: 1, deg), those of the costly topics
    held: sampled every `costly_period` s from 0 (`_add_telemetry`'s ZeroOrderHolds). A look
    every `period` s publishes the others' values, stamped with its time; a look every
    `costly_period` s the costly ones' held values, stamped with their sample's time (a period
    before; at 0 nothing is sampled yet)."""

    def __init__(self, context, names: ros_names.RobotNames, period: float = STATE_PERIOD,
                 costly_period: float = TELEMETRY_PERIOD, topics: tuple | None = None):
        """`topics`: the robot's (`topics.telemetry_topics`; default the Corobot's)."""
        super().__init__()
        for topic in topics or ros_names.TELEMETRY_TOPICS:
            ports = [self.DeclareVectorInputPort(spec.port, spec.size) for spec in topic.signals]
            channel = tp.json_channel(names.topic(topic.name), topic.schema(), context)
            # The looks on the holds' own schedule (period, offset 0): a look and a sample at
            # one time are at the same float time, the look first.
            self.DeclarePeriodicPublishEvent(costly_period if topic.costly else period, 0.0,
                                             self._publisher(topic, ports, channel,
                                                             costly_period if topic.costly
                                                             else 0.0))

    @staticmethod
    def _publisher(topic: ros_names.TelemetryTopic, ports: list, channel, age: float):
        """The publish event of `topic`, whose inputs are `age` s old (a hold's period, or
        0)."""
        def publish(context):
            t = context.get_time() - age
            if t < -TOLERANCE:
                return  # nothing sampled yet
            channel.log(topic.message(t, [port.Eval(context) for port in ports]),
                        log_time=ros_names.nanoseconds(t))
        return publish


class FoxgloveSensorSink:
    """A sensor's Foxglove channels (its kind's `foxglove_channels`, under the robot's
    namespace), and what a `looks.SensorPublisher` hands them: each new reading's messages
    (`foxglove_message`, in the sensor's frame), logged at the reading's time."""

    def __init__(self, context, names: ros_names.RobotNames, sensor):
        self._kind, self._frame = sensor.kind, names.frame(sensor.kind.frame_name(sensor.name))
        topic = self._kind.topic_name(sensor.name)
        self._channels = {sub: _channel(names.topic(f"{topic}/{sub}" if sub else topic),
                                        schema, context)
                          for sub, schema in self._kind.foxglove_channels().items()}

    def __call__(self, reading) -> None:
        messages = self._kind.foxglove_message(reading, self._frame)
        if messages is None:
            return
        if list(self._channels) == [""]:  # one topic: the message itself (JSON: a dict)
            messages = {"": messages}
        ns = ros_names.nanoseconds(self._kind.reading_time(reading))
        for sub, message in messages.items():
            self._channels[sub].log(message, log_time=ns)


def _channel(topic: str, schema, context):
    """The channel of `topic`: of a foxglove-sdk message class by its name, or JSON of a
    JSON schema (a dict)."""
    if isinstance(schema, dict):
        return tp.json_channel(topic, schema, context)
    import foxglove.channels

    return getattr(foxglove.channels, f"{schema}Channel")(topic, context=context)


# --- wiring -------------------------------------------------------------------------------


def _body_frames(plant, robots: dict, first: tuple[str, ...]) -> dict:
    """{body index: (frame name, parent body index or None)}: a robot's chassis and every other
    body in the world, a robot's other links in its chassis (`topics.robot_names` names them,
    from the robots the run started with, `first`)."""
    robot_of = {int(parts.model_instance): parts for parts in robots.values()}
    frames = {}
    for i in range(1, plant.num_bodies()):
        body = plant.get_body(BodyIndex(i))
        parts = robot_of.get(int(body.model_instance()))
        if parts is not None:
            names = ros_names.robot_names(parts.name, first, parts.chassis.name())
            parent = None if body.index() == parts.chassis.index() else int(parts.chassis.index())
            frames[i] = (names.body_frame(body.name()), parent)
        else:
            model = plant.GetModelInstanceName(body.model_instance())
            frames[i] = (body.name() if body.name() == model else f"{model}/{body.name()}", None)
    return frames


def _primitive(inspector, gid, rgba):
    """(kind, foxglove primitive) of geometry `gid` if a Box, Cylinder or Sphere; None for
    other shapes."""
    shape = inspector.GetShape(gid)
    pose, c = tp.pose_of(inspector.GetPoseInFrame(gid)), tp.color(rgba)
    if isinstance(shape, Box):
        return "cubes", CubePrimitive(pose=pose, size=tp.vector3(shape.size()), color=c)
    if isinstance(shape, Cylinder):
        d = 2 * shape.radius()
        return "cylinders", CylinderPrimitive(pose=pose, size=tp.vector3([d, d, shape.length()]),
                                              bottom_scale=1.0, top_scale=1.0, color=c)
    if isinstance(shape, Sphere):
        d = 2 * shape.radius()
        return "spheres", SpherePrimitive(pose=pose, size=tp.vector3([d, d, d]), color=c)
    return None


def _hull(inspector, gid, rgba):
    """("triangles", foxglove triangle list) of geometry `gid`'s convex hull if a Mesh or
    Convex (SceneGraph's, of the scaled mesh: a few hundred triangles however large the mesh,
    since /scene is sent again every second); None for other shapes and for a mesh Drake
    cannot hull."""
    if not isinstance(inspector.GetShape(gid), Mesh | Convex):
        return None
    try:
        hull = inspector.GetConvexHull(gid)
    except RuntimeError:  # a model's GLB: Drake hulls OBJ, glTF and VTK
        return None
    if hull is None:
        return None
    points = []
    for face in range(hull.num_faces()):
        polygon = hull.element(face)
        corners = [tp.point3(hull.vertex(polygon.vertex(k)))
                   for k in range(polygon.num_vertices())]
        for b, c in itertools.pairwise(corners[1:]):  # a fan: the polygon is convex
            points += [corners[0], b, c]
    return "triangles", TriangleListPrimitive(pose=tp.pose_of(inspector.GetPoseInFrame(gid)),
                                              points=points, color=tp.color(rgba))


COLLISION_COLOR = (0.6, 0.6, 0.65, 1.0)
"""A body drawn from its collision shapes (its visuals are meshes) is this grey."""


def _scene_entities(plant, scene_graph, frames: dict) -> list:
    """One entity maker per body with a shape: its visual boxes, cylinders and spheres in
    their colours; else (mesh visuals, as the robot's) its collision shapes in grey; else
    (meshes only, as a `!Mesh` world body's) its visual meshes' convex hulls."""
    inspector = scene_graph.model_inspector()
    makers = []
    for i, (frame, _) in [(0, ("world", None)), *frames.items()]:
        body = plant.get_body(BodyIndex(i))
        visual = plant.GetVisualGeometriesForBody(body)
        passes = ((visual, True, _primitive),
                  (plant.GetCollisionGeometriesForBody(body), False, _primitive),
                  (visual, True, _hull))
        for ids, colored, draw in passes:
            shapes = _drawn(inspector, ids, colored, draw)
            if shapes:
                makers.append(_entity_maker(frame, shapes))
                break
    return makers


def _drawn(inspector, ids, colored: bool, draw) -> dict[str, list]:
    """{SceneEntity field: primitives} of the geometries `ids` that `draw` can draw, in their
    illustration colour if `colored`, else grey."""
    shapes: dict[str, list] = {}
    for gid in ids:
        rgba = COLLISION_COLOR
        if colored:
            props = inspector.GetIllustrationProperties(gid)
            rgba = props.GetPropertyOrDefault("phong", "diffuse", Rgba(*COLLISION_COLOR)).rgba
        made = draw(inspector, gid, rgba)
        if made is not None:
            shapes.setdefault(made[0], []).append(made[1])
    return shapes


def _entity_maker(frame: str, shapes: dict):
    def make(t: float) -> SceneEntity:
        return SceneEntity(timestamp=tp.stamp(t), frame_id=frame, id=frame, frame_locked=True,
                           lifetime=Duration(0, 0), **shapes)
    return make


def add_foxglove_topics(builder, plant, scene_graph, robots: dict, scenario, context,
                        first: tuple[str, ...] | None = None) -> None:
    """Adds the publishers of every topic (`topics.py`) for a station's plant and robots
    ({name: station.RobotParts}, built from `scenario`), on the foxglove `context`; `first`:
    the robots the run started with (default: these), whose names a robot keeps when another
    is added while the run goes on (`topics.robot_names`)."""
    first = tuple(robots) if first is None else tuple(first)
    frames = _body_frames(plant, robots, first)
    mounts = []
    for name, parts in robots.items():
        names = ros_names.robot_names(name, first, parts.chassis.name())
        state = builder.AddNamedSystem(f"{name}.foxglove_state", RobotStatePublisher(
            context, names, parts.chassis.index(),
            wheel_joints=tuple(j.name() for j in parts.wheel_joints)))
        RobotStateLooks.connect(builder, plant, name, state)
        builder.Connect(parts.command_source.GetOutputPort("command_log"),
                        state.GetInputPort("command_log"))
        _add_telemetry(builder, context, names, ros_names.telemetry_topics(
            robot_spec(scenario.robots[name].robot)))
        for sensors in parts.sensors.values():
            for sensor in sensors.values():
                mounts.append(_add_sensor(builder, plant, frames, context, names, parts,
                                          sensor))
    tf = builder.AddNamedSystem("foxglove_tf", TransformPublisher(
        context, [(i, f, p) for i, (f, p) in frames.items()], mounts))
    builder.Connect(plant.get_body_poses_output_port(), tf.get_input_port())
    builder.AddNamedSystem("foxglove_scene", ScenePublisher(
        context, _scene_entities(plant, scene_graph, frames)))


def _add_telemetry(builder, context, names: ros_names.RobotNames, topics: tuple) -> None:
    """Adds `<robot>.foxglove_telemetry` of its `topics`, fed by the robot's signals' ports,
    the costly topics' through holds `<robot>.foxglove_<port>` (`looks.connect_signal_topics`)."""
    publisher = builder.AddNamedSystem(f"{names.robot}.foxglove_telemetry",
                                       TelemetryPublisher(context, names, topics=topics))
    connect_signal_topics(builder, names.robot, publisher, topics, "foxglove_")


def _mount(plant, frames: dict, child: str, mount) -> tuple:
    """(parent frame, child frame, X_PC) of a sensor mounted at `mount` = (body, X_BS)."""
    body, X_BS = mount
    parent = "world" if body.index() == plant.world_body().index() else frames[
        int(body.index())][0]
    return parent, child, X_BS


def _add_sensor(builder, plant, frames: dict, context, names, parts, sensor) -> tuple:
    """Adds `<robot>.foxglove_<kind topic>.<sensor>` for one of the robot's sensors (a
    `sensors.kind.BuiltSensor`) if its kind has Foxglove channels; returns the mount of the
    sensor's frame."""
    kind = sensor.kind
    if kind.foxglove_channels():
        publisher = builder.AddNamedSystem(
            f"{names.robot}.foxglove_{kind.topic}.{sensor.name}",
            SensorPublisher(sensor, FoxgloveSensorSink(context, names, sensor)))
        publisher.connect(builder)
    return _mount(plant, frames, names.frame(kind.frame_name(sensor.name)),
                  mount_frame(plant, parts.model_instance, sensor.X_PB))


__all__ = ["STATE_PERIOD", "TELEMETRY_PERIOD", "FoxgloveSensorSink", "RobotStatePublisher",
           "ScenePublisher", "TelemetryPublisher", "TransformPublisher", "add_foxglove_topics",
           "in_window"]
