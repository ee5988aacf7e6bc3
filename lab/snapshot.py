"""Still pictures of a simulation, rendered headless with Drake's VTK renderer
(`tools/snapshot.py`).

:func:`take` renders the scene now from a named view: `chase` (behind and above the robot),
`overview` (the robot and the world's bodies from the side), `robot-camera` (the robot's own
camera: its mount, 320x240, 30 deg vertical fov), or from a free eye and target. The scene is
lit by the scenario's sun (a directional light in the world frame) with the sky colour behind
it (`corobot_drake.sensors.render`).
"""

from __future__ import annotations

import math

import numpy as np

from corobot_drake.config.sensors import default_camera_config
from corobot_drake.sensors import render

VIEWS = ("chase", "overview", "robot-camera")


def overview_view(sim, fov_y_deg: float, aspect: float):
    """From the front-left, high, framing every robot and every world body near them."""
    points, radii = [], []
    for name in sim.robots:
        points.append(render.chassis_pose(sim, name).translation() + np.array([0, 0, 0.1]))
        radii.append(0.2)
    plant = sim.station.plant
    plant_context = plant.GetMyContextFromRoot(sim.context)
    for name, body in sim.station.bodies.items():
        p = plant.EvalBodyPoseInWorld(plant_context, body).translation()
        size = sim.scenario.world.bodies[name].shape
        half = 0.5 * max(getattr(size, "size", [2 * getattr(size, "radius", 0.5)]))
        if np.linalg.norm(p[:2] - points[0][:2]) < 6.0:
            points.append(p)
            radii.append(half * math.sqrt(3))
    points = np.array(points)
    lo = np.min(points - np.array(radii)[:, None], axis=0)
    hi = np.max(points + np.array(radii)[:, None], axis=0)
    center = (lo + hi) / 2
    center[2] = min(center[2], 0.5)
    radius = 0.5 * np.linalg.norm(hi - lo)
    half_fov = math.radians(min(fov_y_deg, fov_y_deg * aspect)) / 2
    distance = 0.7 * radius / math.sin(half_fov)
    direction = np.array([0.5, -1.0, 0.45])
    direction /= np.linalg.norm(direction)
    return render.look_at(center + distance * direction, center)


def take(sim, view: str, width: int, height: int, robot: str | None = None,
         eye=None, target=None) -> np.ndarray:
    """Renders `sim` now from `view` (or from `eye` looking at `target`, world metres);
    returns an H x W x 3 uint8 image."""
    X_WB = render.chassis_pose(sim, robot)
    if view == "robot-camera":
        # The fill light would cast the robot's own shadow ahead of it: no shadows here.
        name = render.add_renderer(sim, shadows=False, name="robot_camera_vtk")
        return render.render(sim, render.robot_camera_view(X_WB), width, height,
                             default_camera_config().focal.y, near=0.001, name=name)
    render.add_renderer(sim)
    fov = 40.0
    if eye is not None:
        X_WC = render.look_at(eye, target if target is not None else X_WB.translation())
    elif view == "chase":
        X_WC = render.chase_view(X_WB)
    elif view == "overview":
        X_WC = overview_view(sim, fov, width / height)
    else:
        raise ValueError(f"view must be one of {VIEWS}, got {view!r}")
    return render.render(sim, X_WC, width, height, fov)
