"""The allowed range of every argument a caller gives the running simulation: the Python API
(`simulation`, which raises ValueError naming the range), the HTTP contract
(`serving.schemas`, which answers 422 naming it) and a scenario file's commands
(`config/bounds.py` makes its `Range`s of these) read them here, so the three agree.

No Drake import here (the HTTP process and `serving.client` read it).
"""

from __future__ import annotations

import math
import reprlib

POWER = (-1.0, 1.0)
"""set_power: power per side."""
SPEED = (-5.0, 5.0)
"""set_speed: rim speed per side, m/s (8x the robot's top speed; the drive then clamps the
axle speed to its maximum)."""
LINEAR = (-5.0, 5.0)
"""set_velocity: chassis speed, m/s (the drive scales both sides down past the max axle
speed)."""
ANGULAR = (-50.0, 50.0)
"""set_velocity: yaw rate, rad/s (positive: left)."""
DRIVE_POWER = (0.0, 1.0)
"""drive_distance / rotate_degrees: power in (0, 1] (the lower end excluded)."""
DISTANCE = (-100.0, 100.0)
"""drive_distance: m (negative: backwards)."""
DEGREES = (-3600.0, 3600.0)
"""rotate_degrees: degrees (positive: left)."""
POSITION_LIMIT = 1.0e4
"""m: every position's coordinates within +-10 km of the origin, in a scenario or set_pose
(float steps there are ~2e-12 m, far below contact's scale; further, the world stops being a
place)."""
POSITION = (-POSITION_LIMIT, POSITION_LIMIT)
"""set_pose: x and y, m."""
YAW_DEG = (-3600.0, 3600.0)
"""set_pose: heading, degrees."""

WORKERS = (1, 1024)
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
    allowed = _describe(low, high, low_open, finite)
    # Not a number: a bool (True is not a power), a string, an array (even of one element:
    # numpy would make it a float, hiding a caller's mix-up).
    if isinstance(value, bool) or getattr(value, "ndim", 0) != 0 or (
            not isinstance(value, int | float) and not hasattr(value, "__float__")):
        raise ValueError(f"{name} must be {allowed}, got {reprlib.repr(value)}")
    try:
        x = shown = float(value)
    except OverflowError:  # an int beyond any float: outside every finite range
        x, shown = (math.inf if value > 0 else -math.inf), reprlib.repr(value)
    inside = (low < x if low_open else low <= x) and x <= high
    if not inside or (finite and not math.isfinite(x)):
        raise ValueError(f"{name} must be {allowed}, got {shown}")
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
