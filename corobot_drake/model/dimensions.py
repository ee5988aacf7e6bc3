"""The Corobot's CAD: its dimensions, masses and sensor mounts, what its model is generated from.

Model generation alone reads this module: `model/sdf.py` builds `models/corobot.sdf` from it,
`model/meshes.py` the meshes, and `model/robot_file.py` writes the figures the CAD fixes (the
wheels' radius, track and wheelbase, the IR sensors' and camera's mounts) into the Corobot's
robot file exactly (`tools/make_model.py`; a test keeps both in step). The simulator reads the
Corobot from that robot file and the model it names (`robots/corobot.py`, its `RobotSpec`),
as it reads any robot; the drive, the sensors' settings and the world are not the CAD's.

Every figure is SI (metres, kilograms). The original robot was specified in inches; the
conversion happens here, once. Positions are in the robot body frame ``chassis``: origin on
the ground midway between the axles, +x forward, +y left, +z up.
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
