"""What the robot says on ROS 2, in one table each: its topics (name, type, QoS), the commands
its actions and services issue, and the project's own message definitions.

Derived from the project's existing declarations rather than re-declared: the topics are the
Foxglove recording's (`recording.topics`: names, frames, the telemetry's fields) in ROS's
standard types; the actions' goals are the scenario commands' fields (`config.scenario`), issued
through the HTTP server's calls (`serving.calls`); corobot_interfaces' telemetry messages are
written from `recording.topics.TELEMETRY_TOPICS` (`telemetry_definition`), its actions from
the command table (`action_definition`; a test keeps the files in
`ros_packages/corobot_interfaces/` in step, and `python -m corobot_drake.ros2.interfaces`
rewrites them).

The commands' interfaces (`CMD_VEL`, `ACTIONS`, `SERVICES`, docs/ros2.md's rows:
`command_rows`) are the command table's ROS 2 column (`commands.Ros2`), not a list of
their own.

No ROS import here: the table is read by the bag writer too (no ROS at run time).
"""

from __future__ import annotations

import dataclasses as dc
import enum
import sys
from pathlib import Path

from corobot_drake import commands
from corobot_drake import topics as tp
from corobot_drake.robots import corobot

INTERFACES_DIR = Path(__file__).resolve().parent / "ros_packages"
PACKAGE = "corobot_interfaces"
NODE_NAME = "corobot_drake"


class Qos(enum.Enum):
    """The QoS a topic is offered with, as ROS users expect it."""

    SENSOR = "sensor"
    """A sensor stream, keep last 5: reliable by default (RViz's, image_view's and rqt's
    defaults subscribe reliable), best effort (rclpy's `qos_profile_sensor_data`) when the
    node's `sensor_qos` parameter says so (`offer`)."""
    RELIABLE = "reliable"
    """Reliable, volatile, keep last 10 (state: /tf, /odom, ...; a best-effort subscriber
    matches it too)."""
    LATCHED = "latched"
    """Reliable, transient local, keep last 1 (/tf_static, /robot_description: a late
    subscriber gets the one message)."""


@dc.dataclass(frozen=True)
class Offer:
    """What a topic's publisher offers, in ROS's terms (the node's rclpy profile and the bag's
    recorded one are made from this)."""

    reliable: bool
    transient_local: bool
    depth: int


def offer(qos: Qos, sensor_qos: str = "reliable") -> Offer:
    """The offer of a topic of `qos`; a sensor stream's reliability is `sensor_qos`'s (the
    node's parameter: `reliable` or `best_effort`)."""
    if qos is Qos.SENSOR:
        return Offer(sensor_qos == "reliable", False, 5)
    return Offer(True, qos is Qos.LATCHED, 1 if qos is Qos.LATCHED else 10)


@dc.dataclass(frozen=True)
class Topic:
    name: str
    """Under the robot's namespace (`recording.topics.RobotNames.topic`), except `shared`."""
    type: str
    """The ROS type, `package/msg/Name`."""
    qos: Qos
    what: str
    shared: bool = False
    """One for the whole simulation (/clock, /tf, /tf_static): not under a robot's name."""


def _telemetry_type(topic: tp.TelemetryTopic) -> str:
    return f"{PACKAGE}/msg/{topic.title.split('.')[-1]}"


