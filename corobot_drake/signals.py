"""The robot's signals, one declaration each, from which every front end carries them.

A signal is a value the simulated robot reports: its pose, velocity, axle speeds, encoder
counts, commanded power, IR readings, and the contact telemetry (each wheel's load and slip,
the tip-over margin). Its value (`Robot.signal(name)`) is a float, or a dict of floats by key
(wheel, field or sensor name). Each `Signal` states its unit and where each front end carries
it, as *places*: dotted paths into that front end's tree (a dict, a list, a message's
attributes) where

- a path holds the value: a float, or for a keyed value the dict of it (written key by key);
- `*` in a segment stands for each key (`drive.wheels.*.load`, `ir.*_ir.raw`), and a `#`
  segment for its index in the value's key order (`velocity.#`: a list or an array);
- a trailing `[]` holds the values as a list in key order (`slip.ratio[]`);
- a suffix `|deg` holds it in degrees, `|f32` as a 32-bit float, `|range` as sensor_msgs/
  Range's (a 32-bit float, +Inf when nothing is in range, REP 117: read as its max_range),
  `|pose` in a geometry Pose (position and orientation quaternion: read as x, y, z, roll,
  pitch, yaw); the last three are read only (published formats, built by their publishers).

The places of each front end:

- `summary`: in `Robot.summary()`;
- `http`: in the HTTP robot state (`serving.snapshots.robot_snapshot`; its subscriptions'
  change thresholds: `fields`);
- `log`: the run-log columns (`systems.runlog`), each a key of its value;
- `mcap` / `ros2`: {topic: place in its message}, as the MCAP/Foxglove recording and the ROS 2
  node publish them (a `*` in a topic: one topic per key). A signal with a `topic` gets a
  message of its own there, made from this table (JSON for MCAP, a corobot_interfaces message
  for ROS 2); the published formats (nav_msgs/Odometry, JointState, Range, the drive state)
  are built by their publishers and the table says where in them each signal is.

A new signal is an entry here (a `port` of the robot's subsystem `system`, a `topic`) and
that system's output port: it then appears in the summary, the HTTP state and its
subscriptions, the run log, the MCAP topics and (once corobot_interfaces is rebuilt with its
message, `python -m corobot_drake.ros2.interfaces`) ROS 2. tests/service/test_tables.py holds
every front end to this table.

No Drake import here (the HTTP process reads it).
"""


import dataclasses as dc
import functools
import math

from corobot_drake.robots import corobot

WHEEL_NAMES = corobot.wheel_names()
"""The Corobot's wheels, in its model's joint order (its robot file's): the signals' keys."""
WHEEL_SHORT = tuple("".join(word[0] for word in name.split("_")) for name in WHEEL_NAMES)
"""The Corobot's wheels' short names in run-log columns: fl, fr, rl, rr."""
CODED = ("front_left", "front_right")
"""The Corobot's wheels with an encoder (left, right)."""
ALL, ENCODED = "all", "encoded"
"""`Signal.wheels`: one value per wheel, or per wheel with an encoder."""

POSITION_CHANGE = 1e-4
"""m: a position (x, y, z) change that counts (0.1 mm; a robot at rest creeps by nm)."""
ANGLE_CHANGE = 1e-3
"""rad (0.057 deg): a heading, roll, pitch, yaw or tip margin change that counts."""
SPEED_CHANGE = 1e-3
"""m/s, rad/s: a velocity, yaw rate or axle speed change that counts."""
LOAD_CHANGE = 0.05
"""N: a wheel load change that counts (0.5% of a wheel's share at rest, ~9.9 N)."""
SLIP_RATIO_CHANGE = 1e-3
"""A slip ratio change that counts (free rolling reads ~0.008)."""
SLIP_ANGLE_CHANGE = 0.5
"""deg: a slip angle change that counts (at rest the wheels creep sideways by ~1e-5 m/s, which
reads -0.07 to +0.03 deg against `contact.SLIP_SPEED_FLOOR`; a spin reads 39.5)."""


DEG = "|deg"
F32 = "|f32"
RANGE = "|range"
POSE = "|pose"
"""A place's suffixes (module docstring)."""


