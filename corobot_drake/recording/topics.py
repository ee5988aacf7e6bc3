"""The run's Foxglove topics and their messages, in ROS's conventions (`corobot_drake.topics`
names the topics and frames).

Foxglove's well-known schemas (`foxglove.messages`, protobuf) where one fits, JSON with a JSON
schema where none does. With one robot the topics and frames are bare (`/odom`, `base_link`),
as a ROS robot's; with several, each robot's are under its name (`/<robot>/odom`,
`<robot>/base_link`), as ROS namespaces and tf prefixes put them.

| topic | schema | what |
|---|---|---|
| `/tf` | foxglove.FrameTransforms | world -> base_link, world bodies; base_link -> links, sensors |
| `/scene` | foxglove.SceneUpdate | the bodies' shapes, locked to their frames |
| `/joint_states` | foxglove.JointStates | the four wheel axles: angle (rad), rate (rad/s) |
| `/odom` | foxglove.Odometry | the chassis in the world; velocity in base_link (ground truth) |
| `/drive_state` | corobot.DriveState (JSON) | enabled, power, axle speed, encoder ticks per wheel |
| `/ir/<sensor>` | corobot.Range (JSON) | each scan, sensor_msgs/Range's fields |
| `/ir/<sensor>/rays` | foxglove.SceneUpdate | each scan's rays, in the world |
| `/camera/image/compressed` | foxglove.CompressedImage | each frame, JPEG |
| `/camera/camera_info` | foxglove.CameraCalibration | with each frame |
| `/camera/<camera>/...` | (the same two) | another camera than `front` |
| `/commands` | foxglove.Log | each command issued and how it ended |
| `/wheel_loads` | corobot.WheelLoads (JSON) | each wheel's load (N) |
| `/wheel_slip` | corobot.WheelSlip (JSON) | each wheel's slip ratio and slip angle (deg) |
| `/tip_margin` | corobot.TipMargin (JSON) | the tip-over margin (deg) |

Frames: `world` (z up); `base_link`, the chassis frame (on the ground midway between the axles,
+x forward, +z up: ROS's base_footprint, REP 103's axes); `<wheel>_wheel` (the wheel links);
`camera_optical_frame` (Drake's camera frame: +z forward, +x right, +y down, ROS's optical
frame; another camera's `camera_<camera>_optical_frame`); `ir_<sensor>` (+x along the beam, as
sensor_msgs/Range's frame). Times are simulation time (a run starts at 1970-01-01 00:00:00,
as a ROS simulation's /clock starts at 0).
"""

import math

import numpy as np
from foxglove import Channel
from foxglove.messages import (
    Color,
    FrameTransform,
    LinePrimitive,
    LinePrimitiveLineType,
    Point3,
    Pose,
    Quaternion,
    Timestamp,
    Vector3,
)
from pydrake.math import RigidTransform

from corobot_drake.topics import INFRARED, nanoseconds


def json_channel(topic: str, schema: dict, context) -> Channel:
    """A JSON channel whose messages follow `schema` (a JSON schema with a `title`)."""
    return Channel(topic, schema=schema, context=context)


