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
| `/<topic>/<sensor>...` | the sensor's kind's | each reading (`SensorKind.foxglove_channels`) |
| `/commands` | foxglove.Log | each command issued and how it ended |
| `/wheel_loads` | corobot.WheelLoads (JSON) | each wheel's load (N) |
| `/wheel_slip` | corobot.WheelSlip (JSON) | each wheel's slip ratio and slip angle (deg) |
| `/tip_margin` | corobot.TipMargin (JSON) | the tip-over margin (deg) |

Frames: `world` (z up); `base_link`, the chassis frame (on the ground midway between the axles,
+x forward, +z up: ROS's base_footprint, REP 103's axes); `<wheel>_wheel` (the wheel links);
each sensor's frame (its kind's `frame_name`, at its mount on a link: its readings' frame).
Times are simulation time (a run starts at 1970-01-01 00:00:00,
as a ROS simulation's /clock starts at 0).
"""


from foxglove import Channel
from foxglove.messages import (
    Color,
    FrameTransform,
    Point3,
    Pose,
    Quaternion,
    Timestamp,
    Vector3,
)
from pydrake.math import RigidTransform

from corobot_drake.topics import nanoseconds


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
