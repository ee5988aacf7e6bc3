"""The robot's commands, one declaration each, which every front end reads.

Each command is a dataclass declared here with `@command(...)`: its fields are its arguments
(with their ranges, `limits`, and defaults); the decorator adds what the front ends need to
name it. From each declaration come:

- the scenario's YAML tag and script entry (`!SetPower {left: 0.5, right: 0.5}`: the class
  itself, `config.scenario.Command`), and the command log's name;
- the Python method (`Robot.set_power`, `Robot.command("set_power", ...)`) and its argument
  check (`check`: ValueError naming the range);
- the HTTP route `POST /robots/{robot}/drive/<method>` and its request schema
  (`serving.schemas.request_model`), 422 naming the range;
- the ROS 2 interface it maps to (`ros2`: a topic, service or action by name and type);
- whether it completes (runs until it ends succeeded or failed: a script waits for it, HTTP
  follows it as an operation, ROS 2 serves it as an action or a service that answers when
  it has ended).

    from corobot_drake.commands import COMMANDS
    for spec in COMMANDS.values():
        print(spec.name, spec.method, [(a.name, a.range.text()) for a in spec.args])

No Drake import here (the HTTP process reads it).
"""

import dataclasses as dc
import math
from typing import Any, Union

import numpy as np

from corobot_drake import limits as lim
from corobot_drake.limits import Range, bound_of, bounded


@dc.dataclass(frozen=True)
class Ros2:
    """The ROS 2 interface a command maps to (the names are the robot's, before any
    namespace)."""

    kind: str
    """`topic` (subscribed), `service` or `action`."""
    name: str
    """`/cmd_vel`, `/drive_distance`, ..."""
    type: str
    """The interface type, `geometry_msgs/msg/Twist`, ... An action's goal is the command's
    arguments, field for field; a std_srvs Trigger issues the command as it is, a SetBool
    with its one flag; `corobot_interfaces/srv/SetPose` is SetPose's own (yaw in rad)."""
    feedback: str = ""
    """An action's feedback field: what is left of the command, in its first argument's unit
    (`MotionCommands.remaining_command`)."""
    what: str = ""
    """What it does, for the interface tables (the command's summary when empty)."""


@dc.dataclass(frozen=True)
class Arg:
    """One argument of a command: a field of its dataclass that the front ends take."""

    name: str
    type: type
    """float or bool."""
    default: Any
    """The Python API's default (`dc.MISSING`: a required argument; a scenario's script
    defaults every field, to the dataclass' default)."""
    range: Range | None
    """The allowed values of a float (`limits`); None for a bool."""
    doc: str
    """What it is (without its range or unit, which `range` states)."""

    @property
    def required(self) -> bool:
        """Whether the Python API needs it (it has no default)."""
        return self.default is dc.MISSING

    @property
    def unit(self) -> str:
        """Its range's unit (`m`, `m/s`, ...; '' for a bool or a unitless number)."""
        return self.range.unit if self.range is not None else ""


@dc.dataclass(frozen=True)
class CommandSpec:
    """One command as every front end sees it."""

    name: str
    """The scenario's tag and the command log's name: `SetPower`."""
    dataclass: type
    """The command itself (a scenario's script holds these; `Robot.issue` takes them)."""
    method: str
    """The Python method and the HTTP route's last part: `set_power`."""
    summary: str
    """One line: what it does (the HTTP route's summary)."""
    args: tuple[Arg, ...]
    """What the Python API, HTTP and ROS 2 take, in order (a saved scene's extra fields, such
    as DriveDistance's `start`, are the scenario's only)."""
    completing: bool
    """Runs until it ends succeeded or failed (the script waits; HTTP follows an operation)."""
    issuable: bool
    """The Python API, HTTP and ROS 2 take it (Wait is a script's pause only)."""
    ros2: Ros2 | None
    """The ROS 2 interface it maps to; None: none (a side's power or rim speed)."""
    http_request: str
    """Its HTTP request schema's name in the OpenAPI document (published: stays as it is)."""
    http_defaults: dict[str, Any]
    """HTTP's defaults where they differ from the Python API's (`Arg.default`)."""


