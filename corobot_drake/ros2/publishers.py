"""The LeafSystems that publish the robot's ROS 2 topics (`interfaces.TOPICS`) on a `bus.Bus`.

As the Foxglove recording's (`recording.publishers`; the schedules, windows, the robot state's
inputs and the signals' own topics' wiring are shared: `recording.looks`): each publishes on
periodic publish events from its input ports alone, so they keep no memory and a reset or
replayed Context publishes the same messages, at the same simulated times, live (`--ros2`) or
into a bag (`--rosbag`). A look at t sees what happened in [t - period, t).

`add_ros2_topics` adds them all to a station's builder (`station.build_station`'s `extras`).
Each sensor's topics, frames and messages are its kind's (`sensors.kind.SensorKind`): one
`recording.looks.SensorPublisher` per sensor hands each new reading to its `RosSensorSink`.
"""

from __future__ import annotations

from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform
from pydrake.systems.framework import LeafSystem

from corobot_drake import topics as tp
from corobot_drake.config.poses import mount_frame
from corobot_drake.recording.looks import (
    STATE_PERIOD,
    TELEMETRY_PERIOD,
    TOLERANCE,
    RobotStateLooks,
    SensorPublisher,
    connect_signal_topics,
)
from corobot_drake.ros2 import interfaces as ifc
from corobot_drake.ros2.messages import Messages

CLOCK_PERIOD = 0.01
"""s: /clock at 100 Hz (the plant's default step: a look adds no Simulator stop)."""
ODOM_FRAME = "odom"
"""The fixed frame /odom's poses are in: where the odometry started, which is the world's
origin and axes (the dead reckoning integrates from the true start pose, and a teleport puts
it at the true pose)."""
WORLD_FRAME = "world"
"""With several robots, /tf_static joins each robot's odom to this one frame."""


def _channel(bus, names: tp.RobotNames | None, topic: ifc.Topic):
    """The bus channel of `topic`, under the robot's namespace unless shared."""
    name = f"/{topic.name}" if names is None or topic.shared else names.topic(topic.name)
    return bus.channel(name, topic.type, topic.qos)


class ClockPublisher(LeafSystem):
    """/clock (rosgraph_msgs/Clock): the simulation time every `period` s. No inputs."""

    def __init__(self, bus, period: float = CLOCK_PERIOD):
        super().__init__()
        self._m = Messages(bus.store)
        self._channel = _channel(bus, None, ifc.TOPIC["clock"])
        self.DeclarePeriodicPublishEvent(period, 0.0, self._publish)

    def _publish(self, context):
        if self._channel.watched():
            t = context.get_time()
            self._channel.publish(tp.nanoseconds(t), self._m.clock(t))


class StaticPublisher(LeafSystem):
    """/tf_static and each robot's /robot_description, once, at initialization (latched: a
    late subscriber gets them). No inputs. `mounts`: (parent, child, X_PC) fixed transforms;
    `descriptions`: {robot names: URDF text}."""

    def __init__(self, bus, mounts: list, descriptions: dict):
        super().__init__()
        self._m = Messages(bus.store)
        self._mounts = mounts
        self._tf = _channel(bus, None, ifc.TOPIC["tf_static"])
        self._descriptions = [(_channel(bus, names, ifc.TOPIC["robot_description"]), text)
                              for names, text in descriptions.items()]
        self.DeclareInitializationPublishEvent(self._publish)

    def _publish(self, context):
        t = context.get_time()
        ns = tp.nanoseconds(t)
        self._tf.publish(ns, self._m.tf([self._m.transform(t, p, c, X)
                                         for p, c, X in self._mounts]))
        for channel, text in self._descriptions:
            channel.publish(ns, self._m.string(text))


