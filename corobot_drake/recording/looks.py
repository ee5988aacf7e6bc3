"""What the publishers of the run's topics share, the recording's (`recording.publishers`,
Foxglove) and ROS 2's (`ros2.publishers`): when they look at the simulation, the robot state
they read (`RobotStateLooks`: its input ports and the chassis read), the one publisher of every
sensor's readings, whatever its kind (`SensorPublisher`, handing them to a wire's sink), and
how the topics of signals with a message of their own are fed (`connect_signal_topics`).

A publisher looks on periodic publish events from its input ports alone: what to publish at
time t is decided from the Context, so it keeps no memory and a reset or replayed Context
publishes the same messages. A publish event at t runs before the updates at t, so a look at t
sees what happened in [t - period, t).

No Foxglove or ROS import here.
"""

import numpy as np
from pydrake.common.value import AbstractValue, Value
from pydrake.math import RigidTransform
from pydrake.multibody.math import SpatialVelocity
from pydrake.systems.framework import LeafSystem, PortDataType
from pydrake.systems.primitives import ZeroOrderHold

from corobot_drake.robots import corobot
from corobot_drake.systems.runlog import HELD_PERIOD

STATE_PERIOD = 0.02
"""s: the robot state topics (/tf, /joint_states, /odom, /drive_state, ...) are published at
50 Hz (a multiple of the plant steps used here, 1 to 10 ms, so the looks add no Simulator
stops)."""
TELEMETRY_PERIOD = HELD_PERIOD
"""s: the costly signals' topics (`signals.Signal.costly`: /wheel_loads, /wheel_slip) are
sampled at 10 Hz by holds of their own at the instants the run log samples them
(`runlog.HELD_PERIOD`: no Simulator stop of their own), and published a period later. On a
discrete plant they sample in the same discrete update as the run log's holds and share their
evaluation of the ports (one cache; on a continuous plant the run log makes its own when it is
read); a publish event could not: it runs before the updates at its time, whose new commands
change the contact results again, so each look would evaluate the plant's contact solution
once more."""
TOLERANCE = 1e-9
"""s: an event this close to a look counts as at it (float sums of periods)."""


def in_window(x: float, t: float, period: float) -> bool:
    """Whether an event at `x` (s) happened in [t - period, t): the look at t publishes it."""
    return t - period - TOLERANCE <= x < t - TOLERANCE


class RobotStateLooks(LeafSystem):
    """The base of a robot's state publishers: their input ports and the chassis read.

    .. pydrake_system::

        name: RobotStateLooks
        input_ports:
        - body_poses
        - body_spatial_velocities
        - wheel_state
        - drive_state

    Inputs: `body_poses` and `body_spatial_velocities` (the plant's, abstract lists by body
    index; the chassis is `chassis_index`), `wheel_state` (2 n: the n axles' angles, rad,
    then rates, rad/s, in the robot's wheel order, whose joints are `wheel_joints`; the
    Corobot's by default), `drive_state` (abstract `odometry.DriveState`). A subclass declares
    its publish events (and any further inputs)."""

    def __init__(self, chassis_index: int, wheel_joints: tuple[str, ...] | None = None):
        super().__init__()
        self._chassis = int(chassis_index)
        self.wheel_joints = tuple(wheel_joints or corobot.spec().wheel_joints)
        """The wheels' joint names, wheel order (/joint_states names them so)."""
        self._poses = self.DeclareAbstractInputPort("body_poses",
                                                    AbstractValue.Make([RigidTransform()]))
        self._velocities = self.DeclareAbstractInputPort(
            "body_spatial_velocities", AbstractValue.Make([SpatialVelocity()]))
        self._wheels = self.DeclareVectorInputPort("wheel_state", 2 * len(self.wheel_joints))
        self._drive = self.DeclareAbstractInputPort("drive_state", Value(object()))

    def chassis(self, context) -> tuple[RigidTransform, np.ndarray, np.ndarray]:
        """The chassis pose in the world X_WB, and its velocity in base_link (its own frame,
        as nav_msgs/Odometry's twist): linear (m/s) and angular (rad/s)."""
        X_WB = self._poses.Eval(context)[self._chassis]
        V_WB = self._velocities.Eval(context)[self._chassis]
        R_BW = X_WB.rotation().inverse()
        return X_WB, R_BW @ V_WB.translational(), R_BW @ V_WB.rotational()

    def wheel_state(self, context) -> tuple[np.ndarray, np.ndarray]:
        """The axles' angles (rad) and rates (rad/s), wheel order."""
        x = self._wheels.Eval(context)
        n = len(self.wheel_joints)
        return x[:n], x[n:]

    def drive_state(self, context):
        """The drive state (`odometry.DriveState`)."""
        return self._drive.Eval(context)

    @staticmethod
    def connect(builder, plant, robot: str, publisher) -> None:
        """Connects the robot's sources to a `publisher`'s (a `RobotStateLooks`) inputs."""
        for port, source in (
                ("body_poses", plant.get_body_poses_output_port()),
                ("body_spatial_velocities", plant.get_body_spatial_velocities_output_port()),
                ("wheel_state", builder.GetSubsystemByName(f"{robot}.wheel_state")
                 .get_output_port()),
                ("drive_state", builder.GetSubsystemByName(f"{robot}.drive_state")
                 .GetOutputPort("drive_state"))):
            builder.Connect(source, publisher.GetInputPort(port))


