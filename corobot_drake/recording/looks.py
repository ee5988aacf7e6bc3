"""What the publishers of the run's topics share, the recording's (`recording.publishers`,
Foxglove) and ROS 2's (`ros2.publishers`): when they look at the simulation, the robot state
they read (`RobotStateLooks`: its input ports and the chassis read), the camera frames and IR
scans they find (`CameraLooks`, `IrScanLooks`) and how the topics of signals with a message of
their own are fed (`connect_signal_topics`).

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
from pydrake.systems.framework import LeafSystem
from pydrake.systems.primitives import ZeroOrderHold
from pydrake.systems.sensors import ImageRgba8U

from corobot_drake.model import dimensions as dim
from corobot_drake.model.ir_models import SharpGP2D12
from corobot_drake.sensors.ir_sensor import SCAN_TIME, scan_state_layout
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
    index; the chassis is `chassis_index`), `wheel_state` (8: the four axles' angles, rad,
    then rates, rad/s, `dimensions.WHEEL_NAMES` order), `drive_state` (abstract
    `odometry.DriveState`). A subclass declares its publish events (and any further
    inputs)."""

    def __init__(self, chassis_index: int):
        super().__init__()
        self._chassis = int(chassis_index)
        self._poses = self.DeclareAbstractInputPort("body_poses",
                                                    AbstractValue.Make([RigidTransform()]))
        self._velocities = self.DeclareAbstractInputPort(
            "body_spatial_velocities", AbstractValue.Make([SpatialVelocity()]))
        self._wheels = self.DeclareVectorInputPort("wheel_state", 2 * len(dim.WHEEL_NAMES))
        self._drive = self.DeclareAbstractInputPort("drive_state", Value(object()))

    def chassis(self, context) -> tuple[RigidTransform, np.ndarray, np.ndarray]:
        """The chassis pose in the world X_WB, and its velocity in base_link (its own frame,
        as nav_msgs/Odometry's twist): linear (m/s) and angular (rad/s)."""
        X_WB = self._poses.Eval(context)[self._chassis]
        V_WB = self._velocities.Eval(context)[self._chassis]
        R_BW = X_WB.rotation().inverse()
        return X_WB, R_BW @ V_WB.translational(), R_BW @ V_WB.rotational()

    def wheel_state(self, context) -> tuple[np.ndarray, np.ndarray]:
        """The axles' angles (rad) and rates (rad/s), `dimensions.WHEEL_NAMES` order."""
        x = self._wheels.Eval(context)
        n = len(dim.WHEEL_NAMES)
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


class CameraLooks(LeafSystem):
    """The base of a camera's frame publishers: their input ports, and the frame each look
    finds.

    .. pydrake_system::

        name: CameraLooks
        input_ports:
        - rgb_image
        - image_time

    Inputs `rgb_image` (abstract ImageRgba8U, `width` x `height`) and `image_time` (1, s: its
    capture; NaN before the first), the camera's outputs. It looks every `look` s and hands
    a frame that came out (capture + `delay`) since the previous look to the subclass's
    `publish_frame(context, captured, image)`, as `camera.CameraFrameSaver` saves one."""

    def __init__(self, width: int, height: int, look: float, delay: float):
        super().__init__()
        self._look, self._delay = float(look), float(delay)
        self._image = self.DeclareAbstractInputPort(
            "rgb_image", AbstractValue.Make(ImageRgba8U(width, height)))
        self._image_time = self.DeclareVectorInputPort("image_time", 1)
        self.DeclarePeriodicPublishEvent(self._look, 0.0, self._find_frame)

    def _find_frame(self, context):
        captured = float(self._image_time.Eval(context)[0])
        if in_window(captured + self._delay, context.get_time(), self._look):  # False: NaN
            self.publish_frame(context, captured, self._image.Eval(context))

    def publish_frame(self, context, captured: float, image: ImageRgba8U) -> None:
        """Publishes the frame captured at `captured` (s)."""
        raise NotImplementedError


class IrScanLooks(LeafSystem):
    """The base of an IR sensor's scan publishers: its input port, the sensor's limits, and
    the scan each look finds.

    .. pydrake_system::

        name: IrScanLooks
        input_ports:
        - scan_state

    Input `scan_state` (the `IrSensor`'s, `ir_sensor.scan_state_layout`). It looks on the
    sensor's own event schedule (`IrSensor.events`: a look and a scan at one time are at the
    same float time, the look first; a look scheduled apart could fall an ulp after a scan
    and miss the scan before it) and hands the scan taken since the previous look to the
    subclass's `publish_scan(context, when, scan)`. `fov_deg`, `min_range` and `max_range`
    (m) are the sensor's cone and the distances it can read."""

    def __init__(self, sensor_system):
        super().__init__()
        config = sensor_system.config
        self._period = sensor_system.events[0]
        self.fov_deg = config.dispersion_cone_angle
        self.min_range = SharpGP2D12.min_distance if config.model == "sharp_gp2d12" else 0.0
        self.max_range = config.maximum_range
        self._scan = self.DeclareVectorInputPort(
            "scan_state", scan_state_layout(sensor_system.num_rays)[0])
        self.DeclarePeriodicPublishEvent(*sensor_system.events, self._find_scan)

    def _find_scan(self, context):
        scan = self._scan.Eval(context)
        when = float(scan[SCAN_TIME])
        if in_window(when, context.get_time(), self._period):  # False: NaN, no scan yet
            self.publish_scan(context, when, scan)

    def publish_scan(self, context, when: float, scan) -> None:
        """Publishes `scan` (the sensor's scan state) taken at `when` (s)."""
        raise NotImplementedError


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