class TransformPublisher(LeafSystem):
    """/tf: each robot's odom -> base_link (its dead reckoning, or with `ground_truth` its
    chassis pose in the world) and base_link -> its wheels' frames, every `period` s, in one
    tf2_msgs/TFMessage.

    .. pydrake_system::

        name: TransformPublisher
        input_ports:
        - body_poses
        - <robot>_odometry (one per robot; not with ground_truth)

    Input `body_poses` (the plant's: abstract list of X_WB by body index); `<robot>_odometry`
    (3: the robot's dead-reckoned x, y m, yaw rad). `robots`: for each robot, (its
    `RobotNames`, chassis body index, [(wheel body index, wheel frame)])."""

    def __init__(self, bus, robots: list, period: float = STATE_PERIOD,
                 ground_truth: bool = False):
        super().__init__()
        self._m = Messages(bus.store)
        self._robots = [(names.frame(ODOM_FRAME), names.base_frame(), int(chassis),
                         [(int(i), frame) for i, frame in wheels],
                         None if ground_truth else self.DeclareVectorInputPort(
                             f"{names.robot}_odometry", 3))
                        for names, chassis, wheels in robots]
        self._poses = self.DeclareAbstractInputPort("body_poses",
                                                    AbstractValue.Make([RigidTransform()]))
        self._channel = _channel(bus, None, ifc.TOPIC["tf"])
        self.DeclarePeriodicPublishEvent(period, 0.0, self._publish)

    def _publish(self, context):
        if not self._channel.watched():
            return
        t, X_W = context.get_time(), self._poses.Eval(context)
        transforms = []
        for odom, base, chassis, wheels, odometry in self._robots:
            X_WB = X_W[chassis]
            X_OB = X_WB if odometry is None else _planar(odometry.Eval(context))
            transforms.append(self._m.transform(t, odom, base, X_OB))
            transforms += [self._m.transform(t, base, frame, X_WB.InvertAndCompose(X_W[i]))
                           for i, frame in wheels]
        self._channel.publish(tp.nanoseconds(t), self._m.tf(transforms))


class RobotStatePublisher(RobotStateLooks):
    """One robot's /odom, /wheel_odom, /joint_states and /drive_state, every `period` s.

    .. pydrake_system::

        name: RobotStatePublisher
        input_ports:
        - body_poses
        - body_spatial_velocities
        - wheel_state
        - drive_state
        - odometry
        - travel

    Inputs: `recording.looks.RobotStateLooks`' and `odometry` (3: the dead-reckoned x, y m,
    yaw rad) and `travel` (2: the distance rolled m and turning rad since its last reset,
    `systems.dead_reckoning.DeadReckoning`'s). /wheel_odom: the dead reckoning, its twist from
    the front axles' measured speeds through the drive's effective wheel radius and track
    width (`drive`: the robot's `config.scenario.Drive`), with the covariances of its
    `error_model` (`systems.odometry_error`; default the Corobot's with `drive`) after that
    travel; /ground_truth: the chassis
    pose in the world and its velocity in base_link; /odom: the first (or with
    `ground_truth`, the second, in odom)."""

    def __init__(self, bus, names: tp.RobotNames, chassis_index: int, drive,
                 period: float = STATE_PERIOD, ground_truth: bool = False,
                 wheel_joints: tuple[str, ...] | None = None, error_model=None):
        """`wheel_joints`: the robot's wheels' joint names (the Corobot's by default)."""
        from corobot_drake.robots import robot_spec
        from corobot_drake.systems.odometry_error import error_model as model_of

        super().__init__(chassis_index, wheel_joints)
        self._error = error_model or model_of(robot_spec("corobot"), drive)
        self._m = Messages(bus.store)
        self._odom, self._base = names.frame(ODOM_FRAME), names.base_frame()
        self._radius, self._track = drive.effective_wheel_radius, drive.effective_track_width
        self._ground_truth = ground_truth
        self._odometry = self.DeclareVectorInputPort("odometry", 3)
        self._travel = self.DeclareVectorInputPort("travel", 2)
        self._joint_names = list(self.wheel_joints)
        self._channels = {name: _channel(bus, names, ifc.TOPIC[name]) for name in (
            "odom", "wheel_odom", "ground_truth", "joint_states", "drive_state")}
        self.DeclarePeriodicPublishEvent(period, 0.0, self._publish)

    def _publish(self, context):
        """Each topic someone watches (`bus.Channel.watched`: a bag, or a subscriber)."""
        t = context.get_time()
        ns, m, c = tp.nanoseconds(t), self._m, self._channels
        watched = {name for name, channel in c.items() if channel.watched()}
        if "joint_states" in watched:
            angles, rates = self.wheel_state(context)
            c["joint_states"].publish(ns, m.joint_state(t, self._joint_names, angles, rates))
        if watched & {"ground_truth", "odom"}:
            X_WB, linear, angular = self.chassis(context)
        if "ground_truth" in watched:
            c["ground_truth"].publish(ns, m.odometry(t, WORLD_FRAME, self._base, X_WB, linear,
                                                     angular))
        if watched & {"odom", "wheel_odom"}:
            wheel = self.wheel_odometry(context)
        if "odom" in watched:
            c["odom"].publish(ns, m.odometry(t, self._odom, self._base, X_WB, linear, angular)
                              if self._ground_truth else wheel)
        if "wheel_odom" in watched:
            c["wheel_odom"].publish(ns, wheel)
        if "drive_state" in watched:
            c["drive_state"].publish(ns, m.drive_state(t, self._odom, self.drive_state(context)))

    def wheel_odometry(self, context):
        """The dead reckoning as nav_msgs/Odometry, with its error model's covariances."""
        t = context.get_time()
        x, y, yaw = self._odometry.Eval(context)
        left, right = self.wheel_state(context)[1][:2]  # front axles
        forward = 0.5 * self._radius * (left + right)
        yaw_rate = self._radius * (right - left) / self._track
        variances = (self._error.pose_variances(*self._travel.Eval(context)),
                     self._error.twist_variances())
        return self._m.odometry(t, self._odom, self._base, _planar((x, y, yaw)),
                                (forward, 0.0, 0.0), (0.0, 0.0, yaw_rate), variances)


