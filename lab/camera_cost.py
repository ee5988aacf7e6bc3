"""Camera frame cost, visual meshes vs collision boxes (`tools/camera_cost.py`).

The robot drives a circle beside the giant box; between frames the simulation advances one
camera period (1/30 s) and only the render call is timed: one 320x240 colour frame (the Corobot's
camera) rendered by VTK with the camera's lighting (sun + fill, no shadows). Views: the
robot's own camera (`robot-camera`: the robot itself is out of its view, so this is the cost
the robot pays) and a 320x240 chase camera that looks at the robot (`chase`: the worst case
for the meshes, every robot triangle drawn).

`meshes_vs_boxes_ms(view)` renders the two visuals alternately, frame by frame, so load from
other processes slows both alike; the median of each is reported. `camera_frame_ms(visual,
view)` renders one visual alone.
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path

from corobot_drake.config.scenario import load_scenario
from corobot_drake.config.sensors import default_camera_config
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.sensors import render
from corobot_drake.simulation import Simulation, quiet_drake_warnings

CIRCLE = ("robots: {corobot: {pose: {translation: [0.6, 0.8, 0], "
          "rotation: !Rpy {deg: [0, 0, 150]}}, commands: [!SetPower {left: 0.3, right: 0.7}]}}")
VIEWS = ("robot-camera", "chase")
RENDERER = "camera_cost_vtk"


class _Camera:
    """One simulation of the circle drive with its robot drawn as `visual`, rendering frames."""

    def __init__(self, visual: str, view: str, scenario: Path):
        quiet_drake_warnings()
        self.sim = Simulation(load_scenario(scenario, overrides=[
            CIRCLE, f"robots: {{corobot: {{visual: {visual}}}}}"]))
        # The robot's camera renders without shadows (camera.py): so does this.
        self.renderer = render.add_renderer(self.sim, shadows=False, name=RENDERER)
        self.view = view

    def frame_seconds(self) -> float:
        """Advances one camera period, then times one frame's render (wall-clock s)."""
        self.sim.advance(1.0 / 30.0)
        X_WB = render.chassis_pose(self.sim)
        X_WC = (render.robot_camera_view(X_WB) if self.view == "robot-camera"
                else render.chase_view(X_WB))
        start = time.perf_counter()
        camera = default_camera_config()  # the Corobot's, as its robot file says
        render.render(self.sim, X_WC, camera.width, camera.height,
                      camera.focal.y, name=self.renderer)
        return time.perf_counter() - start


def camera_frame_ms(visual: str = "meshes", view: str = "robot-camera", frames: int = 120,
                    warmup: int = 10, scenario: Path = DEFAULT_SCENARIO) -> float:
    """Median wall-clock ms to render one 320x240 frame of `view` with the robot drawn as
    `visual` (`meshes` or `boxes`)."""
    camera = _Camera(visual, view, scenario)
    times = [camera.frame_seconds() for _ in range(warmup + frames)][warmup:]
    return 1000.0 * statistics.median(times)


def meshes_vs_boxes_ms(view: str = "robot-camera", frames: int = 300, warmup: int = 10,
                       scenario: Path = DEFAULT_SCENARIO) -> dict[str, float]:
    """{"boxes": ms, "meshes": ms}: median per frame, the two rendered alternately (so a busy
    machine slows both alike)."""
    cameras = {v: _Camera(v, view, scenario) for v in ("boxes", "meshes")}
    times = {v: [] for v in cameras}
    for i in range(warmup + frames):
        for v, camera in cameras.items():
            t = camera.frame_seconds()
            if i >= warmup:
                times[v].append(t)
    return {v: 1000.0 * statistics.median(t) for v, t in times.items()}
