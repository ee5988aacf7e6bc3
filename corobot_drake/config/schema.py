"""The scenario's schema: a typed description of a world and its robots.

In the style of Drake's `examples/hardware_sim`: a `Scenario` dataclass read with
`pydrake.common.yaml.yaml_load_typed`, with Drake's own config structs where they fit. Every
pose is Drake's `pydrake.common.schema.Transform` (`config/poses.py`). This module declares
the fields (and reads files' bytes, one line per problem: `ScenarioError`); `config/scenario.py`
loads a scenario through the one validation pass (`config/validate.py`), which reads this
module only: the schema imports neither.
"""


import dataclasses as dc
import math
import os
import stat
from pathlib import Path
from typing import Union

from pydrake.common.schema import Transform
from pydrake.multibody.contact_solvers import IcfSolverParameters
from pydrake.multibody.parsing import ModelDirective
from pydrake.multibody.plant import MultibodyPlantConfig
from pydrake.systems.analysis import SimulatorConfig

from corobot_drake import limits as lim
from corobot_drake.commands import (  # noqa: F401 (the scenario's commands, `sc.SetPower`)
    COMPLETING_COMMANDS,
    AllStop,
    Command,
    DriveDistance,
    Enable,
    RotateDegrees,
    SetPose,
    SetPower,
    SetSpeed,
    SetVelocity,
    Wait,
)
from corobot_drake.config.bounds import CENIC
from corobot_drake.limits import OneOf, Range, bounded
from corobot_drake.model.sdf import VISUALS, WheelContact
from corobot_drake.robots import ROBOTS, corobot
from corobot_drake.sensors.registry import KINDS

# --- shapes -----------------------------------------------------------------------------


@dc.dataclass
class Box:
    """Box with edge lengths (x, y, z), metres."""

    size: list[float] = bounded(lambda: [1.0, 1.0, 1.0], lim.SHAPE_SIZE, size=3)
    """m: the edge lengths along the body frame's x, y and z (the box centred on its origin)."""


@dc.dataclass
class Sphere:
    radius: float = bounded(0.5, lim.SHAPE_SIZE)
    """m: the sphere's radius (centred on the body frame's origin)."""


@dc.dataclass
class Cylinder:
    """Cylinder along its z axis."""

    radius: float = bounded(0.5, lim.SHAPE_SIZE)
    """m: the radius about the body frame's z axis."""
    length: float = bounded(1.0, lim.SHAPE_SIZE)
    """m: the length along z, centred on the origin."""


@dc.dataclass
class Capsule:
    """Capsule along its z axis (length excludes the end caps)."""

    radius: float = bounded(0.5, lim.SHAPE_SIZE)
    """m: the radius of the cylinder and of its two hemispherical caps."""
    length: float = bounded(1.0, lim.SHAPE_SIZE)
    """m: the cylinder's length along z, between the caps' centres."""


@dc.dataclass
class Ellipsoid:
    """Ellipsoid with semi-axes a, b, c along x, y, z."""

    a: float = bounded(0.5, lim.SHAPE_SIZE)
    """m: the semi-axis along the body frame's x."""
    b: float = bounded(0.5, lim.SHAPE_SIZE)
    """m: the semi-axis along y."""
    c: float = bounded(0.5, lim.SHAPE_SIZE)
    """m: the semi-axis along z."""


@dc.dataclass
class Mesh:
    """A mesh file: drawn as it is (OBJ, glTF or GLB), touching others through `collision`."""

    filename: str = ""
    """A path relative to the scenario file (an --override's: to the working directory), an
    absolute path or a `package://` URI (`package://corobot_drake/...`: the project's
    `models/`)."""
    scale: float = bounded(1.0, lim.MESH_SCALE)
    """Uniform scale from the file's units to metres."""
    collision: str = "convex_hull"
    """`convex_hull`: contact with the mesh's convex hull (compliant hydroelastic, or point
    contact when `hydroelastic_modulus` is 0); `mesh`: with the mesh's own surface, rigid
    hydroelastic (`hydroelastic_modulus` must be 0; a fixed body only): the one way Drake takes
    a concave surface into contact (its point contact uses the convex hull)."""


MESH_COLLISIONS = ("convex_hull", "mesh")
MESH_EXTENSIONS = (".obj", ".gltf", ".glb")
"""The mesh files a world body or a directives' model may use (any case); `config/mesh_files.py`
checks them. `collision: mesh` reads OBJ only (Drake's rigid hydroelastic mesh)."""