def _planar(pose) -> RigidTransform:
    """X_OB of a planar pose (x, y m, yaw rad): base_link on the ground, level."""
    from pydrake.math import RotationMatrix

    x, y, yaw = pose
    return RigidTransform(RotationMatrix.MakeZRotation(float(yaw)), [float(x), float(y), 0.0])


class TelemetryPublisher(LeafSystem):
    """One robot's signals with a message of their own (`recording.topics.TELEMETRY_TOPICS`:
    the contact telemetry, /wheel_loads, /wheel_slip, /tip_margin) as corobot_interfaces
    messages.

    .. pydrake_system::

        name: TelemetryPublisher
        input_ports:
        - wheel_loads
        - wheel_slip_ratio
        - wheel_slip_angle
        - tip_margin

    Inputs and schedule as `recording.publishers.TelemetryPublisher`'s: the costly topics'
    ports held (sampled every `costly_period` s, published a period later with their sample's
    time), the others' looked at every `period` s."""

    def __init__(self, bus, names: tp.RobotNames, period: float = STATE_PERIOD,
                 costly_period: float = TELEMETRY_PERIOD, topics: tuple | None = None):
        """`topics`: the robot's (`topics.telemetry_topics`; default the Corobot's)."""
        super().__init__()
        m, frame = Messages(bus.store), names.base_frame()
        for topic in topics or tp.TELEMETRY_TOPICS:
            ports = [self.DeclareVectorInputPort(s.port, s.size) for s in topic.signals]
            spec = ifc.TOPIC[topic.name]
            channel = _channel(bus, names, spec)
            age = costly_period if topic.costly else 0.0

            def publish(context, topic=topic, ports=ports, channel=channel, age=age,
                        msgtype=spec.type):
                t = context.get_time() - age
                if t < -TOLERANCE or not channel.watched():
                    return  # nothing sampled yet, or nobody to see it
                channel.publish(tp.nanoseconds(t), m.telemetry(
                    msgtype, topic, t, frame, [port.Eval(context) for port in ports]))

            self.DeclarePeriodicPublishEvent(costly_period if topic.costly else period, 0.0,
                                             publish)


class RosSensorSink:
    """A sensor's ROS 2 topics (its kind's `ros2_channels`, under the robot's namespace) on a
    bus, and what a `recording.looks.SensorPublisher` hands them: each new reading's messages
    (`ros2_message`, in the sensor's frame), at the reading's time."""

    def __init__(self, bus, names: tp.RobotNames, sensor):
        self._m = Messages(bus.store)
        self._kind, self._frame = sensor.kind, names.frame(sensor.kind.frame_name(sensor.name))
        topic = self._kind.topic_name(sensor.name)
        self._channels = {
            sub: bus.channel(names.topic(f"{topic}/{sub}" if sub else topic), msgtype,
                             ifc.Qos(qos))
            for sub, (msgtype, qos) in self._kind.ros2_channels().items()}

    def watched(self) -> bool:
        """Whether any of its topics reaches anyone (`bus.Channel.watched`): else the
        `SensorPublisher` neither makes the reading nor hands it on (a camera nobody watches
        renders nothing for ROS 2)."""
        return any(channel.watched() for channel in self._channels.values())

    def __call__(self, reading) -> None:
        messages = self._kind.ros2_message(self._m, reading, self._frame)
        if messages is None:
            return
        if list(self._channels) == [""]:  # one topic: the message itself
            messages = {"": messages}
        ns = tp.nanoseconds(self._kind.reading_time(reading))
        for sub, message in messages.items():
            self._channels[sub].publish(ns, message)


# --- wiring -------------------------------------------------------------------------------


def add_ros2_topics(bus, builder, plant, scene_graph, robots: dict, scenario,
                    settings=None) -> None:
    """Adds the publishers of every topic (`interfaces.TOPICS`) for a station's plant and
    robots ({name: station.RobotParts}, built from `scenario`), on `bus`; `settings`: the
    node's read-only parameters (`parameters.Settings`; default: their defaults). Each
    robot's names are `topics.robot_names`' (of the robots the bus's first simulation had:
    a robot spawned later is under its name, the first ones keep theirs); a topic the
    simulation this one replaces had and this one has not is forgotten (`Bus.building`)."""
    with bus.building(robots):
        _add_ros2_topics(bus, builder, plant, robots, scenario, settings)