COMMANDS: dict[str, CommandSpec] = {}
"""Every command by scenario tag, in declaration order (the scenario's `Command` order)."""


def command(*, method: str, summary: str, docs: dict[str, str] | None = None,
            completing: bool = False, issuable: bool = True, ros2: Ros2 | None = None,
            http_request: str = "", http_defaults: dict | None = None,
            optional: tuple[str, ...] = (), scenario_only: tuple[str, ...] = ()):
    """Declares a command: makes the class a dataclass and enters it in `COMMANDS`. `docs`:
    each argument's description; `optional`: the arguments the Python API and HTTP may leave
    out (then their dataclass default; the others are required); `scenario_only`: fields only
    a scenario (a saved scene) gives, not arguments of the other front ends."""

    def declare(cls):
        cls = dc.dataclass(cls)
        args = tuple(Arg(f.name, _field_type(f),
                         f.default if f.name in optional else dc.MISSING, _range(f),
                         (docs or {}).get(f.name, ""))
                     for f in dc.fields(cls) if f.name not in scenario_only)
        COMMANDS[cls.__name__] = CommandSpec(
            cls.__name__, cls, method, summary, args, completing, issuable, ros2,
            http_request or f"{cls.__name__}Request", dict(http_defaults or {}))
        return cls

    return declare


def _field_type(field: dc.Field) -> type:
    if field.type not in (float, bool):
        raise TypeError(f"a command's argument is a float or a bool, not {field.type!r}")
    return field.type


def _range(field: dc.Field) -> Range | None:
    bound = bound_of(field)
    return bound if isinstance(bound, Range) else None


# --- the commands -----------------------------------------------------------------------------

CMD_VEL = Ros2("topic", "/cmd_vel", "geometry_msgs/msg/Twist", what=(
    "issued as SetVelocity (`linear.x` m/s, `angular.z` rad/s); TwistStamped with the node's "
    "parameter `cmd_vel_stamped`, a publisher of the other type reported once in the log; "
    "the robot stops when none has come for 0.5 s (parameter `cmd_vel_timeout`, 0: never)"))


@command(method="set_power", summary="Power per side in [-1, 1]", http_request="PowerRequest",
         docs={"left": "power", "right": "power"})
class SetPower:
    """Wheel power per side in [-1, 1] (clamped): axle speed = power x MotorTorqueScaling."""

    left: float = bounded(0.0, lim.SIDE_POWER)
    right: float = bounded(0.0, lim.SIDE_POWER)


@command(method="set_speed", summary="Rim speed per side, m/s", http_request="SpeedRequest",
         docs={"left": "rim speed", "right": "rim speed"})
class SetSpeed:
    """Rim speed per side in m/s (axle speed = v / R, clamped to the max axle speed)."""

    left: float = bounded(0.0, lim.SIDE_SPEED)
    right: float = bounded(0.0, lim.SIDE_SPEED)


@command(method="set_velocity", ros2=CMD_VEL, http_request="VelocityRequest",
         summary="Chassis velocity (cmd_vel): linear m/s, angular rad/s (positive left)",
         docs={"linear": "forward (the drive clamps the axle speed)",
               "angular": "yaw rate, positive turns left"})
class SetVelocity:
    """The chassis' velocity, ROS `cmd_vel` style: `linear` forward speed (m/s, +x of the
    chassis) and `angular` yaw rate (rad/s, positive turns left), turned into rim speeds per
    side by the skid-steer kinematics (`systems.drive.skid_steer_rim_speeds`), then clamped like
    `SetSpeed` (keeping the ratio of the sides, so the path's curvature)."""

    linear: float = bounded(0.0, lim.LINEAR_SPEED)
    angular: float = bounded(0.0, lim.YAW_RATE)


@command(method="all_stop", summary="Both sides to zero speed", http_request="EmptyRequest",
         ros2=Ros2("service", "/all_stop", "std_srvs/srv/Trigger"))
class AllStop:
    """Command both sides to zero speed."""