# typing.Union, not `|`: the YAML tags (!Box ...) are read from a Union's members.
Shape = Union[Box, Sphere, Cylinder, Capsule, Ellipsoid, Mesh]  # noqa: UP007

# --- world ------------------------------------------------------------------------------


GROUND_FRICTION = 0.5
"""The ground's Coulomb friction (the chapter's world)."""


@dc.dataclass
class Ground:
    """The ground: a rigid hydroelastic half-space at z = 0."""

    friction: float = bounded(GROUND_FRICTION, lim.FRICTION)
    """Coulomb friction (static = dynamic); a tyre's or a body's is combined with it
    (`World.model_friction`)."""
    color: list[float] = bounded(lambda: [0.45, 0.5, 0.4, 1.0], lim.COLOR, size=4)
    """RGBA in [0, 1], as the camera and Meshcat draw it."""


@dc.dataclass
class WorldBody:
    """A body of the world: free (it has mass and moves) or fixed (welded to the world)."""

    shape: Shape = dc.field(default_factory=Box)
    """Its geometry, one tag of `!Box`, `!Sphere`, `!Cylinder`, `!Capsule`, `!Ellipsoid`,
    `!Mesh`, in its frame B: drawn and touching alike."""
    mass: float = bounded(1.0, lim.MASS)
    """kg; ignored when fixed."""
    pose: Transform = dc.field(default_factory=Transform)
    """X_WB: the body's frame (its centre) in the world."""
    velocity: list[float] = bounded(lambda: [0.0] * 6, lim.SPATIAL_VELOCITY, size=6)
    """Initial spatial velocity in the world [wx, wy, wz, vx, vy, vz] (rad/s, m/s)."""
    fixed: bool = False
    """true: welded to the world at `pose` (it never moves); false: free."""
    friction: float = bounded(0.5, lim.FRICTION)
    """Coulomb friction (static = dynamic) of its surface."""
    hydroelastic_modulus: float = bounded(1.0e7, lim.HYDROELASTIC_MODULUS)
    """Pa: the body is compliant-hydroelastic (a cheap contact patch on the ground and with
    the tyres); 0 makes it rigid, touching everything by point contact: for a fixed body, or a
    free sphere (point contact holds a free body on the ground at one point: a face sinks)."""
    color: list[float] = bounded(lambda: [0.75, 0.55, 0.3, 1.0], lim.COLOR, size=4)
    """RGBA in [0, 1] (a mesh file with materials of its own is drawn in those)."""


def from_mrds_frame(v) -> list[float]:
    """A vector in MRDS's world frame (y up, a robot at rest facing -z) in this project's
    (z up, facing +x): x = -z_mrds, y = -x_mrds, z = y_mrds (a proper rotation)."""
    x, y, z = (float(c) for c in v)
    return [-z, -x, y]


BOOK_SUN_DIRECTION = from_mrds_frame((0.5, -0.75, 0.5))
"""[-0.5, -0.5, -0.75]: the book's sun, travelling down and towards the giant box's side."""


@dc.dataclass
class Sun:
    """A directional light: `direction` is the way the light travels, in the world frame
    (the book's by default); `intensity` 1 is full sunlight in the camera and Meshcat's
    default brightness for its directional light."""

    direction: list[float] = bounded(lambda: list(BOOK_SUN_DIRECTION), Range(-1e3, 1e3),
                                     size=3)
    """Not zero (checked with the scene)."""
    intensity: float = bounded(1.0, Range(0.0, 100.0))
    """1: brightness, relative to full sunlight (0: no sun)."""


@dc.dataclass
class World:
    """What the robots drive in: the ground, bodies, light and sky."""

    ground: Ground = dc.field(default_factory=Ground)
    """The ground plane z = 0."""
    bodies: dict[str, WorldBody] = dc.field(default_factory=dict)
    """Boxes, balls, meshes and such, by name (a name is also the body's model name)."""
    sun: Sun = dc.field(default_factory=Sun)
    """The directional light of the camera images and of Meshcat."""
    sky_color: list[float] = bounded(lambda: [0.53, 0.73, 0.92], lim.COLOR, size=3)
    """RGB in [0, 1]: the background of the camera images and of Meshcat."""
    model_friction: float | None = bounded(None, lim.FRICTION)
    """Coulomb friction (static = dynamic) of every collision geometry of the directives'
    models; None keeps their files' own, and Drake's parsers give 1.0 to a geometry whose file
    sets none (URDF, SDFormat and MJCF alike). Two surfaces in contact combine theirs as
    2 mu1 mu2 / (mu1 + mu2): on the ground's 0.5, 1.0 gives 0.67."""