@dc.dataclass(frozen=True, eq=False)
class Signal:
    """One value (or dict of values by key) the robot reports (each declared once: compared
    and hashed by identity)."""

    name: str
    """The robot's term, and its reader: `Robot.signal(name)`."""
    unit: str
    doc: str
    port: str = ""
    """The station's robot output port `<robot>.<port>` it is read from ("": `reader`)."""
    keys: tuple[str, ...] = ()
    """The keys of its port's values, in order (none: one float)."""
    system: str = ""
    """The robot's subsystem `<robot>.<system>` whose output port `port` is: the station
    exports it, the recording and ROS 2 read it there ("": the station wires it itself)."""
    reader: str = ""
    """For a signal without a port: the `Robot` method that reads it."""
    integer: bool = False
    """Whole counts (rounded from the port's floats)."""
    fields: dict = dc.field(default_factory=dict)
    """Its field names in the HTTP state and its topic's messages -> the change that counts
    for a subscription (0: any change)."""
    summary: str = ""
    """Its place in `Robot.summary()`."""
    http: tuple[str, ...] = ()
    """Its places in the HTTP robot state."""
    log: tuple[tuple[str, str], ...] = ()
    """Its run-log columns: (column, key of its value; "" for a float)."""
    log_format: str = ".6g"
    """The CSV format of its columns."""
    topic: str = ""
    """The topic of its own message (under the robot's namespace), MCAP and ROS 2."""
    mcap: dict = dc.field(default_factory=dict)
    """{topic: place}: where the published formats of the MCAP recording carry it."""
    ros2: dict = dc.field(default_factory=dict)
    """{topic: place}: where the published formats of the ROS 2 node carry it."""
    costly: bool = False
    """Evaluating it costs the plant's contact results or velocities: the run log and the
    recording sample it every `runlog.HELD_PERIOD` and hold it."""
    wheels: str = ""
    """Its keys are the robot's wheels: `ALL` (one value per wheel, wheel order) or
    `ENCODED` (the wheels with an encoder: the first left and first right); declared with
    the Corobot's, each robot's are `for_robot`'s."""

    @property
    def per_wheel(self) -> bool:
        """One value per wheel (the robot's wheel order)."""
        return self.wheels == ALL and bool(self.keys)

    def for_robot(self, wheel_names: tuple[str, ...], encoded: tuple[str, str]) -> "Signal":
        """This signal for a robot whose wheels are `wheel_names` (wheel order) and whose
        encoders are on `encoded` (left, right): its keys and run-log columns by that robot's
        wheels (itself when they are the Corobot's)."""
        if not self.wheels or (wheel_names, encoded) == (WHEEL_NAMES, CODED):
            return self
        rename = dict(zip(CODED, encoded, strict=True))
        keys = self.keys
        if self.keys:
            keys = tuple(wheel_names) if self.wheels == ALL else tuple(encoded)
        if self.per_wheel and self.log:  # one column per wheel: <prefix>_<short>
            prefix = self.log[0][0].rsplit("_", 1)[0]
            log = _per_wheel(prefix, wheel_names)
        else:
            log = tuple((column, rename.get(key, key)) for column, key in self.log)
        return dc.replace(self, keys=keys, log=log)

    @property
    def field(self) -> str:
        """Its one field (a signal with several has no single one)."""
        (name,) = self.fields
        return name

    @property
    def size(self) -> int:
        """Its port's size."""
        return len(self.keys) or 1

    @property
    def own_place(self) -> str:
        """Its place in its own topic's message: by wheel under `wheels`, else its field(s)."""
        if self.per_wheel:
            return f"wheels.*.{self.field}"
        return "*" if self.keys else self.field

    @property
    def mcap_places(self) -> dict:
        """{topic: place} of every MCAP topic that carries it (its own topic's too)."""
        return {**self.mcap, **({self.topic: self.own_place} if self.topic else {})}

    @property
    def ros2_places(self) -> dict:
        """{topic: place} of every ROS 2 topic that carries it (its own topic's too: arrays by
        wheel, as `ros2.interfaces.telemetry_definition` writes them)."""
        if not self.topic:
            return dict(self.ros2)
        own = f"{self.field}.#" if self.per_wheel else self.own_place
        return {**self.ros2, self.topic: own}

    @property
    def log_columns(self) -> tuple[str, ...]:
        return tuple(column for column, _ in self.log)

    def value_of(self, vector) -> float | dict:
        """Its value from its port's `vector`."""
        convert = round if self.integer else float
        if not self.keys:
            return convert(vector[0])
        return {key: convert(x) for key, x in zip(self.keys, vector, strict=True)}


def wheel_short(wheel_names: tuple[str, ...]) -> tuple[str, ...]:
    """The wheels' short names in run-log columns: each name's words' initials (the
    Corobot's fl, fr, rl, rr), or the names themselves when two initials are alike."""
    short = tuple("".join(word[:1] for word in name.split("_")) for name in wheel_names)
    return short if len(set(short)) == len(short) else tuple(wheel_names)


