"""The sensors' configuration: each robot's sensors, a typed map per kind, as the scenario
holds them.

Each registered kind (`sensors/registry.KINDS`) gives the scenario's `Robot` its map:
`robots.<name>.ir_sensors.<sensor>` (`IrSensorConfig`) and `robots.<name>.cameras.<camera>`
(Drake's `CameraConfig`, as Drake's hardware_sim holds its `cameras:`). The map key names the
sensor (its systems, ports, topics and URLs); a `CameraConfig.name` is not read. A key the
defaults lack starts as the Corobot's own sensor of that kind (`SensorKind.new_sensor`: a
second camera is the Corobot's camera until its fields say otherwise).

Every sensor is mounted the same way, by Drake's `pydrake.common.schema.Transform` `X_PB`: the
sensor's pose in the frame `X_PB.base_frame` (a link of its robot, `chassis` by default; a
scoped name `model::link` for another model's link; empty for the world). The sensor frame
of an IR sensor looks along its +x; a camera's is Drake's (+z forward, +x right, +y down).
The values are checked by the loader (`config/validate.py`), once; the systems trust them.
"""

import copy
import dataclasses as dc
import functools

from pydrake.common.schema import Transform
from pydrake.common.yaml import yaml_load_typed
from pydrake.systems.sensors import CameraConfig

from corobot_drake.config.poses import mount
from corobot_drake.limits import RATE, OneOf, Range, bounded
from corobot_drake.model.ir_models import MODELS as IR_MODELS
from corobot_drake.robots import corobot

# --- IR distance sensors (the scenario's `robots.<name>.ir_sensors.<sensor>`) ----------------

_IR = corobot.sensor("ir_sensors", "front")
"""The Corobot's front IR sensor (its robot file's): an IR sensor's defaults."""


@dc.dataclass
class IrSensorConfig:
    """One IR distance sensor on a robot."""

    X_PB: Transform = dc.field(
        default_factory=lambda: mount(*corobot.mount_of("ir_sensors", "front")))
    """The sensor frame S (looking along its +x) in `base_frame` (default `chassis`: origin
    on the ground midway between the axles, +x forward), as the camera's `X_PB`."""
    samples: int = bounded(_IR["samples"], Range(2, 64, why="rays per fan"))
    """Rays per fan of the cross (one horizontal fan, one vertical), at least 2."""
    dispersion_cone_angle: float = bounded(_IR["dispersion_cone_angle"],
                                           Range(0.0, 180.0, high_open=True, unit="deg"))
    """Degrees: each fan spreads its rays evenly over this angle."""
    maximum_range: float = bounded(_IR["maximum_range"],
                                   Range(0.0, 100.0, low_open=True, unit="m"))
    """m: the reading when nothing is hit (0.762 m)."""
    scan_rate_hz: float = bounded(20.0, RATE)
    """Scans per second (a periodic discrete update, independent of the physics step)."""
    model: str = bounded("ideal", OneOf(IR_MODELS))
    """Output model: `ideal` (the book's) or `sharp_gp2d12` (datasheet voltage, ADC, noise)."""
    change_threshold: float = bounded(1e-4, Range(0.0, 100.0, unit="m"))
    """m: `changed` is set when the reading moves by more than this from the previous scan
    (a robot standing still creeps by nanometres; subscribers want real changes)."""
    noise_std: float = bounded(0.01, Range(0.0, 10.0, unit="V"))
    """V: Gaussian noise on the sharp_gp2d12 voltage (0: none)."""
    noise_seed: int = 0
    """Mixed with the scenario's random_seed and the robot and sensor names."""
    enabled: bool = True
    """False: no sensor (a default sensor can't otherwise be removed from the mapping)."""


def default_ir_sensors() -> dict[str, IrSensorConfig]:
    """The Corobot's two sensors, as its robot file says: `front` looking forward, `rear`
    back."""
    return copy.deepcopy(_corobot_sensors("ir_sensors", IrSensorConfig))


# --- the cameras (the scenario's `robots.<name>.cameras.<camera>`, Drake's CameraConfig) -----

FRONT_CAMERA = "front"
"""The Corobot's own camera, the one every robot has by default. Its front ends keep
the unqualified names (`/camera/...` topics, `/robots/<robot>/camera` routes, frames saved in
`<dir>/<robot>/`); any other camera's carry its name (`camera_names`)."""

ENGINES = ("RenderEngineGl", "RenderEngineVtk")
"""The render engines a camera can use, the faster here first."""

RENDERERS = ("", *ENGINES)
"""`CameraConfig.renderer_class` names this project builds ("": the faster one available)."""

RENDERER_NAME = "corobot_camera"
"""The default `renderer_name` of the robots' cameras (one engine for all of them)."""

CAMERA_ROTATION_RPY_DEG = (-90.0, 0.0, -90.0)
"""Drake camera axes (+z forward, +x right, +y down) looking along the body's +x, level."""

CAPTURE_OFFSET = 0.0005
"""s: the default camera captures 0.5 ms past each 1/30 s tick, so that with plant steps of
10, 5, 2 or 1 ms its capture and output events never fall within rounding distance of a
step. Drake computes a periodic event's next time as offset + k * period, rounding
(t - offset) / period up, so an event a few ulps after another stop can be skipped: a 10 Hz
camera with a 30 ms delay captured at 0.30000000000000004 s, a plant step stopped at 0.33,
and the output at 0.33000000000000007 never came (its frame was lost)."""


def default_camera_config(name: str = FRONT_CAMERA) -> CameraConfig:
    """The Corobot's camera, as its robot file says (320 x 240, 30 deg vertical fov, 30 Hz,
    on the chassis' front face looking forward); every robot camera renders with one engine
    (`RENDERER_NAME`). `name`: its map key (kept in `CameraConfig.name` for a reader of the
    YAML; the key names the camera)."""
    config = copy.deepcopy(_corobot_sensors("cameras", CameraConfig)[FRONT_CAMERA])
    config.name = name
    return config


@functools.cache
def _corobot_sensors(field: str, config_type) -> dict:
    """{name: config} of one kind of sensor in the Corobot's robot file (read once; copy a
    config before changing it)."""
    schema = dc.make_dataclass("CorobotSensors", [
        (field, dict[str, config_type], dc.field(default_factory=dict))])
    loaded = yaml_load_typed(schema=schema, filename=str(corobot.FILE),
                             allow_yaml_with_no_schema=True)
    return getattr(loaded, field)


def default_cameras() -> dict[str, CameraConfig]:
    """The Corobot's one camera, `front` (`{rgb: false}` turns it off)."""
    return {FRONT_CAMERA: default_camera_config()}


def camera_names(camera: str) -> tuple[str, str]:
    """(topic part, frame part) of a camera's front-end names: `camera` for the front camera,
    `camera/<name>` and `camera_<name>` for another (topics `/camera/<name>/image_raw`, frames
    `camera_<name>_optical_frame`)."""
    if camera == FRONT_CAMERA:
        return "camera", "camera"
    return f"camera/{camera}", f"camera_{camera}"