# --- robots -----------------------------------------------------------------------------


WHEEL_HOLD_GAIN = 10.0
"""1/s: the default `Drive.hold_gain` (every robot's: the drive law's, not a robot's figure)."""


@dc.dataclass
class Drive:
    """Drive parameters of one robot; the defaults are the Corobot's (its robot file's)."""

    motor_torque_scaling: float = bounded(corobot.drive("motor_torque_scaling"), lim.AXLE_SPEED)
    """Axle speed (rad/s) at power 1."""
    slew_rate: float = bounded(corobot.drive("slew_rate"),
                               Range(0.0, 1e4, low_open=True, unit="rad/s^2"))
    """rad/s^2: how fast the commanded axle speed may change."""
    max_axle_speed: float = bounded(corobot.drive("max_axle_speed"), lim.AXLE_SPEED)
    """rad/s: set_speed clamps to +-this."""
    control_period: float = bounded(corobot.drive("control_period"), lim.PERIOD)
    """s: the drive controller's update period."""
    hold_gain: float = bounded(WHEEL_HOLD_GAIN, Range(
        0.0, 50.0, unit="1/s", why="0: no hold"))
    """1/s: at zero command each resting wheel is held at the angle it stopped at, as a geared
    motor's gearbox holds it (`systems.drive.DriveController`); 0 leaves the servo only damping
    and the robot rolls up to ~2 mm into a facet of its tyres' mesh (docs/tuning.md, "At rest")."""
    effective_wheel_radius: float = bounded(corobot.wheels("radius"), Range(
        0.0, 10.0, low_open=True, unit="m"))
    """m: the rolling radius the dead-reckoning odometry turns encoder ticks into distance with
    (`tools/calibrate_odometry.py` identifies it; default the nominal wheel radius)."""
    effective_track_width: float = bounded(corobot.wheels("track"),
                                           Range(0.0, 40.0, low_open=True, unit="m"))
    """m: the track width the odometry turns the left-right wheel difference into yaw with; a
    skid-steer robot's is wider than its geometric one (default the geometric track)."""


SEED_WINDOW = 6 / 60
"""s: the seed profile estimates the time left from the progress over this last stretch (the
book's 6 samples of 1/60 s); a saved command's `recent_progress` holds at most this much."""


PROFILES = ("closed_loop", "seed")


@dc.dataclass
class Motion:
    """How DriveDistance and RotateDegrees slow down, land and give up (`motion.py`)."""

    profile: str = bounded("closed_loop", OneOf(PROFILES))
    """`closed_loop`: speed from the measured distance/angle left, heading held while
    driving; `seed`: the book's (last 6 samples at 60 Hz, halve the speed when < 6 frames
    remain, stop when reached)."""
    stall_time: float = bounded(1.0, Range(0.0, 1e3, low_open=True, unit="s"))
    """s: a command that makes no progress for this long fails as `stalled`."""
    stall_distance: float = bounded(0.005, Range(0.0, 10.0, low_open=True, unit="m"))
    """m: progress a DriveDistance must make within `stall_time`."""
    stall_angle_deg: float = bounded(0.5, Range(0.0, 360.0, low_open=True, unit="deg"))
    """deg: progress a RotateDegrees must make within `stall_time`."""


def with_sensor_maps(cls):
    """Gives a robot's class one field per registered kind of sensor
    (`sensors.registry.KINDS`, in their order): `<kind.field>: dict[str, kind.config_type]`,
    its sensors by name, default `kind.defaults()` (the Corobot's own); e.g. `ir_sensors`
    (defaults `front` and `rear`, `{enabled: false}` removes one) and `cameras` (Drake's
    CameraConfig, default `front`; `{rgb: false}` removes one). A name the defaults lack
    starts as `kind.new_sensor(name)`; `X_PB.base_frame` names a link of the robot."""
    for kind in KINDS:
        cls.__annotations__[kind.field] = dict[str, kind.config_type]
        setattr(cls, kind.field, dc.field(default_factory=kind.defaults))
    return cls