@command(method="enable", summary="Enable or disable the drive", http_request="EnableRequest",
         optional=("enabled",),
         ros2=Ros2("service", "/enable_drive", "std_srvs/srv/SetBool"),
         docs={"enabled": "true: enabled; false: disabled"})
class Enable:
    """Enable or disable the drive (disabled: wheels held at zero speed, motion ignored)."""

    enabled: bool = True


@command(method="wait", summary="Let the previous command run this long", issuable=False,
         optional=("seconds",),
         docs={"seconds": "how long the previous command runs on before the next is issued"})
class Wait:
    """Let the previous command run for this long (s) before the next one. 0 s: the next one
    is issued at the next control update (not with the commands before it when the
    simulation starts: what a saved scene writes before a script's rest that is due), and
    the log records no Wait."""

    seconds: float = bounded(1.0, lim.DURATION)


COMPLETING_POWER_OVER_HTTP = 0.2
"""HTTP's default power of a completing command (the Python API's: its dataclass default)."""


@command(method="drive_distance", completing=True, scenario_only=("start", "recent_progress"),
         summary="Drive straight |distance| m (negative: backwards); completes",
         ros2=Ros2("action", "/drive_distance", "corobot_interfaces/action/DriveDistance",
                   feedback="remaining"),
         docs={"distance": "negative: backwards", "power": "power"},
         optional=("power",), http_defaults={"power": COMPLETING_POWER_OVER_HTTP})
class DriveDistance:
    """Drive straight until |distance| m from the start pose (negative: backwards), at
    `power` in (0, 1]; ends succeeded on arrival."""

    distance: float = bounded(0.0, lim.DISTANCE)
    power: float = bounded(0.5, lim.DRIVE_POWER)
    start: list[float] = bounded(list, lim.START_POSE)
    """[x, y, yaw_deg] (m, m, deg): the pose the distance counts from (and, closed loop, the
    heading held); empty: where the robot is when the command starts. A saved scene resumes
    a running drive so (`Simulation.saved_scenario`)."""
    recent_progress: list[float] = bounded(list, lim.POSITION)
    """m from `start` at the drive's last control updates, oldest first (the seed profile's
    last 0.1 s, the closed loop's last update); only a saved scene writes it (it needs
    `start`). Given, the drive carries on from its last update: its speed estimates go on
    from these as the uninterrupted drive's would. Empty: none (a command written by hand)."""


@command(method="rotate_degrees", completing=True, scenario_only=("start", "recent_progress"),
         summary="Turn in place (positive: left, counter-clockwise); completes",
         ros2=Ros2("action", "/rotate_degrees", "corobot_interfaces/action/RotateDegrees",
                   feedback="remaining_degrees"),
         docs={"degrees": "positive turns left (CCW)", "power": "power"},
         optional=("power",), http_defaults={"power": COMPLETING_POWER_OVER_HTTP})
class RotateDegrees:
    """Turn in place by `degrees` (positive: counter-clockwise seen from above, i.e. left),
    at `power` in (0, 1]; ends succeeded on arrival."""

    degrees: float = bounded(0.0, lim.DEGREES)
    power: float = bounded(0.5, lim.DRIVE_POWER)
    start: list[float] = bounded(list, lim.START_POSE)
    """[x, y, yaw_deg] (m, m, deg): the heading the turn counts from, as if read at the
    control update before it starts (within +-180 deg of the heading then; x and y are not
    used); empty: the heading when the command starts. A saved scene resumes a running turn
    so (`Simulation.saved_scenario`), from the heading at its last update."""
    recent_progress: list[float] = bounded(list, lim.ANGLE)
    """deg turned from `start`'s heading at the turn's last control updates, oldest first
    (the seed profile's last 0.1 s; a saved scene's last is 0); only a saved scene writes it
    (it needs `start`). Given, the seed profile's time-left estimate goes on from these as
    the uninterrupted turn's would. Empty: none (a command written by hand)."""