TOPICS = (
    Topic("clock", "rosgraph_msgs/msg/Clock", Qos.RELIABLE,
          "simulation time, every 10 ms (use_sim_time)", shared=True),
    Topic("tf", "tf2_msgs/msg/TFMessage", Qos.RELIABLE,
          "odom -> base_link (as /odom), base_link -> the wheels, at 50 Hz", shared=True),
    Topic("tf_static", "tf2_msgs/msg/TFMessage", Qos.LATCHED,
          "each sensor's frames at its mount (its kind's `ros2_frames`)", shared=True),
    Topic("robot_description", "std_msgs/msg/String", Qos.LATCHED,
          "the robot's URDF (`ros2.urdf`: the Corobot's from its figures, another robot's "
          "from its own model), for RViz and robot_state_publisher"),
    Topic("odom", "nav_msgs/msg/Odometry", Qos.RELIABLE,
          "the wheel odometry (parameter odom_source: wheel, with its covariance) or the "
          "ground truth (ground_truth): pose in odom, twist in base_link, at 50 Hz"),
    Topic("wheel_odom", "nav_msgs/msg/Odometry", Qos.RELIABLE,
          "the encoders' dead reckoning, at 50 Hz, its covariances from the robot's odometry "
          "error model (`systems/odometry_error.py`: the encoders' quantization, the error its "
          "drive test leaves per metre driven and per radian turned, a radius or track other "
          "than the calibrated ones), growing with the distance and turning since the last "
          "reset; a teleport (set_pose) or a reset puts it at the true pose and its "
          "covariances back at the quantization's"),
    Topic("ground_truth", "nav_msgs/msg/Odometry", Qos.RELIABLE,
          "the simulation's true pose in world (odom's origin and axes), twist in base_link, "
          "at 50 Hz"),
    Topic("joint_states", "sensor_msgs/msg/JointState", Qos.RELIABLE,
          "the robot's wheel joints (the Corobot's four `<wheel>_axle`): angle (rad), rate "
          "(rad/s), at 50 Hz"),
    Topic("drive_state", f"{PACKAGE}/msg/DriveState", Qos.RELIABLE,
          "enabled, power, axle speed, encoder ticks per wheel, GPS and compass, at 50 Hz"),
    *(Topic(t.name, _telemetry_type(t), Qos.RELIABLE,
            t.description.split(":")[0].lower() + (" at 10 Hz" if t.costly else " at 50 Hz"))
      for t in tp.TELEMETRY_TOPICS),
)
"""Everything the node publishes but the sensors' topics (each sensor's kind says its own:
`sensors.kind.SensorKind.ros2_channels`)."""
TOPIC = {t.name: t for t in TOPICS}


def _ros2_commands(kind: str) -> list[commands.CommandSpec]:
    """The commands whose ROS 2 interface (the command table's `ros2` column) is a `kind`."""
    return [s for s in commands.COMMANDS.values() if s.ros2 is not None and s.ros2.kind == kind]


(_CMD_VEL,) = _ros2_commands("topic")
CMD_VEL = (_CMD_VEL.ros2.name.lstrip("/"), _CMD_VEL.ros2.type)
"""Subscribed: issued as `commands.SetVelocity` (linear.x m/s, angular.z rad/s)."""
DEADMAN_TIMEOUT = 0.5
"""s of simulated time without a Twist after which the robot stops (ROS parameter
`cmd_vel_timeout`; 0 turns the deadman off)."""


@dc.dataclass(frozen=True)
class Action:
    name: str
    type: str
    command: type
    """The scenario command its goal is: the goal's fields are the command's own."""
    call: str
    """`serving.calls.start_operation`'s name for it."""
    feedback: str
    """The feedback field: what is left of the command (`MotionCommands.remaining_command`)."""


ACTIONS = tuple(Action(s.ros2.name.lstrip("/"), s.ros2.type, s.dataclass, s.method,
                       s.ros2.feedback) for s in _ros2_commands("action"))
"""The command table's actions (`commands.Ros2`), each a completing command."""


def goal_fields(command: type) -> tuple[str, ...]:
    """The fields of a scenario command a user gives (not a saved scene's resume state)."""
    return tuple(f.name for f in dc.fields(command) if f.name not in ("start", "recent_progress"))


@dc.dataclass(frozen=True)
class Service:
    name: str
    type: str
    call: str
    """The `Robot` method (through `serving.calls`) it issues."""


SERVICES = tuple(Service(s.ros2.name.lstrip("/"), s.ros2.type, s.method)
                 for s in _ros2_commands("service"))
"""The command table's services (`commands.Ros2`): the node serves each by its type."""

