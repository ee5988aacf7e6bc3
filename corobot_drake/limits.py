"""Every allowed range, stated once with its reason: the scenario's fields, the commands'
arguments and the Python API's other arguments.

The Python API raises ValueError naming a range (`Range.check`, `number`), the HTTP contract
answers 422 with it (its request models are made of the commands' ranges, `commands.py`), and
the scenario loader (`config/validate.py`) checks every field against the bound it declares
beside it, as dataclass metadata (`bounded`):

    slew_rate: float = bounded(30.0, Range(0, 1e4, low_open=True, unit="rad/s^2"))

and says so in one line:

    robots.corobot.drive.slew_rate: must be in (0, 10000] rad/s^2; got -1

A float field without a bound must still be finite (`FINITE`), an int must fit Drake's int
(`DRAKE_INT`); the fields of Drake's own config structs get theirs from
`config.bounds.DRAKE_BOUNDS`, the one part that needs Drake's types.

No Drake import here (the HTTP process and `serving.client` read it).
"""

from __future__ import annotations

import dataclasses as dc
import math
import reprlib


@dc.dataclass(frozen=True)
class Range:
    """low <= value <= high (`low_open`/`high_open`: strictly). NaN never passes; an infinite
    value only when the bound is that infinity and closed. `zero` also allows exactly 0 (its
    meaning in `zero`: "rigid"). `why` is said after the range."""

    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False
    unit: str = ""
    why: str = ""
    zero: str = ""

    def allows(self, value: float) -> bool:
        if math.isnan(value):
            return False
        if self.zero and value == 0:
            return True
        above = value > self.low if self.low_open else value >= self.low
        below = value < self.high if self.high_open else value <= self.high
        return above and below

    def text(self) -> str:
        """The allowed values in words: `in (0, 10000] rad/s^2`, `> 0 and finite`, ..."""
        unit = f" {self.unit}" if self.unit else ""
        lo, hi = self.low, self.high
        if lo == -math.inf and hi == math.inf:
            words = f"a finite number{unit}"
        elif hi == math.inf:
            words = f"{'>' if self.low_open else '>='} {_number(lo)}{unit}"
            words += " and finite" if self.high_open else ", or .inf"
        elif lo == -math.inf:
            words = f"{'<' if self.high_open else '<='} {_number(hi)}{unit} and finite"
        else:
            words = (f"in {'(' if self.low_open else '['}{_number(lo)}, {_number(hi)}"
                     f"{')' if self.high_open else ']'}{unit}")
        if self.zero:
            words = f"0 ({self.zero}) or {words}"
        return words + (f" ({self.why})" if self.why else "")

    def check(self, name: str, value, *, finite: bool = True) -> float:
        """`value` as a float if it is a number in the range (`finite`: also finite), else
        ValueError naming `name`, the range and the value: the Python API's check (`number`)."""
        if self.high_open or self.zero:
            raise TypeError("the Python API's ranges are closed above and have no zero")
        return number(name, value, self.low, self.high, low_open=self.low_open, finite=finite)

    def problem(self, value) -> str | None:
        """None when `value` is allowed, else what is wrong and what is allowed."""
        if self.allows(float(value)):
            return None
        return f"must be {self.text()}; got {_number(value)}"


def _number(x) -> str:
    """An int as it is, a float as `%g` (1e+08, 0.0001, inf)."""
    return str(x) if isinstance(x, int) else f"{x:g}"


@dc.dataclass(frozen=True)
class OneOf:
    """A name from a fixed list."""

    names: tuple[str, ...]
    why: str = ""

    def problem(self, value) -> str | None:
        if value in self.names:
            return None
        return (f"{value!r} is not one of {', '.join(self.names)}"
                + (f" ({self.why})" if self.why else ""))


FINITE = Range(low_open=True, high_open=True)
"""The bound of every float that declares none."""

DRAKE_INT = Range(-(2**31), 2**31 - 1, why="Drake's int")
"""The bound of every int that declares none (Drake's schema ints are 32 bits)."""


def bounded(default, bound, size: int | None = None):
    """A dataclass field with `default` (a value, or a callable for a factory) and its bound
    (a Range or OneOf; for a list, one bound for every element or a tuple, one per element)
    and, for a list, its `size`."""
    kwargs = {"default_factory": default} if callable(default) else {"default": default}
    return dc.field(metadata={"bound": bound, "size": size}, **kwargs)


def bound_of(field: dc.Field):
    return field.metadata.get("bound")



# --- the commands' arguments (`commands.py`: Python, HTTP and a scenario's script) ------------

