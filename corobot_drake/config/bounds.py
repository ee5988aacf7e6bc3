"""The bounds of the fields of Drake's own config structs that the scenario holds, and the
rules of fields whose allowed values depend on another field of their struct.

Every other range, and the `bounded` fields that declare theirs, is in `corobot_drake.limits`
(Drake-free, so the HTTP process reads it too); this is the part that needs Drake's types.
The loader (`config/validate.py`) checks these, and the scenario reference
(`docs/_ext/corobot_docs/scenario.py`) shows them: each rule's `text` and `problem` are one
declaration.
"""

import dataclasses as dc

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
    TIME_STEP,
    OneOf,
    Range,
)

CENIC = "cenic"
"""`SimulatorConfig.integration_scheme` of Drake's CENIC integrator."""

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
        "integration_scheme": OneOf(
            tuple(GetIntegrationSchemes()),
            f"{CENIC} with a continuous plant (plant_config.time_step 0), another with a "
            "discrete one"),
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


# --- rules that read another field of the struct -------------------------------------------


@dc.dataclass(frozen=True)
class When:
    """`bound` holds while the struct's field `field` is `equals` (besides the field's own
    bound); `why` is said after a problem."""

    field: str
    equals: object
    bound: Range
    why: str

    def text(self) -> str:
        return f"with {self.field} `{self.equals}`: {self.bound.text()}"

    def problem(self, struct, name: str) -> str | None:
        if getattr(struct, self.field) != self.equals:
            return None
        problem = self.bound.problem(getattr(struct, name))
        return f"{problem} ({self.why})" if problem else None


@dc.dataclass(frozen=True)
class WithinPeriod:
    """Less than one period of the struct's rate `rate` (Hz): a delay within a frame."""

    rate: str
    period: str

    def text(self) -> str:
        return f"less than one {self.period} (1/{self.rate})"

    def problem(self, struct, name: str) -> str | None:
        value, period = getattr(struct, name), 1.0 / getattr(struct, self.rate)
        if value < period:
            return None
        return (f"must be >= 0 and less than one {self.period} (1/{self.rate} = {period:.4g} s);"
                f" got {value:g}")


@dc.dataclass(frozen=True)
class FalseOnly:
    """A switch of Drake's that this project does not simulate: false only."""

    why: str

    def text(self) -> str:
        return f"`false` only ({self.why})"

    def problem(self, struct, name: str) -> str | None:
        return f"{self.why}; set it false" if getattr(struct, name) else None


COLOUR_ONLY = FalseOnly("only the colour image is simulated")

DRAKE_RULES: dict[type, dict[str, When | WithinPeriod | FalseOnly]] = {
    # Checked with the integrator (`validate.LayerChecks._integrator`): a later layer may
    # still switch the scheme.
    SimulatorConfig: {"max_step_size": When("integration_scheme", CENIC, TIME_STEP,
                                            "cenic's step")},
    # Checked on a camera that is on (`rgb: true`), in this order, before its kind's own
    # checks (`validate.LayerChecks._sensor`).
    CameraConfig: {"depth": COLOUR_ONLY, "label": COLOUR_ONLY,
                   "output_delay": WithinPeriod("fps", "frame")},
}
"""The fields of Drake's config structs whose allowed values depend on another field."""


def rule_problem(struct) -> tuple[str, str] | None:
    """(field, problem) of the first of the struct's `DRAKE_RULES` it breaks, or None."""
    for name, rule in DRAKE_RULES.get(type(struct), {}).items():
        problem = rule.problem(struct, name)
        if problem:
            return name, problem
    return None
