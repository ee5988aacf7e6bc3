"""The robot's signals, one declaration each, which every front end reads.

A signal is a value the simulated robot reports: its pose, velocity, axle speeds, encoder
counts, commanded power, IR readings, and the contact telemetry (each wheel's load and slip,
the tip-over margin). Each `Signal` states its unit and where each front end carries it:

- the station's robot output port (`<robot>.<port>`) that `Robot.signal(name)` reads;
- its key in `Robot.summary()` (a dotted path: `slip.ratio`);
- its field(s) in the HTTP state (`serving.snapshots`: a wheel's or the drive state's) and
  the change that counts for a subscription (`serving.routes.subscriptions`);
- its run-log column(s) (`systems.runlog`);
- the ROS-style topic that carries it, as the MCAP/Foxglove recording publishes it
  (`recording.topics`) and the ROS 2 front end does.

The contact telemetry (`TELEMETRY`) is derived everywhere from this table: a new telemetry
signal is a new entry here and an output port of its system. The state signals' front ends
are written out by hand (their formats are published contracts); the table states where each
carries them, and the contract tests check that every front end reports the same value.

No Drake import here (the HTTP process reads it).
"""

import dataclasses as dc
import math

from corobot_drake.model.dimensions import WHEEL_NAMES

WHEEL_SHORT = tuple("".join(word[0] for word in name.split("_")) for name in WHEEL_NAMES)
"""The wheels' short names in run-log columns: fl, fr, rl, rr."""

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


@dc.dataclass(frozen=True, eq=False)
class Signal:
    """One value (or vector: one per wheel, per axis) the robot reports (each declared once:
    compared and hashed by identity)."""

    name: str
    """The robot's term, and its reader: `Robot.signal(name)` (and a method of that name)."""
    unit: str
    doc: str
    port: str = ""
    """The station's robot output port `<robot>.<port>` it is read from ("": read otherwise)."""
    per_wheel: bool = False
    """One value per wheel (`WHEEL_NAMES` order) or one."""
    fields: dict = dc.field(default_factory=dict)
    """Its field names in the HTTP state and its topic's messages -> the change that counts
    for a subscription (0: any change)."""
    summary: str = ""
    """Its key in `Robot.summary()` (dotted: nested)."""
    log: tuple[str, ...] = ()
    """Its run-log columns (a per-wheel signal: one per wheel)."""
    topic: str = ""
    """The topic that carries it (under the robot's namespace), MCAP and ROS 2."""
    costly: bool = False
    """Evaluating it costs the plant's contact results or velocities: the run log and the
    recording sample it every `runlog.HELD_PERIOD` and hold it."""

    @property
    def field(self) -> str:
        """Its one field (a signal with several has no single one)."""
        (name,) = self.fields
        return name

    def summary_value(self, value):
        """Its value (`Robot.signal`) as `Robot.summary` reports it: a per-wheel signal's as a
        list in `WHEEL_NAMES` order."""
        return list(value.values()) if self.per_wheel else value


def _per_wheel(prefix: str) -> tuple[str, ...]:
    return tuple(f"{prefix}_{w}" for w in WHEEL_SHORT)


TELEMETRY = (
    Signal("wheel_loads", "N", "the vertical (world +z) component of the wheel's contact "
           "forces; at rest the four sum to the robot's weight",
           port="wheel_loads", per_wheel=True, fields={"load": LOAD_CHANGE},
           summary="wheel_loads_N", log=_per_wheel("load"), topic="wheel_loads", costly=True),
    Signal("wheel_slip_ratio", "", "longitudinal, dimensionless: + traction (turns faster "
           "than it travels), - braking",
           port="wheel_slip_ratio", per_wheel=True, fields={"slip_ratio": SLIP_RATIO_CHANGE},
           summary="slip.ratio", log=_per_wheel("slip_ratio"), topic="wheel_slip",
           costly=True),
    Signal("wheel_slip_angle", "deg", "between where the wheel points and where it goes, + "
           "moving to the left of the heading",
           port="wheel_slip_angle", per_wheel=True, fields={"slip_angle_deg": SLIP_ANGLE_CHANGE},
           summary="slip.angle_deg", log=_per_wheel("slip_angle"), topic="wheel_slip",
           costly=True),
    Signal("tip_margin", "deg", "the robot can still roll or pitch before its centre of mass "
           "passes an edge of the wheels' support; 37.4 upright at rest on level ground, "
           "negative tipping over",
           port="tip_margin", fields={"tip_margin_deg": math.degrees(ANGLE_CHANGE)},
           summary="tip_margin_deg", log=("tip_margin",), topic="tip_margin"),
)
"""The contact telemetry (`systems.contact`, `systems.stability`), in the run log's order."""

STATE = (
    Signal("pose", "m, rad", "the chassis frame in the world: x, y, z, roll, pitch, yaw",
           fields={"x": POSITION_CHANGE, "y": POSITION_CHANGE, "z": POSITION_CHANGE,
                   "roll": ANGLE_CHANGE, "pitch": ANGLE_CHANGE, "yaw": ANGLE_CHANGE},
           summary="pose", log=("x", "y", "yaw"), topic="odom"),
    Signal("velocity", "m/s, rad/s", "the chassis' forward and leftward speed and yaw rate",
           fields={"forward": SPEED_CHANGE, "lateral": SPEED_CHANGE, "yaw_rate": SPEED_CHANGE},
           summary="velocity", topic="odom"),
    Signal("heading", "rad", "compass: the chassis' yaw about world z, in (-pi, pi]",
           port="heading", fields={"heading": ANGLE_CHANGE,
                                   "heading_deg": math.degrees(ANGLE_CHANGE)},
           summary="heading", topic="drive_state"),
    Signal("position", "m", "GPS: the chassis frame's origin in the world", port="position",
           fields={"x": POSITION_CHANGE, "y": POSITION_CHANGE, "z": POSITION_CHANGE},
           summary="position", topic="drive_state"),
    Signal("axle_speeds", "rad/s", "each axle's measured speed", port="axle_speed",
           per_wheel=True, fields={"axle_speed": SPEED_CHANGE}, summary="wheels",
           topic="joint_states"),
    Signal("encoders", "ticks", "the front wheels' encoder counts, 600 per revolution",
           port="encoder_ticks", fields={"encoder_ticks": 0.0}, summary="encoders",
           log=("left_ticks", "right_ticks"), topic="drive_state"),
    Signal("commanded_power", "", "the drive's commanded power per side, in [-1, 1]",
           fields={"commanded_power": 0.0}, log=("left_power", "right_power"),
           topic="drive_state"),
    Signal("odometry", "m, rad", "dead reckoning from the encoders: x, y, yaw",
           port="odometry", summary="odometry"),
    Signal("ir_distances", "m", "each IR sensor's latest raw reading, by sensor",
           summary="ir", topic="ir/<sensor>"),
)
"""The robot's state: its front ends are written out by hand (published formats)."""

SIGNALS = {s.name: s for s in (*STATE, *TELEMETRY)}
"""Every signal by name."""


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


def get(tree: dict, path: str):
    """`tree[a][b]` for the dotted `path` `a.b`."""
    for key in path.split("."):
        tree = tree[key]
    return tree
