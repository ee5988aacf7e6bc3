"""The robot's front camera: Drake's `CameraConfig` in the scenario, rendered by VTK headless.

Each robot's `camera` (a `pydrake.systems.sensors.CameraConfig`, the scenario field
`robots.<name>.camera`) becomes, in the diagram:

- `<robot>.camera`: an `RgbdSensor` on the chassis (colour only; it renders when asked),
- `<robot>.camera_hold`: `CameraHold`, which asks for one frame at `fps` (and one at
  initialization) and holds it; its output is exported as `<robot>.camera.rgb_image`
  (ImageRgba8U) and `<robot>.camera.image_time` (s), the latest frame for any other system,
- with `save_dir`, `<robot>.camera_saver`: `CameraFrameSaver`, writing that frame as numbered
  PNG files `<save_dir>/<robot>/frame_000000.png`, ... at its own rate.

This is `ApplyCameraConfig` without its LCM publisher and with a colour-only hold: Drake's
`RgbdSensorDiscrete` also renders a depth image every frame (twice the cost), and
`RgbdSensorAsync` (what `ApplyCameraConfig` picks when `output_delay > 0`) is documented as
unsafe with VTK; here it failed with "Unable to eglMakeCurrent" from its worker thread.

The renderer is VTK with the scenario's sun as a directional light in the world frame, a dim
fill light from the camera (the sky's scattered light, so faces turned from the sun are shaded,
not black) and the sky colour as background. Cameras of all robots share it.

A robot without a camera: `camera: {rgb: false}` (Drake's own convention: no image, no sensor).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from pydrake.common.schema import Rotation, Transform
from pydrake.common.value import AbstractValue
from pydrake.geometry import (
    LightParameter,
    MakeRenderEngineVtk,
    RenderEngineVtkParams,
    Rgba,
)
from pydrake.math import RigidTransform
from pydrake.multibody.parsing import GetScopedFrameByName
from pydrake.systems.framework import LeafSystem
from pydrake.systems.sensors import CameraConfig, ImageRgba8U, RgbdSensor

from corobot_drake import dimensions as dim

RENDERER_NAME = "corobot_camera"
"""The default `renderer_name` of the robots' cameras (one VTK engine for all of them)."""

FILL_INTENSITY = 0.5
"""The fill light (from the camera, the sky's scattered light); the sun is the scenario's."""

CAMERA_ROTATION_RPY_DEG = (-90.0, 0.0, -90.0)
"""Drake camera axes (+z forward, +x right, +y down) looking along the body's +x, level."""

SAVE_OFFSET = 1e-6
"""s after each capture time at which the saver writes: a publish event at the capture time
itself would run before the hold's update and save the previous frame."""


def default_camera_config() -> CameraConfig:
    """The Corobot's camera (SPEC): 320 x 240, 30 deg vertical fov, 30 Hz, on the chassis at
    `dimensions.CAMERA`, looking forward. `X_PB.base_frame` is `chassis`, resolved in the
    robot's own model instance (a scoped name `model::frame` is used as given)."""
    return CameraConfig(
        width=dim.CAMERA_WIDTH,
        height=dim.CAMERA_HEIGHT,
        focal=CameraConfig.FovDegrees(y=dim.CAMERA_FOV_Y_DEG),
        clipping_near=0.01,  # in front of the hollow lens barrel (8 mm) and its glass (0.5 mm)
        clipping_far=100.0,
        X_PB=Transform(base_frame="chassis", translation=list(dim.CAMERA.position),
                       rotation=Rotation.Rpy(deg=[CAMERA_ROTATION_RPY_DEG[0], 0.0,
                                                  CAMERA_ROTATION_RPY_DEG[2]
                                                  + float(np.degrees(dim.CAMERA.yaw))])),
        renderer_name=RENDERER_NAME,
        name="camera",
        fps=dim.CAMERA_FPS,
        rgb=True,
        depth=False,
        label=False,
    )


def check_camera_config(config: CameraConfig) -> tuple[str, str] | None:
    """(field, problem) for a camera this project cannot build, else None."""
    if not config.rgb:
        return None
    if config.depth or config.label:
        return ("depth" if config.depth else "label",
                "only the colour image is simulated; set it false")
    if config.output_delay != 0:
        return ("output_delay", "must be 0 (RgbdSensorAsync is not thread-safe with VTK)")
    if not (config.fps > 0 and np.isfinite(config.fps)):
        return ("fps", "must be a positive number")
    if not config.capture_offset >= 0:
        return ("capture_offset", "must be >= 0")
    rc = config.renderer_class
    if not (isinstance(rc, RenderEngineVtkParams) or rc in ("", "RenderEngineVtk")):
        return ("renderer_class", "only RenderEngineVtk (the default) renders headless here")
    try:
        config.MakeCameras()
        config.X_PB.GetDeterministicValue()
    except Exception as e:  # Drake's own validation: one line
        return ("", str(e).splitlines()[0])
    return None