SIDE_POWER = Range(-1.0, 1.0)
"""SetPower: power per side."""
SIDE_SPEED = Range(-5.0, 5.0, unit="m/s")
"""SetSpeed: rim speed per side (8x the robot's top speed; the drive then clamps the axle
speed to its maximum)."""
LINEAR_SPEED = Range(-5.0, 5.0, unit="m/s")
"""SetVelocity: chassis speed (the drive scales both sides down past the max axle speed)."""
YAW_RATE = Range(-50.0, 50.0, unit="rad/s")
"""SetVelocity: yaw rate (positive: left)."""
DRIVE_POWER = Range(0.0, 1.0, low_open=True)
"""DriveDistance / RotateDegrees: a completing command's power, in (0, 1]."""
DISTANCE = Range(-100.0, 100.0, unit="m")
"""DriveDistance: m (negative: backwards)."""
DEGREES = Range(-3600.0, 3600.0, unit="deg")
"""RotateDegrees: degrees (positive: left)."""
YAW_DEG = Range(-3600.0, 3600.0, unit="deg")
"""SetPose: heading, degrees."""

# --- physical limits (each used by the bounds of several fields) -----------------------------

POSITION_LIMIT = 1.0e4
"""m: every position's coordinates within +-10 km of the origin, in a scenario or SetPose
(float steps there are ~2e-12 m, far below contact's scale; further, the world stops being a
place)."""
POSITION = Range(-POSITION_LIMIT, POSITION_LIMIT, unit="m")
"""A position coordinate: a scenario's, SetPose's x and y."""
START_POSE = (POSITION, POSITION, YAW_DEG)
"""[x, y, yaw_deg] (m, m, deg): the pose a resumed DriveDistance or RotateDegrees counts from
(its `start`, which a saved scene writes)."""

LINEAR_SPEED_LIMIT = 50.0
"""m/s: a body's initial speed (80 times the robot's top speed; beyond, a body crosses a
metre per plant step and tunnels through the contact instead of meeting it)."""
ANGULAR_SPEED_LIMIT = 100.0
"""rad/s: a body's initial angular speed."""
SPATIAL_VELOCITY = (
    *(Range(-ANGULAR_SPEED_LIMIT, ANGULAR_SPEED_LIMIT, unit="rad/s"),) * 3,
    *(Range(-LINEAR_SPEED_LIMIT, LINEAR_SPEED_LIMIT, unit="m/s"),) * 3,
)
"""[wx, wy, wz, vx, vy, vz] of an initial spatial velocity."""

AXLE_SPEED_LIMIT = 200.0
"""rad/s: any axle speed, commanded or initial (12 m/s at the rim, 20 times the robot's
top speed; 1e9 rad/s froze the plant)."""

AXLE_SPEED = Range(0.0, AXLE_SPEED_LIMIT, low_open=True, unit="rad/s")
AXLE_SPEED_RANGE = Range(-AXLE_SPEED_LIMIT, AXLE_SPEED_LIMIT, unit="rad/s")
ANGLE = Range(-1e6, 1e6, unit="deg")
HEADING = Range(-1e6, 1e6, unit="rad")
"""An unwrapped heading (rad; it counts whole turns)."""
ENCODER_COUNT = Range(-1e9, 1e9, unit="ticks")
"""An encoder's count (600 a turn: 1e9 ticks are 1.6 million turns, beyond any wheel angle
a scenario may start at)."""
SHAPE_SIZE = Range(0.001, 100.0, unit="m", why="a shape's dimensions")
MESH_SCALE = Range(1e-4, 1e4, why="from a file's units to metres (0.1 mm to 10 km units)")
"""A mesh's scale; the scaled mesh must also be a shape's size across (`config/mesh_files.py`)."""
ELLIPSOID_MAX_ASPECT = 4.0
"""A compliant ellipsoid's largest semi-axis over its smallest, at most. Its hydroelastic mesh
is refined to a tenth of its smallest size (`station.py`) all over: its mesh took 0.2 s of CPU
at 4, 0.8 s at 5, 4 s at 10, 22 s and 600 MB at 20. A rigid
one (`hydroelastic_modulus: 0`) has no mesh and no limit."""
FRICTION = Range(0.0, 10.0, why="Coulomb friction; Drake needs >= 0")
COLOR = Range(0.0, 1.0, why="a colour component")
MASS = Range(1e-3, 1e5, unit="kg")
HYDROELASTIC_MODULUS = Range(1e4, 1e11, unit="Pa", zero="rigid",
                             why="from foam to steel; 1e30 failed the contact solver")