class SensorPublisher(LeafSystem):
    """One sensor's publisher on one wire: it looks for a new reading and hands it to
    `sink(reading)` (the wire's messages of it: `recording.publishers.FoxgloveSensorSink`,
    `ros2.publishers.RosSensorSink`), once, at the first look after it came out.

    .. pydrake_system::

        name: SensorPublisher
        input_ports:
        - <the kind's wire_ports> (e.g. reading)

    Everything comes from the sensor's kind (`sensors.kind.SensorKind`): its inputs are the
    ports the kind names (`wire_ports`: vector or abstract as they are), its looks are on
    the kind's schedule (`looks`), and a look at t hands on the reading (`wire_reading`,
    asked only then) that came out (`out_time`; NaN: none yet) in [t - period, t), if the
    sink wants it: a sink with `watched()` False (a live ROS 2 topic nobody subscribes to)
    is handed nothing, and the reading is not made (a camera's frame is not rendered for
    it)."""

    def __init__(self, sensor, sink):
        super().__init__()
        self._sensor, self._kind, self._sink = sensor, sensor.kind, sink
        self._watched = getattr(sink, "watched", lambda: True)
        self._kind.add_reader(sensor, self._watched)
        self._inputs = {}
        for name, port in self._kind.wire_ports(sensor).items():
            if port.get_data_type() == PortDataType.kVectorValued:
                self._inputs[name] = self.DeclareVectorInputPort(name, port.size())
            else:
                self._inputs[name] = self.DeclareAbstractInputPort(name, port.Allocate())
        self._period, offset = self._kind.looks(sensor)
        self.DeclarePeriodicPublishEvent(self._period, offset, self._look)

    def connect(self, builder) -> None:
        """Connects the sensor's ports (`wire_ports`) to this publisher's inputs."""
        for name, port in self._kind.wire_ports(self._sensor).items():
            builder.Connect(port, self._inputs[name])

    def _look(self, context):
        def inputs(name):
            return self._inputs[name].Eval(context)

        out = self._kind.out_time(self._sensor, inputs)
        if in_window(out, context.get_time(), self._period) and self._watched():  # (NaN: none)
            self._sink(self._kind.wire_reading(self._sensor, inputs))


def connect_signal_topics(builder, robot: str, publisher, topics, prefix: str) -> None:
    """Feeds `publisher`'s input port of each signal of `topics` (`topics.TELEMETRY_TOPICS`)
    from the robot's system that has it (`signals.Signal.system`), a costly topic's through a
    hold `<robot>.<prefix><port>` (`TELEMETRY_PERIOD`)."""
    for topic in topics:
        for spec in topic.signals:
            source = builder.GetSubsystemByName(f"{robot}.{spec.system}").GetOutputPort(
                spec.port)
            if topic.costly:
                hold = builder.AddNamedSystem(f"{robot}.{prefix}{spec.port}", ZeroOrderHold(
                    TELEMETRY_PERIOD, source.size()))
                builder.Connect(source, hold.get_input_port())
                source = hold.get_output_port()
            builder.Connect(source, publisher.GetInputPort(spec.port))
