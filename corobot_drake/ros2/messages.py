"""The robot's values as ROS 2 messages (`rosbags` type-store instances; `bus.typestore`), in
ROS's conventions: SI units, REP 103 axes, time stamps in simulation time (a run starts at
0 s, as a ROS simulation's /clock does).
"""

from __future__ import annotations

import numpy as np
from pydrake.math import RigidTransform, RotationMatrix

from corobot_drake import topics as tp
from corobot_drake.ros2.bus import typestore
from corobot_drake.signals import put_value

UNUSED_VARIANCE = 1e6
"""A covariance's diagonal for what a planar odometry does not measure (z, roll, pitch):
large, so a fusing filter (robot_localization) ignores it, as ROS drivers of wheeled bases do."""


def covariance(variances: tuple) -> np.ndarray:
    """A 6 x 6 row-major covariance (x, y, z, roll, pitch, yaw) from the planar variances
    (x m^2, y m^2, yaw rad^2), or (forward (m/s)^2, yaw rate (rad/s)^2) for a twist
    (`systems.odometry_error.OdometryErrorModel`'s)."""
    diag = ([variances[0], variances[1], UNUSED_VARIANCE, UNUSED_VARIANCE,
             UNUSED_VARIANCE, variances[2]] if len(variances) == 3 else
            [variances[0], UNUSED_VARIANCE, UNUSED_VARIANCE, UNUSED_VARIANCE,
             UNUSED_VARIANCE, variances[1]])
    return np.diag(diag).flatten()


class Messages:
    """Makes the messages; one per bus (its type store's classes looked up once)."""

    def __init__(self, store=None):
        self.T = (store or typestore()).types
        self._zero_covariance = np.zeros(36)

    def msg(self, name: str):
        """The class of `package/msg/Name`."""
        return self.T[name]

    def time(self, t: float):
        ns = tp.nanoseconds(t)
        return self.T["builtin_interfaces/msg/Time"](sec=ns // 1_000_000_000,
                                                     nanosec=ns % 1_000_000_000)

    def header(self, t: float, frame: str):
        return self.T["std_msgs/msg/Header"](stamp=self.time(t), frame_id=frame)

    def clock(self, t: float):
        return self.T["rosgraph_msgs/msg/Clock"](clock=self.time(t))

    def vector3(self, v):
        return self.T["geometry_msgs/msg/Vector3"](x=float(v[0]), y=float(v[1]), z=float(v[2]))

    def quaternion(self, R: RotationMatrix):
        q = R.ToQuaternion()
        return self.T["geometry_msgs/msg/Quaternion"](x=float(q.x()), y=float(q.y()),
                                                      z=float(q.z()), w=float(q.w()))

    def pose(self, X: RigidTransform):
        p = X.translation()
        return self.T["geometry_msgs/msg/Pose"](
            position=self.T["geometry_msgs/msg/Point"](x=float(p[0]), y=float(p[1]),
                                                       z=float(p[2])),
            orientation=self.quaternion(X.rotation()))

    def transform(self, t: float, parent: str, child: str, X_PC: RigidTransform):
        """geometry_msgs/TransformStamped: `child`'s pose in `parent` at `t` (s)."""
        return self.T["geometry_msgs/msg/TransformStamped"](
            header=self.header(t, parent), child_frame_id=child,
            transform=self.T["geometry_msgs/msg/Transform"](
                translation=self.vector3(X_PC.translation()),
                rotation=self.quaternion(X_PC.rotation())))

    def tf(self, transforms: list):
        return self.T["tf2_msgs/msg/TFMessage"](transforms=transforms)

    def odometry(self, t: float, frame: str, child: str, X: RigidTransform, linear, angular,
                 variances: tuple | None = None):
        """nav_msgs/Odometry: pose `X` in `frame`, twist (`linear` m/s, `angular` rad/s) in
        `child`; `variances` (an estimate's: (pose's, twist's), as `covariance` takes them)
        or none (ground truth: exact, all zero)."""
        T = self.T
        pose_cov, twist_cov = ((self._zero_covariance,) * 2 if variances is None else
                               (covariance(variances[0]), covariance(variances[1])))
        return T["nav_msgs/msg/Odometry"](
            header=self.header(t, frame), child_frame_id=child,
            pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=self.pose(X),
                                                           covariance=pose_cov),
            twist=T["geometry_msgs/msg/TwistWithCovariance"](
                twist=T["geometry_msgs/msg/Twist"](linear=self.vector3(linear),
                                                   angular=self.vector3(angular)),
                covariance=twist_cov))

    def joint_state(self, t: float, names: list[str], positions, velocities):
        return self.T["sensor_msgs/msg/JointState"](
            header=self.header(t, ""), name=names,
            position=np.asarray(positions, dtype=np.float64),
            velocity=np.asarray(velocities, dtype=np.float64),
            effort=np.zeros(0, dtype=np.float64))

    def string(self, text: str):
        return self.T["std_msgs/msg/String"](data=text)

    def drive_state(self, t: float, frame: str, state):
        """corobot_interfaces/DriveState of a `systems.odometry.DriveState`."""
        T = self.T
        wheels = [T["corobot_interfaces/msg/WheelState"](
            name=name, commanded_power=float(w.commanded_power), axle_speed=float(w.axle_speed),
            has_encoder=w.encoder_ticks is not None, encoder_ticks=int(w.encoder_ticks or 0))
            for name, w in state.wheels.items()]
        x, y, z = state.position
        return T["corobot_interfaces/msg/DriveState"](
            header=self.header(t, frame), is_enabled=bool(state.is_enabled),
            distance_between_wheels=float(state.distance_between_wheels),
            power_scaling_factor=float(state.power_scaling_factor), wheels=wheels,
            position=T["geometry_msgs/msg/Point"](x=float(x), y=float(y), z=float(z)),
            heading=float(state.heading))

    def telemetry(self, msgtype: str, topic: tp.TelemetryTopic, t: float, frame: str,
                  values: list):
        """One of corobot_interfaces' messages of signals' own (`interfaces.telemetry_definition`)
        from its signals' port values (each a vector: one per wheel, wheel order, or one per
        key)."""
        fields: dict = {}
        for spec, vector in zip(topic.signals, values, strict=True):
            if spec.per_wheel:
                fields[spec.field] = np.asarray(vector, dtype=np.float64).copy()
            else:
                put_value(fields, spec.own_place, spec.value_of(vector))
        if topic.per_wheel:
            fields["wheel_names"] = list(topic.signals[0].keys)  # the robot's wheels
        return self.T[msgtype](header=self.header(t, frame), **fields)
