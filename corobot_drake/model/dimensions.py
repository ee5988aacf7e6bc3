"""The Corobot's dimensions, masses and sensor mounts: what its model is generated from.

The Corobot is one robot of several (`corobot_drake/robots`): `model/sdf.py` builds its model
from these figures and its robot file (`models/corobot/robot.yaml`) states them exactly
(a test keeps the two in step); the station, the systems and the front ends read any robot's
figures from its `RobotSpec`, the Corobot's included. Only the Corobot's own defaults (its
sensors' mounts, the chapter's world) still come from here.

Every figure is SI (metres, kilograms). The original robot was specified in inches; the
conversion happens here, once. Positions are in the robot body frame ``chassis``: origin on
the ground plane midway between the axles, +x forward, +y left, +z up.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

INCH = 0.0254
"""Metres per inch."""


@dataclass(frozen=True)
class BoxPart:
    """A box-shaped part fixed to the chassis body.

    size: (length along x, width along y, height along z) in metres.
    center: box centre in the chassis frame, metres.
    """

    size: tuple[float, float, float]
    center: tuple[float, float, float]
    mass: float

    def inertia_diagonal(self) -> tuple[float, float, float]:
        """Solid-box principal moments about the box centre (kg m^2)."""
        lx, ly, lz = self.size
        k = self.mass / 12.0
        return (k * (ly**2 + lz**2), k * (lx**2 + lz**2), k * (lx**2 + ly**2))


TOTAL_BODY_MASS = 3.63
"""Chassis plus platform, kg (the wheels add WHEEL_MASS each)."""

CHASSIS = BoxPart(
    size=(8.5 * INCH, 5.85 * INCH, 2.5 * INCH),  # 0.2159 x 0.14859 x 0.0635
    center=(0.0, 0.0, 1.5 * INCH + 1.25 * INCH),  # bottom 0.0381 above ground
    mass=TOTAL_BODY_MASS / 2,
)
PLATFORM = BoxPart(
    size=(8.5 * INCH, 11.0 * INCH, 3.0 * INCH),  # 0.2159 x 0.2794 x 0.0762
    center=(0.0, 0.0, 5.75 * INCH + 1.5 * INCH),  # bottom 0.14605 above ground
    mass=TOTAL_BODY_MASS / 2,
)

WHEEL_RADIUS = 4.75 * INCH / 2  # 0.060325
WHEEL_WIDTH = 2.2 * INCH  # 0.05588
WHEEL_MASS = 0.1
WHEEL_HUB_RADIUS = 0.7 * WHEEL_RADIUS
"""Inner radius of the tyre (visual only)."""

HALF_WHEELBASE = 3.625 * INCH  # 0.092075: axle x = +-HALF_WHEELBASE
HALF_TRACK = 4.4 * INCH  # 0.11176: wheel-centre y = +-HALF_TRACK
TRACK = 2 * HALF_TRACK
"""DistanceBetweenWheels, 0.22352 m."""

WHEEL_NAMES = ("front_left", "front_right", "rear_left", "rear_right")
"""Wheel order used everywhere: actuators, desired state, drive state."""


def wheel_center(name: str) -> tuple[float, float, float]:
    """Centre of the named wheel in the chassis frame (metres)."""
    x = HALF_WHEELBASE if name.startswith("front") else -HALF_WHEELBASE
    y = HALF_TRACK if name.endswith("left") else -HALF_TRACK
    return (x, y, WHEEL_RADIUS)


def wheel_inertia_diagonal() -> tuple[float, float, float]:
    """Solid-cylinder moments (kg m^2) about the wheel centre, axle along y."""
    r, w, m = WHEEL_RADIUS, WHEEL_WIDTH, WHEEL_MASS
    radial = m * (3 * r**2 + w**2) / 12.0
    return (radial, m * r**2 / 2.0, radial)


@dataclass(frozen=True)
class SensorMount:
    """A sensor's position (chassis frame, metres) and the yaw (radians) of its look direction."""

    position: tuple[float, float, float]
    yaw: float


FRONT_IR = SensorMount(position=(4.25 * INCH, 0.0, CHASSIS.center[2]), yaw=0.0)
REAR_IR = SensorMount(position=(-4.25 * INCH, 0.0, CHASSIS.center[2]), yaw=math.pi)
CAMERA = SensorMount(position=(4.25 * INCH, 0.0, CHASSIS.center[2] - 0.01), yaw=0.0)
"""1 cm below the IR sensors on the front face: (0.10795, 0, 0.05985)."""
CAMERA_WIDTH = 320
CAMERA_HEIGHT = 240
CAMERA_FOV_Y_DEG = 30.0
CAMERA_FPS = 30.0
"""Frames per second of the robot camera."""
CAMERA_OUTPUT_DELAY = 0.03
"""s from a frame's capture to its output: a USB webcam's latency, just under one frame at
30 Hz (Drake's RgbdSensorAsync needs less than 1/fps). Rendering happens meanwhile on a worker
thread, so the simulation goes on during it."""

ENCODER_TICKS_PER_REVOLUTION = 600

IR_MAXIMUM_RANGE = 30 * INCH
"""m (0.762): an IR sensor's reading when nothing is within range."""
IR_DISPERSION_CONE_ANGLE_DEG = 8.0
IR_SAMPLES = 3
"""Rays per fan of an IR sensor's cross of rays."""

# Drive figures (defaults of the scenario's drive parameters).
MOTOR_TORQUE_SCALING_UNTUNED = 20.0
"""The untuned MotorTorqueScaling: axle rad/s at power 1 (~1.2 m/s top speed)."""
MOTOR_TORQUE_SCALING = 10.16
"""Tuned so full power gives the real Corobot's 2 ft/s top speed."""
TARGET_TOP_SPEED = 2 * 12 * INCH  # 0.6096 m/s
MAX_AXLE_SPEED = 20.0
"""set_speed clamps axle speed to +-this (rad/s)."""
SLEW_RATE = 30.0
"""Axle-speed slew limit, rad/s^2 (0.5 rad/s per 1/60 s frame)."""
CONTROL_PERIOD = 0.01
"""Drive controller update period, seconds: the plant's default 10 ms step, so the drive's
events fall on the plant's steps (the original ran at 60 Hz; its per-frame rules are expressed
per second: docs/performance.md)."""
WHEEL_HOLD_GAIN = 10.0
"""1/s: at zero command the drive pulls each resting wheel back to the angle it stopped at with
a velocity target of this times the angle error (docs/tuning.md, "At rest"): the velocity servo
alone only damps, and the tyres' hydroelastic mesh rolls a resting robot up to ~2 mm."""

# The chapter's world.
GIANT_BOX_SIZE = 2.0
GIANT_BOX_MASS = 100.0
GIANT_BOX_CENTER = (-(29 * INCH + GIANT_BOX_SIZE / 2), 0.0, GIANT_BOX_SIZE / 2)
GROUND_FRICTION = 0.5
