"""Cost of the robot's camera per frame (run: python tools/bench_camera.py).

Two figures for the SPEC camera (320 x 240, 30 deg vertical fov, VTK headless, sun + fill
light, no shadows), both in the default scene with the robot driving a circle:

- `camera_frame_ms()`: the render itself. The robot's own sensor (`<robot>.camera`, the
  station's RgbdSensor) is asked for its colour image once per 1/30 s of simulated time and
  only that call is timed; median over `frames`.
- `camera_overhead_ms()`: what the camera adds to a simulation: the wall time of `seconds`
  simulated with the camera at 30 Hz minus the same run without it, per frame rendered.

`tools/bench.py` can import either.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from corobot_drake.scenario import load_scenario
from corobot_drake.simulation import Simulation, quiet_drake_warnings

DEFAULT_SCENARIO = Path(__file__).resolve().parent.parent / "scenarios" / "corobot.yaml"
CIRCLE = "robots: {corobot: {commands: [!SetPower {left: 0.4, right: 0.8}]}}"
FPS = 30.0
_CLOCKS = {"wall": time.perf_counter, "cpu": time.process_time}


def _sim(camera: bool, fps: float = FPS, overrides=()) -> Simulation:
    scenario = load_scenario(DEFAULT_SCENARIO, overrides=[CIRCLE, *overrides])
    for robot in scenario.robots.values():
        robot.camera.rgb = camera
        robot.camera.fps = fps
    return Simulation(scenario)


def camera_frame_ms(frames: int = 90, warmup: int = 5, overrides=(), clock: str = "wall"
                    ) -> float:
    """Median ms for the robot's camera to render one frame: `clock` "wall" (wall-clock) or
    "cpu" (this process's CPU time, all threads: steadier on a loaded machine)."""
    now = _CLOCKS[clock]
    quiet_drake_warnings()
    # The hold renders at 1e-3 Hz (at t = 0 only): each timed frame is the only render.
    sim = _sim(True, fps=1e-3, overrides=overrides)
    sensor = sim.station.diagram.GetSubsystemByName("corobot.camera")
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


def _elapsed(sim: Simulation, seconds: float, clock: str) -> float:
    sim.advance(0.1)  # first steps (and the t = 0 frame) out of the timing
    now = _CLOCKS[clock]
    start = now()
    sim.advance(seconds)
    return now() - start


def camera_overhead_ms(seconds: float = 3.0, overrides=(), clock: str = "wall") -> float:
    """ms (`clock` "wall" or "cpu") the camera adds to the simulation per frame, at 30 Hz."""
    quiet_drake_warnings()
    with_camera = _elapsed(_sim(True, overrides=overrides), seconds, clock)
    without = _elapsed(_sim(False, overrides=overrides), seconds, clock)
    return 1000.0 * (with_camera - without) / (seconds * FPS)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=90)
    parser.add_argument("--seconds", type=float, default=3.0)
    parser.add_argument("--repeats", type=int, default=3, help="median of this many runs")
    args = parser.parse_args()
    render = statistics.median(camera_frame_ms(args.frames) for _ in range(args.repeats))
    cpu = statistics.median(camera_frame_ms(args.frames, clock="cpu")
                            for _ in range(args.repeats))
    overhead = statistics.median(camera_overhead_ms(args.seconds) for _ in range(args.repeats))
    overhead_cpu = statistics.median(camera_overhead_ms(args.seconds, clock="cpu")
                                     for _ in range(args.repeats))
    print("| camera, 320x240, VTK headless | ms per frame (median) |")
    print("|---|---|")
    print(f"| render (the sensor's colour image), wall clock | {render:.2f} |")
    print(f"| render, CPU time (all threads) | {cpu:.2f} |")
    print(f"| added to a simulation at 30 Hz, wall clock | {overhead:.2f} |")
    print(f"| added to a simulation at 30 Hz, CPU time | {overhead_cpu:.2f} |")


if __name__ == "__main__":
    main()