def _per_wheel(prefix: str, wheel_names: tuple[str, ...] = WHEEL_NAMES
               ) -> tuple[tuple[str, str], ...]:
    return tuple((f"{prefix}_{short}", wheel) for short, wheel in zip(
        wheel_short(wheel_names), wheel_names, strict=True))


def _same(*names: str) -> tuple[tuple[str, str], ...]:
    return tuple((name, name) for name in names)


TELEMETRY = (
    Signal("wheel_loads", "N", "the vertical (world +z) component of the wheel's contact "
           "forces; at rest the four sum to the robot's weight",
           port="wheel_loads", keys=WHEEL_NAMES, wheels=ALL, system="wheel_contacts",
           fields={"load": LOAD_CHANGE}, summary="wheel_loads_N[]",
           http=("drive.wheels.*.load",), log=_per_wheel("load"), topic="wheel_loads",
           costly=True),
    Signal("wheel_slip_ratio", "", "longitudinal, dimensionless: + traction (turns faster "
           "than it travels), - braking",
           port="wheel_slip_ratio", keys=WHEEL_NAMES, wheels=ALL, system="wheel_contacts",
           fields={"slip_ratio": SLIP_RATIO_CHANGE}, summary="slip.ratio[]",
           http=("drive.wheels.*.slip_ratio",), log=_per_wheel("slip_ratio"),
           topic="wheel_slip", costly=True),
    Signal("wheel_slip_angle", "deg", "between where the wheel points and where it goes, + "
           "moving to the left of the heading",
           port="wheel_slip_angle", keys=WHEEL_NAMES, wheels=ALL, system="wheel_contacts",
           fields={"slip_angle_deg": SLIP_ANGLE_CHANGE}, summary="slip.angle_deg[]",
           http=("drive.wheels.*.slip_angle_deg",), log=_per_wheel("slip_angle"),
           topic="wheel_slip", costly=True),
    Signal("tip_margin", "deg", "the robot can still roll or pitch before its centre of mass "
           "passes an edge of the wheels' support; 37.4 upright at rest on level ground, "
           "negative tipping over",
           port="tip_margin", system="tip_margin",
           fields={"tip_margin_deg": math.degrees(ANGLE_CHANGE)}, summary="tip_margin_deg",
           http=("drive.tip_margin_deg",), log=(("tip_margin", ""),), topic="tip_margin"),
)
"""The contact telemetry (`systems.contact`, `systems.stability`)."""

POSE_FIELDS = ("x", "y", "z", "roll", "pitch", "yaw")

