"""What a robot file and its model say, measured once: `RobotSpec`.

`measure` parses the model into a scratch plant with Drake's parser, stands the base link's
origin on the ground, and reads what every module needs from the model's own shapes: the
wheels (their joints, sides, radius, centres), the track and wheelbase, the casters (other
collision shapes touching the ground), the mass, the links a sensor may ride on. A robot
file the model contradicts fails with one line at the robot file's field
(`RobotFileError`, a `ScenarioError`).
"""

from __future__ import annotations

import dataclasses as dc
import math
from pathlib import Path

import numpy as np

from corobot_drake.model.sdf import WheelContact

AGREEMENT = 0.02
"""A stated radius, track or wheelbase must be within 2% (or 1 mm) of the measured one."""
GROUND_TOLERANCE = 0.002
"""m: a shape whose lowest point at the start pose is within 2 mm of the ground touches it
(a wheel must; any other is a caster)."""
TRACTION_MARGIN = 1.07
"""The default torque limit over the wheels' traction limit mu m g r / n (the Corobot's
0.3 N m over its 0.28 N m): never the limit on flat ground, too little to climb a box."""
MAX_MODEL_BYTES = 8 << 20
"""A model file's largest size (8 MiB; the Corobot's is 9 kB)."""
MAX_MESH_BYTES = 32 << 20
"""A mesh's largest size (32 MiB): a larger collision mesh would take long to measure and
to give a contact surface."""

REFERENCE_WHEEL_RADIUS = 0.060325
"""m: the Corobot's wheel, which the project's tyre (`WheelContact`'s defaults) was tuned on."""
REFERENCE_MASS = 4.03
"""kg: the Corobot's, whose wheels' servo damping is `WheelContact`'s default."""

LEFT, RIGHT = 1, -1
"""A wheel's side: +1 left, -1 right (the sign of its centre's y in the base frame)."""


@dc.dataclass(frozen=True)
class Wheel:
    """One driven wheel: its revolute joint, side, child link and measured geometry."""

    joint: str
    side: int
    """LEFT (+1) or RIGHT (-1)."""
    link: str
    radius: float
    """m, of its collision shape."""
    width: float
    """m along the axle (0 for a sphere)."""
    center: tuple[float, float, float]
    """m, in the base frame at the start pose."""
    mass: float
    """kg of its link."""

    @property
    def short(self) -> str:
        """The joint's name without a trailing `_joint` or `_axle` (`front_left`)."""
        return short_name(self.joint)


def short_name(joint: str) -> str:
    """A wheel joint's name without a trailing `_joint` or `_axle` (`front_left`)."""
    for suffix in ("_joint", "_axle"):
        if joint.endswith(suffix):
            return joint[: -len(suffix)]
    return joint


