"""The allowed values of the scenario's fields: each limit stated once, with its reason.

A field of the project's own schema declares its bound beside it, as dataclass metadata
(`slew_rate: float = bounded(dim.SLEW_RATE, Range(0, 1e4, low_open=True, unit="rad/s^2"))`);
the fields of Drake's own config structs get theirs from `DRAKE_BOUNDS` below. The loader
(`config/validate.py`) walks the loaded scenario and checks every number against its bound,
and every number without one against `FINITE`; its message states the allowed range:

    robots.corobot.drive.slew_rate: must be in (0, 10000] rad/s^2; got -1

A new field gets its bound by the same `bounded(...)` (or, for a Drake struct, an entry in
`DRAKE_BOUNDS`); a float without one must still be finite, an int must fit Drake's int.
"""

import dataclasses as dc
import math

from pydrake.multibody.plant import MultibodyPlantConfig
from pydrake.systems.analysis import GetIntegrationSchemes, SimulatorConfig
from pydrake.systems.sensors import CameraConfig

from corobot_drake import limits as api


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


# --- physical limits (each used by the bounds of several fields) -----------------------------

POSITION_LIMIT = api.POSITION_LIMIT
POSITION = Range(-POSITION_LIMIT, POSITION_LIMIT, unit="m")

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
POWER = Range(*api.DRIVE_POWER, low_open=True)
"""A completing command's power."""

# The commands' arguments: the same ranges as the Python API's and HTTP's (`limits.py`).
SIDE_POWER = Range(*api.POWER)
SIDE_SPEED = Range(*api.SPEED, unit="m/s")
LINEAR_SPEED = Range(*api.LINEAR, unit="m/s")
YAW_RATE = Range(*api.ANGULAR, unit="rad/s")
DISTANCE = Range(*api.DISTANCE, unit="m")
DEGREES = Range(*api.DEGREES, unit="deg")
YAW_DEG = Range(*api.YAW_DEG, unit="deg")
SET_POSITION = Range(*api.POSITION, unit="m")

SHAPE_SIZE = Range(0.001, 100.0, unit="m", why="a shape's dimensions")
ELLIPSOID_MAX_ASPECT = 4.0
"""A compliant ellipsoid's largest semi-axis over its smallest, at most. Its hydroelastic mesh
is refined to a tenth of its smallest size (`station.py`) all over: its mesh took 0.2 s of CPU
at 4, 0.8 s at 5, 4 s at 10, 22 s and 600 MB at 20 (a one-off check, 2026-11-23). A rigid
one (`hydroelastic_modulus: 0`) has no mesh and no limit."""
FRICTION = Range(0.0, 10.0, why="Coulomb friction; Drake needs >= 0")
COLOR = Range(0.0, 1.0, why="a colour component")
MASS = Range(1e-3, 1e5, unit="kg")
HYDROELASTIC_MODULUS = Range(1e4, 1e11, unit="Pa", zero="rigid",
                             why="from foam to steel; 1e30 failed the contact solver")
"""A world body's hydroelastic modulus."""
TYRE_MODULUS = Range(1e5, 1e8, unit="Pa", why="a rubber tyre")
"""The tyres' hydroelastic modulus: at 1e4 Pa they sank 11 mm, at 1e10 the robot bounced and
drove 0.21 m of the 0.50 m it drives in 1 s at full power, and 1e30 failed the contact solver
(one-off runs of the default scene, 2026-11-23)."""
RESOLUTION_HINT = Range(0.001, 0.02, unit="m")
"""The tyres' mesh size: at 1 mm the robot takes 2 s to build (finer grows fast: 1e-6 m took
2.8 GB and growing); coarser than 2 cm the tyre is a polygon (at 6 cm the robot sinks 2.2 mm
and drives 8% short, at 1 m it barely moves; one-off runs, 2026-11-23)."""
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

DRAKE_BOUNDS: dict[type, dict[str, object]] = {
    MultibodyPlantConfig: {
        "time_step": PLANT_TIME_STEP,
        "penetration_allowance": Range(0.0, 0.1, low_open=True, unit="m"),
        "stiction_tolerance": Range(0.0, 1.0, low_open=True, unit="m/s"),
        "sap_near_rigid_threshold": Range(0.0, 100.0),
        "contact_model": OneOf(("hydroelastic", "point", "hydroelastic_with_fallback")),
        "discrete_contact_approximation": OneOf(
            ("lagged", "similar", "sap"),
            "tamsi ignores the wheels' velocity-servo gains: the robot would not move"),
        "contact_surface_representation": OneOf(("polygon", "triangle")),
    },
    SimulatorConfig: {
        "integration_scheme": OneOf(tuple(GetIntegrationSchemes())),
        "max_step_size": Range(0.0, 1.0, low_open=True, unit="s"),
        "accuracy": Range(0.0, 1.0, low_open=True),
        "start_time": Range(0.0, DURATION.high, unit="s",
                            why="the clock of a plant step; negative froze the physics"),
        "target_realtime_rate": Range(0.0, 1000.0, why="0: as fast as possible"),
    },
    CameraConfig: {
        "width": Range(1, CAMERA_MAX_PIXELS, unit="pixels"),
        "height": Range(1, CAMERA_MAX_PIXELS, unit="pixels"),
        "center_x": Range(0.0, CAMERA_MAX_PIXELS, low_open=True, unit="pixels"),
        "center_y": Range(0.0, CAMERA_MAX_PIXELS, low_open=True, unit="pixels"),
        "clipping_near": Range(0.0, 1e3, low_open=True, unit="m"),
        "clipping_far": Range(0.0, 1e5, low_open=True, unit="m"),
        "z_near": Range(0.0, 1e3, low_open=True, unit="m"),
        "z_far": Range(0.0, 1e5, low_open=True, unit="m"),
        "fps": Range(0.0, CAMERA_MAX_FPS, low_open=True, unit="Hz"),
        "capture_offset": DURATION,
        "output_delay": Range(0.0, 1.0, high_open=True, unit="s"),
    },
    CameraConfig.FovDegrees: {
        "x": Range(0.0, 180.0, low_open=True, high_open=True, unit="deg"),
        "y": Range(0.0, 180.0, low_open=True, high_open=True, unit="deg"),
    },
    CameraConfig.FocalLength: {
        "x": Range(0.0, 1e6, low_open=True, unit="pixels"),
        "y": Range(0.0, 1e6, low_open=True, unit="pixels"),
    },
}
"""Bounds of the fields of Drake's config structs that the scenario holds."""