def command_rows() -> list[str]:
    """docs/ros2.md's rows (name, type, QoS, what) of the command table's ROS 2 interfaces."""
    rows = []
    for spec in (s for s in commands.COMMANDS.values() if s.ros2 is not None):
        ros2 = spec.ros2
        what = ros2.what or spec.summary
        if ros2.kind == "action":
            goal = ", ".join(f"`{a.name}`" + (f" {a.unit}" if a.unit else "") for a in spec.args)
            unit = spec.args[0].unit
            what = (f"goal {goal}; feedback `{ros2.feedback}`{f' {unit}' if unit else ''}; "
                    "result `success`, `reason`")
        kind = "(subscribed)" if ros2.kind == "topic" else f"({ros2.kind})"
        qos = "reliable" if ros2.kind == "topic" else ""
        rows.append(f"| `{ros2.name}` {kind} | {ros2.type} | {qos} | {what} |")
    return rows


CANCELED = "canceled"
"""An action's result reason when its goal was cancelled (the robot was stopped)."""


# --- corobot_interfaces' telemetry messages, written from the recording's table ---

def telemetry_definition(topic: tp.TelemetryTopic) -> str:
    """The .msg text of one of `recording.topics.TELEMETRY_TOPICS`."""
    lines = [f"# {topic.description}", "std_msgs/Header header  # stamp: its sample's time"]
    array = "[]" if topic.per_wheel else ""
    if topic.per_wheel:
        lines.append("string[] wheel_names  # " + ", ".join(corobot.spec().wheel_names))
    lines += [f"float64{array} {field}  # {what}" for field, _, what in topic.fields]
    return "\n".join(lines) + "\n"


def telemetry_files() -> dict[Path, str]:
    """{path: text} of the telemetry .msg files."""
    return {INTERFACES_DIR / PACKAGE / "msg" / f"{_telemetry_type(t).split('/')[-1]}.msg":
            telemetry_definition(t) for t in tp.TELEMETRY_TOPICS}


def action_definition(action: Action) -> str:
    """The .action text of one of the command table's actions: the goal is the command's
    arguments (their ranges the command's), the result how it ended, the feedback what is
    left of it."""
    spec = commands.spec_of(action.command)
    lines = [f"# {spec.summary} (corobot_drake's {spec.name})."]
    for arg in spec.args:
        kind = "bool" if arg.type is bool else "float64"
        lines.append(f"{kind} {arg.name}  # {arg.doc}; {arg.range.text()}" if arg.range
                     else f"{kind} {arg.name}  # {arg.doc}")
    unit = spec.args[0].unit
    lines += ["---", "bool success",
              "string reason  # why it failed: stalled, disabled, superseded, canceled, ...",
              "---", f"float64 {action.feedback}  # {unit} still to go"]
    return "\n".join(lines) + "\n"


def action_files() -> dict[Path, str]:
    """{path: text} of the action files, written from the command table."""
    return {INTERFACES_DIR / PACKAGE / "action" / f"{a.type.split('/')[-1]}.action":
            action_definition(a) for a in ACTIONS}


def message_definitions() -> dict[str, str]:
    """{`package/msg/Name`: .msg text} of the messages built here (tf2_msgs and
    corobot_interfaces), for a type store that lacks them (`rosbags`); the messages of
    signals' own topics are written from the table (`telemetry_definition`), so a bag or the
    bus carries a new one before corobot_interfaces is rebuilt."""
    out = {}
    for package in ("tf2_msgs", PACKAGE):
        for path in sorted((INTERFACES_DIR / package / "msg").glob("*.msg")):
            out[f"{package}/msg/{path.stem}"] = path.read_text()
    out.update((_telemetry_type(t), telemetry_definition(t)) for t in tp.TELEMETRY_TOPICS)
    return out


if __name__ == "__main__":
    for path, text in {**telemetry_files(), **action_files()}.items():
        path.write_text(text)
        print(path, file=sys.stderr)