def render_engine_params(sun_direction, sun_intensity: float, sky_color) -> RenderEngineVtkParams:
    """VTK: the sun (directional, world frame), a fill light from the camera, sky background."""
    sun = np.asarray(sun_direction, dtype=float)
    sun = sun / np.linalg.norm(sun)
    return RenderEngineVtkParams(
        default_clear_color=[float(c) for c in sky_color[:3]],
        lights=[
            LightParameter(type="directional", frame="world", direction=sun,
                           intensity=float(sun_intensity), color=Rgba(1, 1, 1, 1)),
            LightParameter(type="directional", frame="camera", direction=[0.0, 0.0, 1.0],
                           intensity=FILL_INTENSITY, color=Rgba(1, 1, 1, 1)),
        ],
    )


class CameraHold(LeafSystem):
    """Renders one colour frame at initialization and every 1/fps s (from `capture_offset`) and
    holds it: outputs `rgb_image` (ImageRgba8U) and `image_time` (s, the capture time)."""

    def __init__(self, width: int, height: int, fps: float, capture_offset: float = 0.0):
        super().__init__()
        model = AbstractValue.Make(ImageRgba8U(width, height))
        self._input = self.DeclareAbstractInputPort("color_image", model)
        self._image = self.DeclareAbstractState(model)
        self._time = self.DeclareDiscreteState(1)
        self.DeclareStateOutputPort("rgb_image", self._image)
        self.DeclareStateOutputPort("image_time", self._time)
        self.DeclareInitializationUnrestrictedUpdateEvent(self._capture)
        self.DeclarePeriodicUnrestrictedUpdateEvent(1.0 / fps, capture_offset, self._capture)

    def _capture(self, context, state):
        state.get_mutable_abstract_state(int(self._image)).set_value(
            self._input.Eval(context))
        state.get_mutable_discrete_state(int(self._time)).SetAtIndex(0, context.get_time())


class CameraFrameSaver(LeafSystem):
    """Writes its `rgb_image` input as numbered PNG files (RGB) `<directory>/frame_NNNNNN.png`
    every `period` s from `offset`; `frames_saved` counts them (a publish event cannot write
    the Context, so the count is this object's)."""

    def __init__(self, directory: str | Path, width: int, height: int, period: float,
                 offset: float = 0.0):
        super().__init__()
        self.directory = Path(directory)
        self.directory.mkdir(parents=True, exist_ok=True)
        self.frames_saved = 0
        self.DeclareAbstractInputPort("rgb_image", AbstractValue.Make(ImageRgba8U(width, height)))
        self.DeclarePeriodicPublishEvent(period, offset, self._save)

    def frame_path(self, index: int) -> Path:
        return self.directory / f"frame_{index:06d}.png"

    def _save(self, context):
        from PIL import Image

        image = self.get_input_port().Eval(context)
        if image.width() == 0:
            return
        Image.fromarray(np.array(image.data[:, :, :3])).save(
            self.frame_path(self.frames_saved), compress_level=1)
        self.frames_saved += 1


def _sensor_pose(plant, instance, config: CameraConfig):
    """(geometry frame id, X_AB): the body frame the sensor rides on and the pose in it."""
    name = config.X_PB.base_frame
    if not name:
        frame = plant.world_frame()
    elif "::" in name:
        frame = GetScopedFrameByName(plant, name)
    else:
        frame = plant.GetFrameByName(name, instance)
    X_FB = config.X_PB.GetDeterministicValue()
    X_AB = frame.GetFixedPoseInBodyFrame() @ X_FB
    return plant.GetBodyFrameIdOrThrow(frame.body().index()), RigidTransform(X_AB)


def add_camera(builder, plant, scene_graph, robot: str, instance, config: CameraConfig,
               renderer_params: RenderEngineVtkParams, save_dir: str | Path | None = None,
               save_rate: float | None = None):
    """Adds `robot`'s camera (see the module doc) and returns (hold, saver or None); nothing
    when `config.rgb` is false."""
    if not config.rgb:
        return None, None
    if not scene_graph.HasRenderer(config.renderer_name):
        params = (config.renderer_class if isinstance(config.renderer_class,
                                                      RenderEngineVtkParams)
                  else renderer_params)
        scene_graph.AddRenderer(config.renderer_name, MakeRenderEngineVtk(params))
    color, depth = config.MakeCameras()
    frame_id, X_AB = _sensor_pose(plant, instance, config)
    sensor = builder.AddNamedSystem(f"{robot}.camera", RgbdSensor(frame_id, X_AB, color, depth))
    builder.Connect(scene_graph.get_query_output_port(), sensor.query_object_input_port())
    hold = builder.AddNamedSystem(f"{robot}.camera_hold", CameraHold(
        config.width, config.height, config.fps, config.capture_offset))
    builder.Connect(sensor.color_image_output_port(), hold.get_input_port())
    builder.ExportOutput(hold.GetOutputPort("rgb_image"), f"{robot}.camera.rgb_image")
    builder.ExportOutput(hold.GetOutputPort("image_time"), f"{robot}.camera.image_time")
    saver = None
    if save_dir is not None:
        rate = save_rate or config.fps
        saver = builder.AddNamedSystem(f"{robot}.camera_saver", CameraFrameSaver(
            Path(save_dir) / robot, config.width, config.height, 1.0 / rate,
            config.capture_offset + SAVE_OFFSET))
        builder.Connect(hold.GetOutputPort("rgb_image"), saver.get_input_port())
    return hold, saver