STATE = (
    Signal("commanded_power", "", "the drive's commanded power per wheel (its side's), in "
           "[-1, 1]", reader="commanded_power", fields={"commanded_power": 0.0},
           summary="commanded_power", http=("drive.wheels.*.commanded_power",),
           log=(("left_power", "front_left"), ("right_power", "front_right")), wheels=ALL,
           mcap={"drive_state": "wheels.*.commanded_power"},
           ros2={"drive_state": "wheels.#.commanded_power"}),
    Signal("encoders", "ticks", "the encoded wheels' counts, the robot file's "
           "encoder_ticks_per_revolution a turn",
           port="encoder_ticks", keys=CODED, wheels=ENCODED, integer=True,
           fields={"encoder_ticks": 0.0}, summary="encoders",
           http=("drive.wheels.*.encoder_ticks", "encoders"),
           log=(("left_ticks", "front_left"), ("right_ticks", "front_right")), log_format="d",
           mcap={"drive_state": "wheels.*.encoder_ticks"},
           ros2={"drive_state": "wheels.#.encoder_ticks"}),
    Signal("pose", "m, rad", "the chassis frame in the world: x, y, z, roll, pitch, yaw",
           reader="pose", fields={"x": POSITION_CHANGE, "y": POSITION_CHANGE,
                                  "z": POSITION_CHANGE, "roll": ANGLE_CHANGE,
                                  "pitch": ANGLE_CHANGE, "yaw": ANGLE_CHANGE},
           summary="pose", http=("drive.pose",), log=_same("x", "y", "yaw"),
           log_format=".6f", mcap={"odom": "pose" + POSE},
           ros2={"ground_truth": "pose.pose" + POSE}),
    Signal("velocity", "m/s, rad/s", "the chassis' forward and leftward speed and yaw rate "
           "(in its heading's frame; ROS 2's /ground_truth twist is in base_link)",
           reader="velocity", fields={"forward": SPEED_CHANGE, "lateral": SPEED_CHANGE,
                                      "yaw_rate": SPEED_CHANGE},
           summary="velocity", http=("drive.velocity",)),
    Signal("heading", "rad", "compass: the chassis' yaw about world z, in (-pi, pi]",
           port="heading", fields={"heading": ANGLE_CHANGE,
                                   "heading_deg": math.degrees(ANGLE_CHANGE)},
           summary="heading",
           http=("drive.heading", "drive.heading_deg" + DEG, "compass.heading",
                 "compass.heading_deg" + DEG),
           mcap={"drive_state": "heading"}, ros2={"drive_state": "heading"}),
    Signal("position", "m", "GPS: the chassis frame's origin in the world", port="position",
           keys=("x", "y", "z"),
           fields={"x": POSITION_CHANGE, "y": POSITION_CHANGE, "z": POSITION_CHANGE},
           summary="position[]", http=("drive.position", "gps"),
           mcap={"drive_state": "position[]", "odom": "pose.position"},
           ros2={"drive_state": "position", "ground_truth": "pose.pose.position"}),
    Signal("axle_speeds", "rad/s", "each axle's measured speed", port="axle_speed",
           keys=WHEEL_NAMES, wheels=ALL, fields={"axle_speed": SPEED_CHANGE}, summary="wheels",
           http=("drive.wheels.*.axle_speed",),
           mcap={"drive_state": "wheels.*.axle_speed", "joint_states": "joints.#.velocity"},
           ros2={"drive_state": "wheels.#.axle_speed", "joint_states": "velocity.#"}),
    Signal("odometry", "m, rad", "dead reckoning from the encoders: x, y, yaw",
           port="odometry", keys=("x", "y", "yaw"), summary="odometry", http=("drive.odometry",),
           ros2={"wheel_odom": "pose.pose" + POSE, "odom": "pose.pose" + POSE}),
    Signal("ir_distances", "m", "each IR sensor's latest raw reading, by sensor",
           reader="ir_distances", summary="ir", http=("ir.*_ir.raw",),
           mcap={"ir/*": "range"}, ros2={"ir/*": "range" + RANGE}),
)
"""The robot's state, in the run log's order (its columns are the table's, in order)."""

SIGNALS = {s.name: s for s in (*STATE, *TELEMETRY)}
"""Every signal by name, in the run log's order (the Corobot's: `robot_signals` any robot's)."""


@functools.cache
def robot_signals(wheel_names: tuple[str, ...] = WHEEL_NAMES,
                  encoded: tuple[str, str] = CODED) -> dict[str, Signal]:
    """`SIGNALS` for a robot whose wheels are `wheel_names` (wheel order, `RobotSpec.
    wheel_names`) with encoders on `encoded` (its first left and right wheel): each per-wheel
    signal keyed by that robot's wheels (`Signal.for_robot`). The Corobot's is `SIGNALS`."""
    if (tuple(wheel_names), tuple(encoded)) == (WHEEL_NAMES, CODED):
        return SIGNALS
    return {name: s.for_robot(tuple(wheel_names), tuple(encoded)) for name, s in SIGNALS.items()}


def spec_signals(spec) -> dict[str, Signal]:
    """`robot_signals` of a `robots.RobotSpec`."""
    left, right = spec.encoded
    return robot_signals(spec.wheel_names, (spec.wheel_names[left], spec.wheel_names[right]))

TOPIC_DOCS = {
    "wheel_loads": "Each wheel's load: systems.contact.WheelContacts.",
    "wheel_slip": "Each wheel's slip: systems.contact.WheelContacts.",
    "tip_margin": "The tip-over margin: systems.stability.TipMargin.",
}
"""The description of a `topic` of signals' own (its messages' schema, its ROS 2 message);
one not here: its first signal's doc."""


def change_thresholds() -> dict[str, float]:
    """Every field of the HTTP state -> the change that counts (fields that count at any
    change left out); one threshold per field name across the signals."""
    out: dict[str, float] = {}
    for signal in SIGNALS.values():
        for field, change in signal.fields.items():
            if change and out.setdefault(field, change) != change:
                raise ValueError(f"field {field!r} has two change thresholds")
    return out


def put(tree: dict, path: str, value) -> None:
    """Sets `tree[a][b] = value` for the dotted `path` `a.b` (making the dicts between)."""
    *parents, leaf = path.split(".")
    for key in parents:
        tree = tree.setdefault(key, {})
    tree[leaf] = value