"""A world body's hydroelastic modulus."""
TYRE_MODULUS = Range(1e5, 1e8, unit="Pa", why="a rubber tyre")
"""The tyres' hydroelastic modulus: at 1e4 Pa they sank 11 mm, at 1e10 the robot bounced and
drove 0.21 m of the 0.50 m it drives in 1 s at full power, and 1e30 failed the contact solver."""
RESOLUTION_HINT = Range(0.001, 0.02, unit="m")
"""The tyres' mesh size: at 1 mm the robot takes 2 s to build (finer grows fast: 1e-6 m took
2.8 GB and growing); coarser than 2 cm the tyre is a polygon (at 6 cm the robot sinks 2.2 mm
and drives 8% short, at 1 m it barely moves)."""
DISSIPATION = Range(0.0, 100.0, unit="s/m", why="Hunt-Crossley; Drake needs >= 0")
DURATION = Range(0.0, 1e7, unit="s")
"""Any duration or time of day: finite, under 116 days (where a 0.1 ms step is still 500
float steps of the clock)."""

SIMULATION_DURATION = Range(0.0, math.inf, low_open=True, unit="s", why="until stopped")

MIN_TIME_STEP = 1e-4
"""s: the finest plant step (10 s of the default scene then take ~100x longer than at 10 ms,
minutes of wall time; 1e-7 hung)."""
MAX_TIME_STEP = 0.02
"""s: the coarsest plant step the tyres' hydroelastic contact resolves: at 20 ms the robot
sinks 2 mm into the ground and tilts under a degree while driving, beyond that the sink and
the rocking grow fast, and at 1 s it falls through the ground (docs/tuning.md, "The largest
plant step": `tools/step_limit.py`)."""
TIME_STEP = Range(MIN_TIME_STEP, MAX_TIME_STEP, unit="s",
                  why="a step the tyres' contact can resolve")
"""The physics' step: a discrete plant's `time_step`, or a continuous plant's integrator step
(`simulator_config.max_step_size`)."""
PLANT_TIME_STEP = dc.replace(TIME_STEP, zero="a continuous plant: simulator_config steps it "
                             "with integration_scheme cenic")

MAX_RATE_HZ = 1000.0
"""Hz: the fastest periodic event of a sensor or controller (a rate of 1e9 hung the run)."""
PERIOD = Range(1.0 / MAX_RATE_HZ, 1.0, unit="s", why="a controller's period; 1e-7 hung the run")
RATE = Range(0.0, MAX_RATE_HZ, low_open=True, unit="Hz")
CAMERA_MAX_FPS = 240.0
"""Hz: the fastest camera (a 320 x 240 frame costs ~6 ms to render here: 240 Hz is 1.5 s of
rendering per simulated second)."""
CAMERA_MAX_PIXELS = 4096
"""A camera image's width and height at most (4096 x 4096 x 4 bytes is 64 MB a frame)."""


# --- the Python API's and the tools' other arguments ----------------------------------------

WORKERS = Range(1, 1024, why="Ray workers; None: the machine's cores")
"""A study's Ray workers (`study.engine.run_study`, `ray_session`; the tools' --workers), a
whole number; None means this machine's cores (or a joined cluster's CPUs)."""

LIVE_RUN_LOG_WINDOW = 300.0
"""s of run log a live run keeps in memory (1.9 MB a robot): a served simulation and the
interactive Meshcat run, which may be left running for days (`Simulation.run_log_window`)."""


def number(name: str, value, low: float = -math.inf, high: float = math.inf, *,
           low_open: bool = False, finite: bool = True) -> float:
    """`value` as a float if it is a number in [low, high] (`low_open`: (low, high]; `finite`:
    also finite); otherwise ValueError naming `name`, the allowed range and the value.
    Booleans are not numbers here (True is not a power)."""
    # Not a number: a bool (True is not a power), a string, an array (even of one element:
    # numpy would make it a float, hiding a caller's mix-up).
    if isinstance(value, bool) or getattr(value, "ndim", 0) != 0 or (
            not isinstance(value, int | float) and not hasattr(value, "__float__")):
        raise ValueError(f"{name} must be {_describe(low, high, low_open, finite)}, "
                         f"got {reprlib.repr(value)}")
    try:
        x = shown = float(value)
    except OverflowError:  # an int beyond any float: outside every finite range
        x, shown = (math.inf if value > 0 else -math.inf), reprlib.repr(value)
    inside = (low < x if low_open else low <= x) and x <= high
    if not inside or (finite and not math.isfinite(x)):
        # Described only here: formatting the bounds on every call cost more than the check
        # (a simulation advanced 10 ms at a time checks its time 100 times a second).
        raise ValueError(f"{name} must be {_describe(low, high, low_open, finite)}, got {shown}")
    return x


def _describe(low: float, high: float, low_open: bool, finite: bool) -> str:
    kind = "a finite number" if finite else "a number"
    if low == -math.inf and high == math.inf:
        return kind
    if high == math.inf:
        return f"{kind} {'>' if low_open else '>='} {low:g}"
    if low == -math.inf:
        return f"{kind} <= {high:g}"
    return f"{kind} in {'(' if low_open else '['}{low:g}, {high:g}]"