@dc.dataclass
@with_sensor_maps
class Robot:
    """One robot: which (`robot`: the Corobot by default), where it starts, how it drives,
    its tyres, its script, and its sensors (a map by name per kind, `with_sensor_maps`). The
    defaults are the Corobot's; a robot of another kind starts from its robot file's
    (`robots.robot_defaults`)."""

    robot: str = "corobot"
    """Which robot: a shipped one (`robots.ROBOTS`: `corobot`, `burger`, `pioneer`) or a
    robot file's path
    (relative to the scenario file; `robots/file.py`). Its drive, tyres and sensors are the
    defaults of this robot's fields."""
    pose: Transform = dc.field(default_factory=Transform)
    """X_WB: the robot's base link in the world (the Corobot's `chassis`: its origin on the
    ground midway between the axles, +x forward): `{translation: [x, y, 0], rotation:
    !Rpy {deg: [0, 0, yaw]}}` stands it on the ground facing `yaw`."""
    drive: Drive = dc.field(default_factory=Drive)
    """The motors, their controller and the odometry's figures."""
    contact: WheelContact = dc.field(default_factory=WheelContact)
    """The tyres' contact and the motors' torque and servo gain."""
    visual: str = bounded("meshes", OneOf(VISUALS))
    """How the robot looks: `meshes` (the detailed model) or `boxes` (its collision shapes)."""
    commands: list[Command] = dc.field(default_factory=list)
    """The robot's script: commands run in order from the start (`!Wait` lets one run on),
    as the Python API's `Robot` methods issue them."""
    motion: Motion = dc.field(default_factory=Motion)
    """How the completing commands (DriveDistance, RotateDegrees) slow down and give up."""
    velocity: list[float] = bounded(lambda: [0.0] * 6, lim.SPATIAL_VELOCITY, size=6)
    """Initial chassis spatial velocity in the world [wx, wy, wz, vx, vy, vz] (rad/s, m/s)."""
    wheel_angles: list[float] = bounded(lambda: [0.0] * corobot.wheel_count(),
                                        Range(-1e6, 1e6, unit="rad"))
    """Initial axle angles (rad), one per wheel in the robot's wheel order
    (`RobotSpec.wheels`): the encoders start here."""
    wheel_speeds: list[float] = bounded(lambda: [0.0] * corobot.wheel_count(),
                                        lim.AXLE_SPEED_RANGE)
    """Initial axle speeds (rad/s, same order); the drive's commanded axle speeds start at the
    encoded wheels' (the first left and right, `RobotSpec.encoded`; the Corobot's front ones: a
    saved scene carries on without a jolt)."""
    axle_speed_command: list[float] = bounded(list, lim.AXLE_SPEED_RANGE)
    """The drive's initial commanded (slewed) axle speeds [left, right], rad/s; empty: the
    encoded wheels' `wheel_speeds`. A saved scene records them (they differ from the wheels'
    while the drive accelerates or brakes)."""
    wheel_hold_angles: list[float] = bounded(list, Range(-1e6, 1e6, unit="rad"))
    """The angles (rad, wheel order as `wheel_angles`) the drive holds the wheels at while
    they rest (`systems.drive.DriveController`); empty: their `wheel_angles`. A saved scene
    records them (a held wheel the ground has pushed is pulled back to its hold angle)."""
    odometry: list[float] = bounded(list, (lim.POSITION, lim.POSITION, lim.HEADING,
                                           lim.ENCODER_COUNT, lim.ENCODER_COUNT))
    """The dead-reckoned odometry's start (`systems.dead_reckoning`): [x, y, yaw] (m, m, rad),
    then optionally the encoded wheels' counts [left, right] (the Corobot's front ones) it
    last integrated
    (default: the counts at the start); empty: the true start pose. A saved scene records all
    five (the odometry has drifted from the true pose, and carries on from its last update)."""


def _default_plant_config() -> MultibodyPlantConfig:
    """A continuous plant, stepped by CENIC (`_default_simulator_config`); `lagged` is the
    SAP approximation a discrete plant gets (`SAP_PLANT`: the SAP family honours the wheels'
    servo gains)."""
    return MultibodyPlantConfig(
        time_step=0.0,
        discrete_contact_approximation="lagged",
        contact_model="hydroelastic_with_fallback",
    )


def _default_simulator_config() -> SimulatorConfig:
    """Drake's CENIC integrator at fixed 10 ms steps (docs/performance.md, "The integrator",
    says what it changes from SAP's discrete plant, `SAP_PLANT`)."""
    return SimulatorConfig(integration_scheme=CENIC, max_step_size=0.010,
                           use_error_control=False)