@dc.dataclass(frozen=True)
class RobotSpec:
    """A robot as its robot file and model describe it: what the station, the systems and the
    front ends read instead of any one robot's constants.

    `wheels` are in the model's joint order, which is the order of the drive's actuators,
    its desired state, the wheel state, the per-wheel telemetry and `wheel_angles`."""

    kind: str
    """The shipped name (`corobot`) or the robot file's stem."""
    file: Path
    """The robot file."""
    model_file: Path
    """The model file, resolved."""
    model_name: str
    """The model's own name (the scenario's robot name replaces it in the plant)."""
    base: str
    wheels: tuple[Wheel, ...]
    wheel_radius: float
    track: float
    wheelbase: float
    mass: float
    """kg, the whole robot."""
    com: tuple[float, float, float]
    """m, the robot's centre of mass in the base frame at the start pose."""
    links: tuple[str, ...]
    """The model's links and frames a sensor can be mounted on (`X_PB.base_frame`)."""
    shapes: tuple = dc.field(compare=False)
    """(name `link/geometry`, Drake shape, pose in the base frame at the start pose) of every
    collision shape: what `config/placement.py` checks the start poses with."""
    casters: tuple[str, ...]
    """The collision geometries (`link/geometry`) that touch the ground besides the wheels."""
    caster_points: tuple[tuple[float, float], ...]
    """m: each caster's (x, y) in the base frame (its shape's origin), `casters` order."""
    caster_friction: float
    drive: object
    """The scenario `Drive` this robot starts with (`config.scenario.Drive`)."""
    contact: WheelContact
    """Its tyres and motors (the scenario's `contact:` starts from it)."""
    encoder_ticks_per_revolution: int
    odometry_test: object = dc.field(default=None, compare=False)
    """Its measured odometry error (`systems.odometry_error.DriveTest`, from the robot file's
    `odometry:`), None when its file states none."""
    sensors: dict = dc.field(default_factory=dict, compare=False)
    """{kind field: {name: config}}: the robot file's own sensors."""
    generated: bool = False
    """The model is the project's generated Corobot (`model/sdf.py`), built with the
    scenario's tyres and look (the file is its output at the defaults)."""

    @property
    def wheel_names(self) -> tuple[str, ...]:
        """The wheels' short names (`Wheel.short`), in `wheels` order."""
        return tuple(w.short for w in self.wheels)

    @property
    def wheel_joints(self) -> tuple[str, ...]:
        """The wheels' revolute joints' names, in `wheels` order."""
        return tuple(w.joint for w in self.wheels)

    @property
    def sides(self) -> tuple[int, ...]:
        """Each wheel's side (LEFT +1, RIGHT -1), in `wheels` order."""
        return tuple(w.side for w in self.wheels)

    @property
    def encoded(self) -> tuple[int, int]:
        """The indices of the wheels whose encoders the odometry reads: the first left and
        the first right wheel (the Corobot's front pair)."""
        return self.sides.index(LEFT), self.sides.index(RIGHT)

    @property
    def half_track(self) -> float:
        """m: half the track (the left wheels' mean y minus the right wheels', base frame)."""
        return self.track / 2

    @property
    def spin_yaw_per_rim_speed(self) -> float:
        """rad/s of yaw per m/s of rim speed (left back, right forward) on the spot, every
        wheel slipping on isotropic Coulomb friction under an equal load (`spin_yaw_rate`).
        Wheels all at +-a along and +-b across (the Corobot's, the Pioneer's four; a = 0: a
        differential drive) give b / (a^2 + b^2), computed so."""
        a, b = self.wheelbase / 2, self.track / 2
        if all(math.isclose(abs(x), a, rel_tol=1e-9, abs_tol=1e-12)
               and math.isclose(abs(y), b, rel_tol=1e-9) for x, y in self._lever_arms()):
            return b / (a**2 + b**2)
        return spin_yaw_rate(self._lever_arms(), self.sides)

    def _lever_arms(self) -> list[tuple[float, float]]:
        """m: each wheel's contact point (x, y) from the wheels' centre (the mean x; midway
        between the sides' mean y), about which a symmetric robot spins."""
        x0 = math.fsum(w.center[0] for w in self.wheels) / len(self.wheels)
        y0 = 0.5 * sum(math.fsum(w.center[1] for w in self.wheels if w.side == side)
                       / sum(w.side == side for w in self.wheels) for side in (LEFT, RIGHT))
        return [(w.center[0] - x0, w.center[1] - y0) for w in self.wheels]

    def top_speed(self) -> float:
        """m/s of the rims at power 1."""
        return self.drive.motor_torque_scaling * self.wheel_radius

    def wheel_center(self, index: int) -> tuple[float, float, float]:
        """m: the centre of wheel `index` (in `wheels` order) in the base frame at the start
        pose."""
        return self.wheels[index].center