@command(method="set_pose", completing=True,
         summary="Teleport the robot to (x, y, yaw) on the ground; completes when settled",
         ros2=Ros2("service", "/set_pose", "corobot_interfaces/srv/SetPose", what=(
             "teleport to `x`, `y` (m), `yaw` (rad); answers once settled, or `blocked`")),
         optional=("yaw_deg",), docs={"x": "world x", "y": "world y", "yaw_deg": "heading"})
class SetPose:
    """Teleport the robot to (x, y) m facing `yaw_deg`: on the ground, at rest, wheels stopped."""

    x: float = bounded(0.0, lim.POSITION)
    y: float = bounded(0.0, lim.POSITION)
    yaw_deg: float = bounded(0.0, lim.YAW_DEG)


# --- what the front ends read -----------------------------------------------------------------

Command = Union[tuple(spec.dataclass for spec in COMMANDS.values())]  # noqa: UP007
"""A scenario script's entry: any command (typing.Union: the YAML tags are its members')."""
COMPLETING_COMMANDS = tuple(s.dataclass for s in COMMANDS.values() if s.completing)
"""Commands that run until they end (succeeded or failed); the script waits for each."""
ISSUABLE = tuple(s for s in COMMANDS.values() if s.issuable)
"""The commands the Python API, HTTP and ROS 2 take, in declaration order."""
BY_METHOD = {s.method: s for s in ISSUABLE}
"""The issuable commands by Python method / HTTP route name."""


def spec_of(command) -> CommandSpec:
    """The declaration of a command (an instance or its class); ValueError for anything else."""
    cls = command if isinstance(command, type) else type(command)
    spec = COMMANDS.get(cls.__name__)
    if spec is None or spec.dataclass is not cls:
        raise ValueError(f"a command must be one of {', '.join(COMMANDS)}; got {command!r}")
    return spec


def by_method(method: str) -> CommandSpec:
    """The issuable command named `method` (`set_power`); ValueError naming them otherwise."""
    spec = BY_METHOD.get(method)
    if spec is None:
        raise ValueError(f"no command {method!r}; commands: {', '.join(BY_METHOD)}")
    return spec


def check(command):
    """`command` with its numbers as floats and its flags as bools; ValueError, naming the field
    and its allowed range, unless it is an issuable command with every argument in range (a
    float without a range must be finite)."""
    if not isinstance(command, tuple(s.dataclass for s in ISSUABLE)):
        names = ", ".join(s.name for s in ISSUABLE)
        raise ValueError(f"a command must be one of {names}; got {command!r}")
    spec = spec_of(command)
    checked = {}
    for f in dc.fields(command):
        value, name = getattr(command, f.name), f"{spec.name}.{f.name}"
        bound = bound_of(f)
        if f.type is float:
            checked[f.name] = (bound.check(name, value) if isinstance(bound, Range)
                               else lim.number(name, value))
        elif f.type is bool:
            if not isinstance(value, bool | np.bool_):
                raise ValueError(f"{name} must be True or False, got {value!r}")
            checked[f.name] = bool(value)
        elif isinstance(value, list) and not all(
                isinstance(v, int | float) and math.isfinite(v) for v in value):
            raise ValueError(f"{name} must hold finite numbers, got {value!r}")
    return dc.replace(command, **checked)


def make(method: str, *args, **kwargs):
    """The command `method` names, made of the Python API's arguments (TypeError for ones it
    does not take or a required one left out), checked (`check`)."""
    spec = by_method(method)
    names = [a.name for a in spec.args]
    if len(args) > len(names):
        raise TypeError(f"{method} takes {len(names)} arguments ({', '.join(names)}), "
                        f"got {len(args)}")
    given = dict(zip(names, args, strict=False))
    if twice := sorted(given.keys() & kwargs.keys()):
        raise TypeError(f"{method} got {', '.join(twice)} twice")
    given.update(kwargs)
    if unknown := sorted(given.keys() - set(names)):
        raise TypeError(f"{method} takes no argument {', '.join(unknown)}; its arguments: "
                        f"{', '.join(names) or 'none'}")
    if missing := [a.name for a in spec.args if a.required and a.name not in given]:
        raise TypeError(f"{method} needs {', '.join(missing)}")
    return check(spec.dataclass(**given))
