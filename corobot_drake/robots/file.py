"""The robot file: the YAML a user writes to bring a robot of their own (the schema).

    model: burger.urdf            # URDF, SDFormat or MJCF, relative to this file
    base: base_link               # the link the scenario's pose places (origin on the ground)
    wheels: {left: [wheel_left_joint], right: [wheel_right_joint]}
    drive: {top_speed: 0.22, slew_rate: 20, encoder_ticks_per_revolution: 4096}
    tyres: {friction: 0.8}        # any field left out: the project's tyre scaled to the wheel
    lidars: {scan: {X_PB: {base_frame: base_scan}}}

Loaded like a scenario (Drake's `yaml_load_typed` after the one schema walk of
`config/validate.py`): a bad field is one line `FILE:LINE: field: message`. What the model
says is measured by `robots/spec.py`; this module only declares the fields.
"""


import dataclasses as dc

from corobot_drake import limits as lim
from corobot_drake.limits import Range, bounded
from corobot_drake.sensors.registry import KINDS

LENGTH = Range(0.0, 100.0, low_open=True, unit="m")


@dc.dataclass
class Wheels:
    """The driven wheels: revolute joints by name, any number per side (one per side plus
    casters: differential drive; two or more: skid steer). Radius, track and wheelbase are
    measured from the wheels' collision shapes; a value stated here must agree with the
    measured one (within `spec.AGREEMENT`) and is then the one used (written exactly, it keeps
    a robot's figures to the bit when its model's numbers are rounded)."""

    left: list[str] = dc.field(default_factory=list)
    """The left side's driven wheels (+y of the right ones): their revolute joints' names in
    the model; the first one's encoder is the odometry's (`RobotSpec.encoded`)."""
    right: list[str] = dc.field(default_factory=list)
    """The right side's driven wheels (-y), as `left`."""
    radius: float | None = bounded(None, LENGTH)
    """m: the wheels' radius (all of them)."""
    track: float | None = bounded(None, LENGTH)
    """m: between the left wheels' mean centre and the right's."""
    wheelbase: float | None = bounded(None, Range(0.0, 100.0, unit="m"))
    """m: twice the root-mean-square distance of the wheels' centres from their mean along
    the robot's x (the front and rear axles' distance for a four-wheel robot; 0 for
    differential drive)."""


@dc.dataclass
class RobotDrive:
    """The motors and encoders: what the scenario's `drive:` starts from for this robot."""

    top_speed: float | None = bounded(None, Range(0.0, 100.0, low_open=True, unit="m/s"))
    """m/s of the rims at power 1; or `motor_torque_scaling` (one of them)."""
    motor_torque_scaling: float | None = bounded(None, lim.AXLE_SPEED)
    """Axle rad/s at power 1 (the Corobot's MotorTorqueScaling)."""
    max_axle_speed: float | None = bounded(None, lim.AXLE_SPEED)
    """rad/s a set-speed command is clamped to; default twice the axle speed at power 1."""
    slew_rate: float = bounded(30.0, Range(0.0, 1e4, low_open=True, unit="rad/s^2"))
    """rad/s^2: how fast the commanded axle speed may change (the motors' acceleration)."""
    torque_limit: float | None = bounded(None, Range(0.0, 1000.0, low_open=True, unit="N m"))
    """N m per axle: the motor's stall torque; default just above the wheels' traction limit
    (`spec.TRACTION_MARGIN`)."""
    encoder_ticks_per_revolution: int = bounded(600, Range(1, 1 << 24))
    """1: the wheel encoders' counts per turn of the wheel (the Corobot's 600)."""
    control_period: float = bounded(0.01, lim.PERIOD)
    """s: the drive controller's update period."""
    servo_damping: float | None = bounded(None, Range(0.0, 1000.0, low_open=True,
                                                      unit="N m s/rad"))
    """N m s/rad: the wheels' velocity servo gain; default the Corobot's scaled by mass."""


@dc.dataclass
class Tyres:
    """The hydroelastic tyres every wheel gets, whatever the model says about contact; a
    field left out is the project's tyre scaled to the wheel (`spec.default_contact`)."""

    friction: float | None = bounded(None, lim.FRICTION)
    """Coulomb friction (static = dynamic) of the tyres; the ground's is combined with it."""
    hydroelastic_modulus: float | None = bounded(None, lim.TYRE_MODULUS)
    """Pa: the tyres' stiffness: softer sinks further into the ground, with a larger contact
    patch."""
    resolution_hint: float | None = bounded(None, lim.RESOLUTION_HINT)
    """m: the size of the tyres' tetrahedral mesh: coarser makes a wheel a polygon."""
    hunt_crossley_dissipation: float | None = bounded(None, lim.DISSIPATION)
    """s/m: damps a tyre's bounce on the ground (Hunt-Crossley)."""


@dc.dataclass
class Casters:
    """Every collision shape but the wheels' that touches the ground at the start pose is a
    caster: it slides with this friction (low, so that the drive goes straight and turns in
    place as the wheels say)."""

    friction: float = bounded(0.05, lim.FRICTION)
    """Coulomb friction (static = dynamic) of every caster."""


@dc.dataclass
class OdometryTest:
    """The robot's measured odometry error: what `tools/calibrate_odometry.py --simulate
    --drive-test` prints for it (the same legs for every robot: 3 loops of seed 1, at power
    0.2), with the odometry at the calibrated radius and track. The ROS 2 node's odometry
    covariances grow from it (`systems.odometry_error`); left out, the worst of the shipped
    robots' is taken."""

    effective_wheel_radius: float | None = bounded(None, LENGTH)
    """m: the calibrated wheel radius the test's odometry ran with."""
    effective_track_width: float | None = bounded(None, LENGTH)
    """m: the calibrated track width the test's odometry ran with."""
    end_error: float | None = bounded(None, Range(0.0, 100.0, unit="m"))
    """m: the dead-reckoned position's distance from the true one at the test's end."""
    heading_error_deg: float | None = bounded(None, Range(0.0, 180.0, unit="deg"))
    """deg: the dead-reckoned heading's error at the test's end (its magnitude)."""


def with_robot_sensor_maps(cls):
    """One field per registered kind of sensor (`sensors.registry.KINDS`), as the scenario's
    robots have, but empty by default: a robot file lists its own sensors."""
    for kind in KINDS:
        cls.__annotations__[kind.field] = dict[str, kind.config_type]
        setattr(cls, kind.field, dc.field(default_factory=dict))
    return cls


@dc.dataclass
@with_robot_sensor_maps
class RobotFile:
    """A robot: its model, the link its pose places, its wheels, drive, tyres and sensors."""

    model: str = ""
    """The URDF, SDFormat or MJCF file (relative to the robot file, absolute, or a
    `package://` URI)."""
    base: str = ""
    """The link the scenario's pose places: its origin on the ground, +x forward, +z up."""
    wheels: Wheels = dc.field(default_factory=Wheels)
    """The driven wheels' joints, and their radius, track and wheelbase if stated."""
    drive: RobotDrive = dc.field(default_factory=RobotDrive)
    """The motors and encoders: the scenario's `drive:` and `contact:` start from them."""
    tyres: Tyres = dc.field(default_factory=Tyres)
    """The tyres' contact, put on every driven wheel."""
    casters: Casters = dc.field(default_factory=Casters)
    """What else touches the ground at the start pose, sliding."""
    odometry: OdometryTest = dc.field(default_factory=OdometryTest)
    """The robot's measured odometry error (`tools/calibrate_odometry.py`)."""
