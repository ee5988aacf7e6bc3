"""Cost of the robot's camera per frame (`tools/bench_camera.py`).

Figures for the Corobot's camera (320 x 240, 30 deg vertical fov, sun + fill light, no shadows)
with each renderer (GL through an X display or a private Xvfb, the default here; VTK, through
GLX when a display is available), in the default scene with the robot driving a circle:

- `camera_frame_ms()`: the render itself. The synchronous camera (`output_delay: 0`: the
  station's RgbdSensor) is asked for its colour image once per 1/30 s of simulated time and
  only that call is timed; median over `frames`.
- `camera_overhead_ms()`: what the camera adds to a simulation: the time of `seconds`
  simulated with the camera at 30 Hz minus the same run without it, per frame. `delay` is the
  camera's output_delay: the default 0.03 renders on a worker thread (GL only: Drake's
  `RgbdSensorAsync` under SAP, `sensors.render_worker` under CENIC), so the wall clock pays
  less than the CPU; 0 renders in the simulation's thread. Under CENIC a worker's frame is
  waited for only when read: `read` reads each one as it comes out (`advance_reading`).
"""

from __future__ import annotations

import statistics
import time

from corobot_drake.config.scenario import load_scenario
from corobot_drake.config.sensors import ENGINES
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.simulation import Simulation, quiet_drake_warnings

CIRCLE = "robots: {corobot: {commands: [!SetPower {left: 0.4, right: 0.8}]}}"
FPS = 30.0
_CLOCKS = {"wall": time.perf_counter, "cpu": time.process_time}
RENDERERS = ENGINES


def _sim(camera: bool, fps: float = FPS, overrides=(), renderer: str = "",
         delay: float | None = None) -> Simulation:
    scenario = load_scenario(DEFAULT_SCENARIO, overrides=[CIRCLE, *overrides])
    for robot in scenario.robots.values():
        front = robot.cameras["front"]
        front.rgb = camera
        front.fps = fps
        front.renderer_class = renderer
        if delay is not None:
            front.output_delay = delay
    return Simulation(scenario)


def camera_frame_ms(frames: int = 90, warmup: int = 5, overrides=(), clock: str = "wall",
                    renderer: str = "") -> float:
    """Median ms for the robot's camera to render one frame: `clock` "wall" (wall-clock) or
    "cpu" (this process's CPU time, all threads: steadier on a loaded machine); `renderer`
    a `CameraConfig.renderer_class` ("" the default)."""
    now = _CLOCKS[clock]
    quiet_drake_warnings()
    # The hold renders at 1e-3 Hz (at t = 0 only): each timed frame is the only render.
    sim = _sim(True, fps=1e-3, overrides=overrides, renderer=renderer, delay=0.0)
    sensor = sim.station.diagram.GetSubsystemByName("corobot.camera.front")
    port = sensor.color_image_output_port()
    sensor_context = sensor.GetMyContextFromRoot(sim.context)
    times = []
    for i in range(warmup + frames):
        sim.advance(1.0 / FPS)  # the robot moved: the cached image is stale
        start = now()
        port.Eval(sensor_context)
        if i >= warmup:
            times.append(now() - start)
    return 1000.0 * statistics.median(times)


READ_STEP = 0.01
"""s: how often a reader looks for a new frame (`advance_reading`): every step of the
default plant, so it adds no Simulator stop and sees each frame as it comes out."""


def advance_reading(sim: Simulation, seconds: float) -> None:
    """Advances `seconds`, reading each camera frame once as it comes out (a consumer's
    30 Hz: a recorder, a ROS 2 image publisher), looking every `READ_STEP`."""
    robot, last = sim.robot(), None
    for _ in range(round(seconds / READ_STEP)):
        sim.advance(READ_STEP)
        if not robot.has_camera:  # the run without it: the same advances
            continue
        taken = robot.camera_image_time()
        if taken != last:
            robot.camera_image()
            last = taken


def _elapsed(sim: Simulation, seconds: float, clock: str, read: bool = False) -> float:
    sim.advance(0.1)  # first steps (and the t = 0 frame) out of the timing
    now = _CLOCKS[clock]
    start = now()
    if read:
        advance_reading(sim, seconds)
    else:
        sim.advance(seconds)
    return now() - start


def camera_overhead_ms(seconds: float = 3.0, overrides=(), clock: str = "wall",
                       renderer: str = "", delay: float | None = None,
                       read: bool = False) -> float:
    """ms (`clock` "wall" or "cpu") the camera adds to the simulation per frame, at 30 Hz,
    with output_delay `delay` (None: the scenario's); `read`: every frame read as it comes
    out (`advance_reading`; the run without the camera advances by the same steps)."""
    quiet_drake_warnings()
    with_camera = _elapsed(_sim(True, overrides=overrides, renderer=renderer, delay=delay),
                           seconds, clock, read)
    without = _elapsed(_sim(False, overrides=overrides), seconds, clock, read)
    return 1000.0 * (with_camera - without) / (seconds * FPS)