def spin_yaw_rate(arms, sides) -> float:
    """rad/s of yaw per m/s of rim speed of a robot spinning on the spot, its wheels at
    `arms` ((x, y), m, from the point it turns about) on `sides` (LEFT, RIGHT) each slipping
    on isotropic Coulomb friction under one load N.

    Rims at -u (left) and +u (right) and a yaw rate w = k u: wheel i's contact point slides
    at s_i = u (-k y_i - r_i, k x_i) (r_i = +1 right, -1 left), so the ground pushes it with
    mu N along -s_i / |s_i|, whose moment about the turning point is
    mu N (-k (x_i^2 + y_i^2) - r_i y_i) / |s_i / u|. The spin is steady where the moments sum
    to nothing. That sum is minus the derivative in k of the friction's power, mu N sum |s_i|,
    which is convex in k: one root, between the smallest and the largest of the wheels' own
    k_i = -r_i y_i / (x_i^2 + y_i^2), found by bisection. Four wheels at +-a, +-b (each |s_i|
    alike): b / (a^2 + b^2); two wheels on the axle (x = 0): 1 / b. Wheels also at the middle
    (x = 0) drag the turn back toward 1 / b: three a side, equally spaced, spin faster than
    b / (a^2 + b^2) of their RMS half wheelbase a."""
    arms = [(float(x), float(y), -float(side)) for (x, y), side in zip(arms, sides, strict=True)]
    own = [-r * y / (x * x + y * y) for x, y, r in arms if x or y]
    low, high = min(own), max(own)

    def moment(k: float) -> float:  # a wheel on the axle not sliding (0 / 0) pushes nothing
        return math.fsum((-k * (x * x + y * y) - r * y) / (math.hypot(k * y + r, k * x) or 1.0)
                         for x, y, r in arms)

    for _ in range(200):  # to the last bit of a double, at most ~60 halvings
        middle = 0.5 * (low + high)
        if not low < middle < high:
            break
        low, high = (middle, high) if moment(middle) > 0 else (low, middle)
    return 0.5 * (low + high)


def default_contact(radius: float, mass: float, wheels: int, tyres, drive) -> WheelContact:
    """The project's tyre (`WheelContact`, the Corobot's) scaled to a wheel of `radius` on a
    robot of `mass` with `wheels` driven wheels; the robot file's `tyres` and `drive` fields
    (torque limit, servo damping) override."""
    base = WheelContact()
    friction = tyres.friction if tyres.friction is not None else base.friction
    scale = radius / REFERENCE_WHEEL_RADIUS
    hint = tyres.resolution_hint or min(0.02, max(0.001, base.resolution_hint * scale))
    load = mass * 9.81 / wheels  # N on each wheel at rest
    return WheelContact(
        friction=friction,
        hydroelastic_modulus=tyres.hydroelastic_modulus or base.hydroelastic_modulus,
        resolution_hint=hint,
        hunt_crossley_dissipation=(tyres.hunt_crossley_dissipation
                                   if tyres.hunt_crossley_dissipation is not None
                                   else base.hunt_crossley_dissipation),
        effort_limit=drive.torque_limit or TRACTION_MARGIN * friction * load * radius,
        # Scaled with the mass only: a first guess (the servo's time constant also goes
        # with r^2 / wheels); a robot file tunes it with `drive.servo_damping`.
        servo_damping=drive.servo_damping or base.servo_damping * mass / REFERENCE_MASS,
    )


def lowest_point(shape, X_BG) -> float:
    """m: the lowest z, in frame B, of `shape` posed at X_BG (its support along -z)."""
    from pydrake.geometry import Box, Capsule, Convex, Cylinder, Ellipsoid, Mesh, Sphere

    d = X_BG.rotation().matrix().T @ np.array([0.0, 0.0, -1.0])  # -z in the shape's frame
    if isinstance(shape, Sphere):
        reach = shape.radius()
    elif isinstance(shape, Box):
        reach = float(np.abs(d) @ (np.asarray(shape.size()) / 2))
    elif isinstance(shape, Cylinder):
        reach = shape.radius() * math.hypot(d[0], d[1]) + shape.length() / 2 * abs(d[2])
    elif isinstance(shape, Capsule):
        reach = shape.radius() + shape.length() / 2 * abs(d[2])
    elif isinstance(shape, Ellipsoid):
        reach = float(np.linalg.norm(np.array([shape.a(), shape.b(), shape.c()]) * d))
    elif isinstance(shape, Mesh | Convex):
        reach = float(np.max(shape.GetConvexHull().vertices().T @ d))
    else:  # a half-space or a point cloud: never a robot's part touching the ground
        return math.inf
    return float(X_BG.translation()[2]) - reach
