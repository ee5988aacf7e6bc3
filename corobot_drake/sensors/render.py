"""Rendering a built station with Drake's VTK renderer: lit by the scenario's sun, sky behind.

Used by `tools/snapshot.py` (README pictures) and `tools/camera_cost.py` (camera frame cost).
Any `Simulation` can be photographed, before or after it has been driven:

    sim = Simulation.from_file("scenarios/corobot.yaml")
    add_renderer(sim)
    image = render(sim, look_at([1, 1, 0.6], [0, 0, 0.1]), 640, 480)   # H x W x 3 uint8

The renderers live in a private SceneGraph context (the station's geometry), posed from the
plant at each render, so taking a picture leaves the simulation as it was (adding a renderer to the
simulation's own context would change its geometry, which Drake's asynchronous camera
refuses to continue after).
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.geometry import (
    ClippingRange,
    ColorRenderCamera,
    LightParameter,
    RenderCameraCore,
    RenderEngineVtkParams,
    Rgba,
)
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.systems.sensors import CameraInfo

from corobot_drake.config import scenario as sc
from corobot_drake.config.sensors import CAMERA_ROTATION_RPY_DEG, FRONT_CAMERA
from corobot_drake.robots import corobot
from corobot_drake.sensors.camera import make_vtk_engine, render_engine_params

RENDERER = "corobot_vtk"
"""Name under which `add_renderer` registers its VTK engine."""

SKY_INTENSITY = 0.35
"""With shadows: light from straight above (the sky), so the ground in the sun's shadow is
shaded, not black (the camera's fill reaches the ground at a grazing angle)."""

R_BC = RotationMatrix(np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]))
"""A camera frame (+z forward, +x right, +y down) looking along the body's +x, level."""


def render_params(world: sc.World, shadows: bool = True) -> RenderEngineVtkParams:
    """The robot camera's lighting (`camera.render_engine_params`: the scenario's sun, a fill
    from the camera, sky background); with `shadows`, cast shadows and a sky light from above."""
    params = render_engine_params(world.sun.direction, world.sun.intensity, world.sky_color)
    if shadows:
        params.lights = [*params.lights, LightParameter(
            type="directional", frame="world", direction=[0.0, 0.0, -1.0],
            intensity=SKY_INTENSITY, color=Rgba(1, 1, 1, 1))]
        params.cast_shadows = True
        params.shadow_map_size = 2048
    return params


def _photo_context(sim):
    """The private SceneGraph context of `sim`'s pictures (made on first use; the renderers
    added by `add_renderer` live there)."""
    context = getattr(sim, "_photo_context", None)
    if context is None:
        context = sim._photo_context = sim.station.scene_graph.CreateDefaultContext()
    return context


def add_renderer(sim, shadows: bool = True, name: str = RENDERER) -> str:
    """Adds the VTK engine for pictures of `sim` (see the module doc); returns its name."""
    scene_graph = sim.station.scene_graph
    context = _photo_context(sim)
    if not scene_graph.HasRenderer(context, name):
        scene_graph.AddRenderer(context, name, make_vtk_engine(
            render_params(sim.scenario.world, shadows)))
    return name


def _posed_query(sim):
    """The QueryObject of the pictures' context, with the plant's current geometry poses."""
    scene_graph, plant = sim.station.scene_graph, sim.station.plant
    context = _photo_context(sim)
    poses = plant.get_geometry_pose_output_port().Eval(plant.GetMyContextFromRoot(sim.context))
    scene_graph.get_source_pose_port(plant.get_source_id()).FixValue(context, poses)
    return scene_graph.get_query_output_port().Eval(context)


def color_camera(width: int, height: int, fov_y_deg: float, near: float = 0.01,
                 far: float = 50.0, name: str = RENDERER) -> ColorRenderCamera:
    return ColorRenderCamera(RenderCameraCore(
        name, CameraInfo(width, height, math.radians(fov_y_deg)), ClippingRange(near, far),
        RigidTransform()), False)


def render(sim, X_WC: RigidTransform, width: int = 640, height: int = 480,
           fov_y_deg: float = 40.0, near: float = 0.01, name: str = RENDERER) -> np.ndarray:
    """An RGB image (height x width x 3, uint8) from camera pose X_WC (Drake camera axes)."""
    camera = color_camera(width, height, fov_y_deg, near, name=name)
    image = _posed_query(sim).RenderColorImage(
        camera, sim.station.scene_graph.world_frame_id(), X_WC)
    return np.array(image.data[:, :, :3], dtype=np.uint8)


def look_at(eye, target) -> RigidTransform:
    """Drake camera pose (+z forward, +x right, +y down) at `eye` looking at `target`, z up."""
    eye, target = np.asarray(eye, float), np.asarray(target, float)
    z = (target - eye) / np.linalg.norm(target - eye)
    x = np.cross(z, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    return RigidTransform(RotationMatrix(np.column_stack([x, np.cross(z, x), z])), eye)


def chassis_pose(sim, robot: str | None = None) -> RigidTransform:
    parts = sim.robot(robot)._parts
    plant = sim.station.plant
    return plant.EvalBodyPoseInWorld(plant.GetMyContextFromRoot(sim.context), parts.chassis)


def heading_frame(X_WB: RigidTransform) -> RigidTransform:
    """The chassis pose with roll and pitch removed (a chase camera should not rock)."""
    yaw = RollPitchYaw(X_WB.rotation()).yaw_angle()
    return RigidTransform(RollPitchYaw(0, 0, yaw), X_WB.translation())


def chase_view(X_WB: RigidTransform, back: float = 0.95, up: float = 0.5,
               ahead: float = 0.4) -> RigidTransform:
    """Behind and above the robot, looking at a point ahead of it."""
    X_WH = heading_frame(X_WB)
    return look_at(X_WH @ np.array([-back, 0.25 * back, up]),
                   X_WH @ np.array([ahead, 0.0, 0.0]))


def robot_camera_view(X_WB: RigidTransform) -> RigidTransform:
    """The robot's own camera (the Corobot's front camera where its robot file mounts it),
    in the world."""
    position, rpy_deg = corobot.mount_of("cameras", FRONT_CAMERA)
    yaw = math.radians(rpy_deg[2] - CAMERA_ROTATION_RPY_DEG[2])  # its turn from looking ahead
    X_BC = RigidTransform(RollPitchYaw(0, 0, yaw).ToRotationMatrix() @ R_BC, position)
    return X_WB @ X_BC