def _add_ros2_topics(bus, builder, plant, robots: dict, scenario, settings) -> None:
    from corobot_drake.robots import robot_spec
    from corobot_drake.ros2.parameters import Settings
    from corobot_drake.ros2.urdf import robot_urdf
    from corobot_drake.systems.odometry_error import error_model

    ground_truth = (settings or Settings()).odom_source == "ground_truth"
    mounts, descriptions, tf_robots, odometries = [], {}, [], []
    builder.AddNamedSystem("ros2_clock", ClockPublisher(bus))
    for name, parts in robots.items():
        names = tp.robot_names(name, bus.first_robots, parts.chassis.name())
        robot = robot_spec(scenario.robots[name].robot)
        state = builder.AddNamedSystem(f"{name}.ros2_state", RobotStatePublisher(
            bus, names, parts.chassis.index(), scenario.robots[name].drive,
            ground_truth=ground_truth, wheel_joints=tuple(j.name() for j in parts.wheel_joints),
            error_model=error_model(robot, scenario.robots[name].drive)))
        RobotStateLooks.connect(builder, plant, name, state)
        dead_reckoning = builder.GetSubsystemByName(f"{name}.dead_reckoning")
        odometry = dead_reckoning.GetOutputPort("pose")
        builder.Connect(odometry, state.GetInputPort("odometry"))
        builder.Connect(dead_reckoning.GetOutputPort("travel"), state.GetInputPort("travel"))
        odometries.append((name, odometry))
        _add_telemetry(builder, bus, names, tp.telemetry_topics(robot))
        tf_robots.append((names, parts.chassis.index(),
                          [(j.child_body().index(), names.body_frame(j.child_body().name()))
                           for j in parts.wheel_joints]))
        mounts += _robot_mounts(builder, bus, plant, names, parts)
        if len(robots) > 1:  # one tree: every robot's odom is the world's origin
            mounts.append((WORLD_FRAME, names.frame(ODOM_FRAME), RigidTransform()))
        descriptions[names] = robot_urdf(robot, name)
    tf = builder.AddNamedSystem("ros2_tf", TransformPublisher(bus, tf_robots,
                                                              ground_truth=ground_truth))
    builder.Connect(plant.get_body_poses_output_port(), tf.GetInputPort("body_poses"))
    for name, odometry in odometries if not ground_truth else ():
        builder.Connect(odometry, tf.GetInputPort(f"{name}_odometry"))
    builder.AddNamedSystem("ros2_static", StaticPublisher(bus, mounts, descriptions))


def _robot_mounts(builder, bus, plant, names, parts) -> list:
    """Adds a publisher of each of the robot's sensors whose kind has ROS 2 topics
    (`<robot>.ros2_<kind topic>.<sensor>`); returns every sensor's frames' fixed mounts (its
    kind's `ros2_frames`, the first at the sensor's mount)."""
    mounts = []
    for sensors in parts.sensors.values():
        for sensor in sensors.values():
            kind = sensor.kind
            if kind.ros2_channels():
                publisher = builder.AddNamedSystem(
                    f"{names.robot}.ros2_{kind.topic}.{sensor.name}",
                    SensorPublisher(sensor, RosSensorSink(bus, names, sensor)))
                publisher.connect(builder)
            (first, X), *rest = kind.ros2_frames(sensor.name)
            parent, child, X_PS = _mount(plant, parts, names, names.frame(first), sensor.X_PB)
            mounts.append((parent, child, X_PS if X is None else X_PS @ X))
            for frame, X_CF in rest:
                mounts.append((child, names.frame(frame), X_CF))
                child = names.frame(frame)
    return mounts


def _mount(plant, parts, names: tp.RobotNames, child: str, X_PB) -> tuple:
    """(parent frame, child frame, X_PC) of a sensor mounted at `X_PB` on the robot."""
    body, X_BS = mount_frame(plant, parts.model_instance, X_PB)
    if body.index() == plant.world_body().index():
        return names.frame(ODOM_FRAME), child, X_BS
    return names.body_frame(body.name()), child, X_BS


def _add_telemetry(builder, bus, names: tp.RobotNames, topics: tuple) -> None:
    """Adds `<robot>.ros2_telemetry` of its `topics`, fed by the robot's signals' ports, the
    costly topics' through holds `<robot>.ros2_<port>` (`recording.looks.connect_signal_topics`)."""
    publisher = builder.AddNamedSystem(f"{names.robot}.ros2_telemetry",
                                       TelemetryPublisher(bus, names, topics=topics))
    connect_signal_topics(builder, names.robot, publisher, topics, "ros2_")
