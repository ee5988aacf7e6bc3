"""The bounds of the fields of Drake's own config structs that the scenario holds.

Every other range, and the `bounded` fields that declare theirs, is in `corobot_drake.limits`
(Drake-free, so the HTTP process reads it too); this is the part that needs Drake's types.
"""

from pydrake.geometry import (
    LightParameter,
    RenderEngineGlParams,
    RenderEngineVtkParams,
    SsaoParameter,
)
from pydrake.multibody.contact_solvers import IcfSolverParameters
from pydrake.multibody.plant import MultibodyPlantConfig
from pydrake.systems.analysis import GetIntegrationSchemes, SimulatorConfig
from pydrake.systems.sensors import CameraConfig

from corobot_drake.limits import (
    CAMERA_MAX_FPS,
    CAMERA_MAX_PIXELS,
    DURATION,
    PLANT_TIME_STEP,
    OneOf,
    Range,
)

SHADOW_MAP_SIZE = Range(1, CAMERA_MAX_PIXELS, unit="pixels",
                        why="a shadow map's side (Drake's default 256)")

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
    IcfSolverParameters: {  # docs/performance.md, "CENIC's solver": what each bound keeps off
        "max_iterations": Range(1, 10_000, why="Newton iterations a step may take"),
        "min_tolerance": Range(0.0, 1e-5, low_open=True,
                               why="1e-5 moves the robot 0.4 mm in 8 s; 1e-2 tilts it at rest"),
        "hessian_reuse_target_iterations": Range(1, 10_000),
        "max_linesearch_iterations": Range(20, 10_000,
                                           why="8 gave up on a step of the gym's"),
        "linesearch_tolerance": Range(1e-14, 5e-3,
                                      why="2e-2 gave up on steps of the gym's; 1e-18 on all"),
        "alpha_max": Range(1.0, 10.0, why="a Newton step cut short: 1e-9 froze the robot"),
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
    # A camera's `renderer_class` may be a renderer's parameters (`sensors/camera.py`).
    RenderEngineVtkParams: {
        "exposure": Range(0.0, 100.0, low_open=True,
                          why="the environment map's tone-mapping exposure"),
        "shadow_map_size": SHADOW_MAP_SIZE,
    },
    RenderEngineGlParams: {"shadow_map_size": SHADOW_MAP_SIZE},
    LightParameter: {
        "intensity": Range(0.0, 1e3, why="a light's brightness (1: Drake's default)"),
        "cone_angle": Range(0.0, 90.0, unit="deg", why="a spot light's half angle"),
    },
    SsaoParameter: {
        "radius": Range(0.0, 100.0, low_open=True, unit="m"),
        "bias": Range(0.0, 1.0, unit="m"),
        "sample_count": Range(1, 1024, why="samples a pixel"),
        "intensity_scale": Range(0.0, 100.0),
        "intensity_shift": Range(-1.0, 1.0, why="added to an occlusion factor in [0, 1]"),
    },
}
"""Bounds of the fields of Drake's config structs that the scenario holds."""