def stamp(t: float) -> Timestamp:
    ns = nanoseconds(t)
    return Timestamp(ns // 1_000_000_000, ns % 1_000_000_000)


def pose_of(X: RigidTransform) -> Pose:
    return Pose(position=vector3(X.translation()), orientation=quaternion(X))


def vector3(v) -> Vector3:
    return Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def point3(v) -> Point3:
    return Point3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def quaternion(X: RigidTransform) -> Quaternion:
    q = X.rotation().ToQuaternion()
    return Quaternion(x=float(q.x()), y=float(q.y()), z=float(q.z()), w=float(q.w()))


def frame_transform(t: float, parent: str, child: str, X_PC: RigidTransform) -> FrameTransform:
    """`child`'s pose in `parent` at time `t` (s)."""
    return FrameTransform(timestamp=stamp(t), parent_frame_id=parent, child_frame_id=child,
                          translation=vector3(X_PC.translation()), rotation=quaternion(X_PC))


def color(rgba) -> Color:
    r, g, b, a = (float(c) for c in rgba)
    return Color(r=r, g=g, b=b, a=a)


RAY_HIT_COLOR = (1.0, 0.2, 0.1, 1.0)
RAY_MISS_COLOR = (0.3, 0.8, 0.3, 0.6)
"""The IR rays drawn in Foxglove: red where a ray hit something, green where it ran out."""


def ray_lines(origin, ends: np.ndarray, hits: np.ndarray) -> LinePrimitive:
    """The rays of one IR scan as a line list in the world frame: origin (3) to each end
    (N x 3, m), coloured by whether it hit (N, 0 or 1)."""
    points, colors = [], []
    o = point3(origin)
    for end, hit in zip(ends, hits, strict=True):
        c = color(RAY_HIT_COLOR if hit > 0.5 else RAY_MISS_COLOR)
        points += [o, point3(end)]
        colors += [c, c]
    return LinePrimitive(type=LinePrimitiveLineType.LineList, thickness=2.0,
                         scale_invariant=True, points=points, colors=colors)


RANGE_SCHEMA = {
    "title": "corobot.Range",
    "description": "One IR scan, with ROS sensor_msgs/Range's fields (metres, radians).",
    "type": "object",
    "properties": {
        "timestamp": {"type": "object", "properties": {
            "sec": {"type": "integer"}, "nsec": {"type": "integer"}}},
        "frame_id": {"type": "string"},
        "radiation_type": {"type": "integer", "description": "1: INFRARED"},
        "field_of_view": {"type": "number", "description": "rad, the cone's full angle"},
        "min_range": {"type": "number"},
        "max_range": {"type": "number"},
        "range": {"type": "number", "description": "the reading (m); max_range: nothing"},
        "true_range": {"type": "number", "description": "the geometric nearest hit (m)"},
    },
}


def range_message(t: float, frame_id: str, field_of_view_deg: float, min_range: float,
                  max_range: float, reading: float, true_range: float) -> dict:
    """One IR scan as `RANGE_SCHEMA` (JSON)."""
    ts = stamp(t)
    return {"timestamp": {"sec": ts.sec, "nsec": ts.nsec}, "frame_id": frame_id,
            "radiation_type": INFRARED, "field_of_view": math.radians(field_of_view_deg),
            "min_range": min_range, "max_range": max_range, "range": float(reading),
            "true_range": float(true_range)}


DRIVE_STATE_SCHEMA = {
    "title": "corobot.DriveState",
    "description": "The drive state (MRDS's, in SI units): systems.odometry.DriveState.",
    "type": "object",
    "properties": {
        "timestamp": {"type": "object", "properties": {
            "sec": {"type": "integer"}, "nsec": {"type": "integer"}}},
        "is_enabled": {"type": "boolean"},
        "distance_between_wheels": {"type": "number", "description": "m"},
        "power_scaling_factor": {"type": "number", "description": "axle rad/s at power 1"},
        "wheels": {"type": "object", "additionalProperties": {
            "type": "object", "properties": {
                "commanded_power": {"type": "number", "description": "[-1, 1]"},
                "axle_speed": {"type": "number", "description": "rad/s"},
                "encoder_ticks": {"type": ["integer", "null"]}}}},
        "position": {"type": "array", "items": {"type": "number"}, "description": "m"},
        "heading": {"type": "number", "description": "rad"},
    },
}


def drive_state_message(state) -> dict:
    """A `systems.odometry.DriveState` as `DRIVE_STATE_SCHEMA` (JSON). (Field by field:
    `dataclasses.asdict` deep-copies, ten times the cost at 50 Hz.)"""
    ts = stamp(state.time_stamp)
    return {"timestamp": {"sec": ts.sec, "nsec": ts.nsec}, "is_enabled": state.is_enabled,
            "distance_between_wheels": state.distance_between_wheels,
            "power_scaling_factor": state.power_scaling_factor,
            "wheels": {name: {"commanded_power": w.commanded_power, "axle_speed": w.axle_speed,
                              "encoder_ticks": w.encoder_ticks}
                       for name, w in state.wheels.items()},
            "position": list(state.position), "heading": state.heading}


def command_event(record, ended: bool) -> str:
    """A command log record's line: `seq 3 DriveDistance started`, `... succeeded`,
    `... failed (stalled)`."""
    what = f"seq {record.seq} {record.command}" if record.seq else record.command
    if not ended:
        return f"{what} started"
    return f"{what} {record.status}" + (f" ({record.reason})" if record.reason else "")