LINESEARCH_TOLERANCE = 1e-3
"""CENIC's exact line search stops within this (Drake's default 1e-8): each step still
converges to `min_tolerance`, so the robot moves by a fraction of a nanometre
(docs/performance.md, "CENIC's solver"), and a slipping robot's step takes 30% fewer
line-search iterations. From about 2e-2 the solver gives up on some steps (the gym's)."""


def _default_cenic_solver() -> IcfSolverParameters:
    """Drake's solver parameters but `LINESEARCH_TOLERANCE`."""
    return IcfSolverParameters(linesearch_tolerance=LINESEARCH_TOLERANCE)


def physics_step(plant_config: MultibodyPlantConfig, simulator_config: SimulatorConfig
                 ) -> float:
    """s: the physics' step: a discrete plant's `time_step`, or a continuous plant's (CENIC's)
    `max_step_size` (its every step with `use_error_control: false`, its longest with)."""
    return plant_config.time_step or simulator_config.max_step_size


def continuous_step(plant_config: MultibodyPlantConfig, simulator_config: SimulatorConfig
                    ) -> float:
    """s: a continuous plant's (CENIC's) step, to which its sensors, looks and stops keep (an
    event between its steps would split one and change the motion); 0 on a discrete plant."""
    return physics_step(plant_config, simulator_config) if plant_config.time_step == 0 else 0.0


SAP_PLANT = ("{plant_config: {time_step: %g}, "
             "simulator_config: {integration_scheme: runge_kutta3}}")
"""A scenario override (`SAP_PLANT % step`): a discrete plant stepped by SAP (the scenario's
`discrete_contact_approximation`, `lagged` by default) every `step` s."""
CENIC_PLANT = ("{plant_config: {time_step: 0}, simulator_config: {integration_scheme: cenic, "
               "max_step_size: %g, use_error_control: false}}")
"""A scenario override (`CENIC_PLANT % step`): a continuous plant stepped by Drake's CENIC
integrator at fixed `step` s (the default's kind; what it changes from SAP:
docs/performance.md, "The integrator")."""


@dc.dataclass
class Scenario:
    """Everything needed to build and run one simulation."""

    random_seed: int = 0
    """The seed every random source (sensor noise) mixes its own seed with: a run is
    repeated exactly from it."""
    simulation_duration: float = bounded(math.inf, lim.SIMULATION_DURATION)
    """s; the CLI's --duration overrides it (.inf: until stopped)."""
    plant_config: MultibodyPlantConfig = dc.field(default_factory=_default_plant_config)
    """The physics: a continuous plant by default (`time_step: 0`), hydroelastic contact
    with point contact for the rest."""
    simulator_config: SimulatorConfig = dc.field(default_factory=_default_simulator_config)
    """The integrator: CENIC at fixed 10 ms steps by default."""
    cenic_solver: IcfSolverParameters = dc.field(default_factory=_default_cenic_solver)
    """The solver of CENIC's steps (Drake's `IcfSolverParameters`; with `integration_scheme:
    cenic` only): Drake's, its line search stopped sooner (`_default_cenic_solver`). With
    `use_error_control: false` each step converges to `min_tolerance` (docs/performance.md,
    "CENIC's solver": what the tolerances cost and move, and why the bounds)."""
    world: World = dc.field(default_factory=World)
    """The ground, the bodies, the sun and the sky."""
    directives: list[ModelDirective] = dc.field(default_factory=list)
    """Models from SDFormat, URDF or MJCF files, as Drake's `ModelDirectives` (`add_model`,
    `add_weld`, `add_frame`, ...; `ProcessModelDirectives`). `file` is a `package://` URI
    (`package://corobot_drake/...`: the project's `models/`), an absolute `file:///` URI, or a
    `file://` URI relative to the scenario file."""
    robots: dict[str, Robot] = dc.field(default_factory=dict)
    """The robots, by name (a URL path segment, `/robots/<name>`, and the robot's model
    name in the plant)."""


# --- loading ----------------------------------------------------------------------------


class ScenarioError(Exception):
    """A scenario that cannot be used; `str()` is one line naming the file, line and field."""

    def __init__(self, source: str, field: str, message: str, line: int | None = None):
        where = f"{source}:{line}" if line is not None else source
        super().__init__(f"{where}: {field or '(top level)'}: {message}")
        self.source, self.field, self.line, self.message = source, field, line, message


