"""What each field of Drake's config structs in the scenario does in this project, in its own
words (Drake's docstrings speak of LCM and C++); the scenario reference
(`docs/_ext/corobot_docs/scenario.py`) shows these, as the dataclasses' field docstrings.

Each text opens with its unit when it has one (`m: ...`, `1: ...` for a dimensionless
number); a field this project accepts but does not read says `Not read` and why. The key ""
is the struct's own line. Their bounds and rules: `config/bounds.py`.
"""

from pydrake.geometry import (
    LightParameter,
    RenderEngineGlParams,
    RenderEngineVtkParams,
    SsaoParameter,
)
from pydrake.multibody.contact_solvers import IcfSolverParameters
from pydrake.multibody.plant import MultibodyPlantConfig
from pydrake.systems.analysis import SimulatorConfig
from pydrake.systems.sensors import CameraConfig

NOT_READ = "Not read"
"""How the text of a field the loader accepts and nothing reads opens."""

_LIGHTS = "The lights (none: one directional light from the camera)."
_SHADOWS = "Whether the lights that can cast shadows do."
_SHADOW_MAP = "pixels: the side of every shadow-casting light's shadow map."

DRAKE_DOCS: dict[type, dict[str, str]] = {
    MultibodyPlantConfig: {
        "": "The plant: its step and how bodies touch (Drake's `AddMultibodyPlant` reads "
            "every field).",
        "time_step": "s: 0, a continuous plant that `simulator_config` steps (CENIC, the "
                     "default); more, a discrete plant that SAP steps every `time_step` "
                     "(docs/performance.md, \"The integrator\").",
        "use_sampled_output_ports": "A discrete plant's outputs report its last step instead "
                                    "of being computed from the current state; a continuous "
                                    "plant ignores it.",
        "penetration_allowance": "m: the penetration point contact's stiffness is chosen for "
                                 "(rigid world bodies, and the point pairs of "
                                 "`hydroelastic_with_fallback`).",
        "stiction_tolerance": "m/s: the sliding speed under which the regularized friction "
                              "counts a contact as sticking.",
        "contact_model": "How bodies touch: `hydroelastic_with_fallback` (hydroelastic where "
                         "both bodies are, point contact otherwise), `hydroelastic` or `point`.",
        "discrete_contact_approximation": "The SAP model a discrete plant solves contact with "
                                          "(`lagged`, the default).",
        "sap_near_rigid_threshold": "1: SAP's near-rigid threshold: a contact stiffer than "
                                    "SAP handles robustly at the step is softened to it (0: "
                                    "never).",
        "contact_surface_representation": "Hydroelastic contact surfaces as `polygon`s or "
                                          "`triangle`s.",
        "adjacent_bodies_collision_filters": "Whether bodies joined by a joint are kept from "
                                             "colliding with each other.",
    },
    SimulatorConfig: {
        "": "The simulator and its integrator (Drake's `ApplySimulatorConfig` reads every "
            "field).",
        "integration_scheme": "The integrator: `cenic` (the default) steps a continuous plant; "
                              "a discrete plant (SAP) takes another, e.g. `runge_kutta3` "
                              "(`schema.SAP_PLANT`).",
        "max_step_size": "s: the integrator's step: each step with `use_error_control: "
                         "false`, the longest with; `cenic`'s is the physics' step.",
        "accuracy": "1: the relative accuracy the integrator's error control aims at "
                    "(`use_error_control: true` only).",
        "use_error_control": "false: fixed steps of `max_step_size` (the default); true: "
                             "steps sized for `accuracy`, at most `max_step_size`.",
        "start_time": "s: the simulated clock at the start (a saved scene writes its time "
                      "here).",
        "target_realtime_rate": "1: simulated s per wall-clock s the run is paced to (0: as "
                                "fast as it can); a run with Meshcat or a live front end "
                                "sets its own pace.",
    },
    IcfSolverParameters: {
        "": "The solver of each CENIC step (Newton's method with an exact line search).",
        "max_iterations": "1: the Newton iterations a step may take; beyond, the run stops "
                          "with one line naming `cenic_solver`.",
        "min_tolerance": "1: the relative tolerance each step's Newton solve converges to.",
        "enable_hessian_reuse": "Whether a Hessian's factorization is reused across iterations "
                                "and steps (faster).",
        "hessian_reuse_target_iterations": "1: with Hessian reuse, the iterations a step aims "
                                           "to converge within before the Hessian is "
                                           "factorized again.",
        "use_dense_algebra": "Dense (LDLT) instead of sparse algebra for the Newton direction "
                             "(for debugging: much slower).",
        "max_linesearch_iterations": "1: the iterations the exact line search may take.",
        "linesearch_tolerance": "1: the relative tolerance the exact line search stops at "
                                "(`schema.LINESEARCH_TOLERANCE`).",
        "alpha_max": "1: the longest line-search step, in Newton steps.",
        "print_solver_stats": "Prints the solver's statistics at each iteration (debugging).",
    },
    CameraConfig: {
        "": "One camera on a robot, named by its map key: its colour image, rendered by the "
            "engine its `renderer_name` names; the fields Drake reads to publish on LCM are "
            "accepted and not read.",
        "width": "pixels: the image's width.",
        "height": "pixels: the image's height.",
        "focal": "The lens: `!FovDegrees {y: 30}` (field of view, deg) or `!FocalLength {x, "
                 "y}` (pixels).",
        "center_x": "pixels: the principal point's x, from the image's left edge; null: the "
                    "image's centre.",
        "center_y": "pixels: the principal point's y, from the image's top edge; null: the "
                    "image's centre.",
        "clipping_near": "m: from the camera, nearer is not drawn.",
        "clipping_far": "m: from the camera, farther is not drawn; beyond `clipping_near`.",
        "z_near": "m: the depth camera's nearest distance: no depth image is simulated, but "
                  "it must be below `z_far`.",
        "z_far": "m: the depth camera's farthest distance (no depth image is simulated).",
        "X_PB": "X_PB: the camera body frame B in `base_frame` (a link of the robot, "
                "`chassis` by default; empty: the world).",
        "X_BC": "X_BC: the colour sensor's frame C in B, Drake's camera axes (+z forward, "
                "+x right, +y down): the image is taken from C.",
        "X_BD": "X_BD: the depth sensor's frame in B (no depth image is simulated).",
        "renderer_name": "The render engine the camera draws with: cameras with one name "
                         "share one engine (`corobot_camera`, the robots' cameras').",
        "renderer_class": "The engine made for `renderer_name`: `RenderEngineGl`, "
                          "`RenderEngineVtk`, or either's parameters (their lights and "
                          "background instead of the sun and the sky); empty: GL with an X "
                          "display, else VTK.",
        "background": f"{NOT_READ}: the image's background is the world's `sky_color`.",
        "name": f"{NOT_READ}: the map key names the camera (a saved scene writes it here).",
        "fps": "Hz: frames per second, captured at `capture_offset` + k / `fps`.",
        "capture_offset": "s: the time of the first capture (the default keeps captures off "
                          "the plant's steps: `config.sensors.CAPTURE_OFFSET`).",
        "output_delay": "s: a frame is out this long after its capture (not with "
                        "`RenderEngineVtk`: frames come without delay).",
        "rgb": "The colour image: false turns the camera off (a default camera stays in the "
               "map otherwise).",
        "depth": "A depth image: not simulated.",
        "label": "A label image: not simulated.",
        "show_rgb": "Drake shows each rendered frame in a window of its own (needs a "
                    "display).",
        "do_compress": f"{NOT_READ}: how Drake compresses the images it publishes on LCM "
                       "(this project publishes none).",
        "lcm_bus": f"{NOT_READ}: the LCM bus Drake publishes images on (this project "
                   "publishes none).",
    },
    CameraConfig.FocalLength: {
        "": "The focal lengths, in pixels.",
        "x": "pixels: along the image's x (its width); null: `y`'s.",
        "y": "pixels: along the image's y (its height); null: `x`'s.",
    },
    CameraConfig.FovDegrees: {
        "": "The fields of view, in degrees.",
        "x": "deg: across the image's width; null: from `y` and the image's aspect.",
        "y": "deg: across the image's height; null: from `x` and the image's aspect.",
    },
    RenderEngineVtkParams: {
        "": "A VTK engine's parameters, used as given: its lights and background instead of "
            "the world's sun and sky.",
        "default_diffuse": "1: RGBA in [0, 1] of a geometry whose model gives none; null: "
                           "Drake's.",
        "default_clear_color": "1: RGB in [0, 1], the background.",
        "lights": _LIGHTS,
        "environment_map": "An image lighting the scene (physically based rendering).",
        "exposure": "1: the environment map's tone-mapping exposure; null: Drake's.",
        "ssao": "Screen-space ambient occlusion; null: none.",
        "cast_shadows": _SHADOWS,
        "shadow_map_size": _SHADOW_MAP,
        "force_to_pbr": "Physically based rendering even without an environment map (else "
                        "Phong shading, unless a material needs it).",
        "gltf_extensions": "Settings of glTF extensions, by the extension's name.",
        "backend": "The graphics library, `GLX` (X display) or `EGL` (headless); empty: GLX "
                   "with an X display, else EGL.",
    },
    RenderEngineGlParams: {
        "": "A GL engine's parameters, used as given: its lights and background instead of "
            "the world's sun and sky.",
        "default_diffuse": "1: RGBA in [0, 1] of a geometry whose model gives none.",
        "default_clear_color": "1: RGBA in [0, 1], the background.",
        "lights": _LIGHTS,
        "cast_shadows": _SHADOWS,
        "shadow_map_size": _SHADOW_MAP,
    },
    LightParameter: {
        "": "One light of a render engine.",
        "type": "`point`, `spot` or `directional`.",
        "color": "1: RGBA in [0, 1], the light's colour.",
        "attenuation_values": "1, 1/m, 1/m^2: a point or spot light's [constant, linear, "
                              "quadratic] falloff with distance.",
        "position": "m: a point or spot light's position in `frame`.",
        "frame": "`world` or `camera`: the frame of `position` and `direction`.",
        "intensity": "1: the light's brightness.",
        "direction": "1: the way a spot or directional light shines, in `frame`.",
        "cone_angle": "deg: a spot light's half angle.",
    },
    SsaoParameter: {
        "": "Screen-space ambient occlusion: creases and corners darkened.",
        "radius": "m: the radius around a point within which geometry occludes it.",
        "bias": "m: the depth offset that keeps a surface from occluding itself.",
        "sample_count": "1: samples per pixel.",
        "intensity_scale": "1: scales the occlusion.",
        "intensity_shift": "1: added to the occlusion.",
        "blur": "Whether the occlusion is blurred (smoother).",
    },
}
"""{struct: {field: the project's words}} for each Drake struct the scenario reference lists."""