def get(tree, path: str):
    """`tree[a][b]` for the dotted `path` `a.b` (a dict's key, a list's index, an object's
    attribute)."""
    for key in path.split("."):
        if isinstance(tree, dict):
            tree = tree[key]
        elif key.isdigit():
            tree = tree[int(key)]
        else:
            tree = getattr(tree, key)
    return tree


def _expand(path: str, key: str, index: int) -> str:
    return ".".join(str(index) if part == "#" else part.replace("*", key)
                    for part in path.split("."))


def _split(place: str) -> tuple[str, str]:
    path, _, conversion = place.partition("|")
    return path, conversion


@functools.cache
def _writer(place: str):
    """(path segments, scale, as a list, keyed) of a place to write (parsed once: the HTTP
    state is written many times a second)."""
    path, conversion = _split(place)
    if conversion not in ("", "deg"):
        raise ValueError(f"place {place!r}: {conversion!r} is read only")
    as_list = path.endswith("[]")
    parts = tuple(path.removesuffix("[]").split("."))
    keyed = any("*" in part or part == "#" for part in parts)
    return parts, math.degrees if conversion == "deg" else None, as_list, keyed


def _put_at(tree: dict, parts, value) -> None:
    for key in parts[:-1]:
        tree = tree.setdefault(key, {})
    tree[parts[-1]] = value


def put_value(tree: dict, place: str, value) -> None:
    """Writes a signal's `value` (a float or a dict by key) at its `place` in `tree` (module
    docstring; not `|pose`, `|f32` or `|range`)."""
    parts, scale, as_list, keyed = _writer(place)
    if not isinstance(value, dict):
        _put_at(tree, parts, scale(value) if scale else value)
    elif as_list:
        _put_at(tree, parts, [scale(v) if scale else v for v in value.values()])
    else:
        parts = parts if keyed else (*parts, "*")
        for index, (key, v) in enumerate(value.items()):
            _put_at(tree, [str(index) if part == "#" else part.replace("*", key)
                           for part in parts], scale(v) if scale else v)


def read_value(tree, place: str, keys: tuple[str, ...] | None):
    """A signal's value read back from its `place` in `tree` (a dict, list or message):
    `keys` of a keyed signal's value (None: a float)."""
    path, conversion = _split(place)
    if conversion == "pose":
        return _pose_fields(get(tree, path), keys)
    if conversion == "range":  # one Range message: +Inf is its max_range
        value = get(tree, path)
        return get(tree, "max_range") if math.isinf(value) else value
    unscale = (lambda v: math.radians(v)) if conversion == "deg" else (lambda v: v)
    if keys is None:
        return unscale(get(tree, path))
    if path.endswith("[]"):
        values = get(tree, path[:-2])
        if len(values) != len(keys):
            raise ValueError(f"{place}: {len(values)} values for {len(keys)} keys")
        return {k: unscale(v) for k, v in zip(keys, values, strict=True)}
    if "*" not in path and "#" not in path.split("."):
        path += ".*"
    return {key: unscale(get(tree, _expand(path, key, i))) for i, key in enumerate(keys)}


def _pose_fields(pose, keys) -> dict:
    """x, y, z and roll, pitch, yaw (extrinsic x-y-z, as Drake's RollPitchYaw) of a Pose (a
    position and an orientation quaternion), those of `keys`."""
    p, q = get(pose, "position"), get(pose, "orientation")
    w, x, y, z = (float(get(q, c)) for c in "wxyz")
    fields = {"x": float(get(p, "x")), "y": float(get(p, "y")), "z": float(get(p, "z")),
              "roll": math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y)),
              "pitch": math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x)))),
              "yaw": math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))}
    return {key: fields[key] for key in keys}


def topic_name(topic: str, key: str) -> str:
    """A place's topic for one key of the value (`ir/*`: `ir/front`)."""
    return topic.replace("*", key)


def own_topics(table: dict | None = None) -> dict[str, tuple[Signal, ...]]:
    """{topic: the signals carried in it}, of every signal with a message of its own, in
    the table's order (`table`: a robot's, `robot_signals`; default `SIGNALS`)."""
    out: dict[str, list] = {}
    for signal in (table or SIGNALS).values():
        if signal.topic:
            out.setdefault(signal.topic, []).append(signal)
    for topic, carried in out.items():
        if not all(s.system for s in carried):
            raise ValueError(f"topic {topic!r}: a signal with a topic of its own needs a system")
        if len({(s.keys, s.costly) for s in carried}) != 1:
            raise ValueError(f"topic {topic!r} carries signals of different keys or costs")
    return {topic: tuple(carried) for topic, carried in out.items()}