def one_line(error: BaseException) -> str:
    """An exception's message as one line (its type's name when it has none)."""
    return (str(error).strip() or type(error).__name__).splitlines()[0]


MAX_FILE_BYTES = 256 << 10
"""A scenario or study file's largest size (256 KiB; the largest shipped is under 2 kB, a
saved scene of several robots ~10 kB, a world of 500 bodies ~60 kB); larger is refused
unread, so that a bad input ends within 2 s (`config/validate.py`, MAX_VALUES)."""


def read_text(path: str | Path, *, kind: str = "a scenario is a YAML file",
              max_bytes: int = MAX_FILE_BYTES) -> str:
    """A file's UTF-8 text (a scenario's, a study's, a log's: `kind` says what it should be);
    ScenarioError (one line) when it cannot be read, is not a regular file (a FIFO, a device:
    never waited on), is over `max_bytes` or not UTF-8."""
    data = read_bytes(path, kind=kind, max_bytes=max_bytes)
    return decode(str(path), data) if kind == "a scenario is a YAML file" else decode(
        str(path), data, f"{kind}, in UTF-8")


def read_bytes(path: str | Path, *, kind: str, max_bytes: int) -> bytes:
    """A regular file's bytes, at most `max_bytes` (`kind`: what the file should be, for the
    errors); ScenarioError (one line) for a file that cannot be read, is not a regular file
    (a FIFO, a device, `/dev/zero`: refused before any read, never waited on) or is larger."""
    source = str(path)
    try:
        # O_NONBLOCK: opening a FIFO with no writer returns at once (then refused below).
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except OSError as e:
        raise ScenarioError(source, "", f"cannot read the file ({e.strerror})") from None
    mode = os.fstat(fd).st_mode
    if not stat.S_ISREG(mode):
        os.close(fd)
        special = ("a directory" if stat.S_ISDIR(mode) else "a FIFO" if stat.S_ISFIFO(mode)
                   else "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode)
                   else "a socket" if stat.S_ISSOCK(mode) else "a special file")
        raise ScenarioError(source, "", f"cannot read {special}; {kind}")
    too_large = ScenarioError(source, "", f"the file is larger than {_size(max_bytes)}, the "
                              f"most {kind.split(' is ')[0]} may be")
    if os.fstat(fd).st_size > max_bytes:  # refused unread
        os.close(fd)
        raise too_large
    with os.fdopen(fd, "rb") as f:
        try:
            data = f.read(max_bytes + 1)
        except OSError as e:
            raise ScenarioError(source, "", f"cannot read the file ({e.strerror})") from None
    if len(data) > max_bytes:  # it grew since
        raise too_large
    return data


def _size(n: int) -> str:
    return f"{n >> 20} MiB" if n >= 1 << 20 else f"{n >> 10} KiB"


def decode(source: str, data: bytes, kind: str = "a scenario is UTF-8 YAML") -> str:
    """`data` as UTF-8 text; ScenarioError at the line of the first byte that is not."""
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        raise ScenarioError(source, "", f"not UTF-8 text (byte 0x{data[e.start]:02x}); "
                            f"{kind}", line) from None


def resolve_path(path: str, base: Path) -> str:
    """A world mesh's filename as an absolute path: relative ones against `base`, the
    scenario file's directory; `package://` URIs stay (resolved as the station builds)."""
    if not path or path.startswith("package://") or Path(path).is_absolute():
        return path
    return str((base / path).resolve())


def resolve_uri(uri: str, base: Path) -> str:
    """A directive's model URI for Drake: a `file://` URI with a relative path becomes the
    absolute `file:///...` against `base`; any other is left for Drake's parser."""
    if not uri.startswith("file://") or uri.startswith("file:///"):
        return uri
    return (base / uri[len("file://"):]).resolve().as_uri()


def resolve_paths(scenario: Scenario, base: Path) -> None:
    """Makes the scenario's relative file references absolute against `base` (in place)."""
    for body in scenario.world.bodies.values():
        if isinstance(body.shape, Mesh):
            body.shape.filename = resolve_path(body.shape.filename, base)
    for robot in scenario.robots.values():
        if robot.robot not in ROBOTS:  # a shipped name stays; a robot file's path: absolute
            robot.robot = resolve_path(robot.robot, base)
    for directive in scenario.directives:
        if directive.add_model is not None:
            directive.add_model.file = resolve_uri(directive.add_model.file, base)
