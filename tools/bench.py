"""Real-time factors of the default scene, headless (run: python tools/bench.py).

One run prints a markdown table: rows are the stacks (physics only; + 2 IR at 20 Hz; + camera at
30 Hz; full stack = both), columns the plant settings (hydroelastic at 10 ms, the default and the
tire-grip sweep's pick, and at 5, 2 and 1 ms; point contact at 10 ms). Each cell simulates
`--seconds` of the robot driving a figure of eight, `--repeats` times, and reports the median
wall-clock real-time factor (the CPU-time one in parentheses: the machine may be shared). Then
the IR cost per scan and the camera cost per frame, both measured in place (the extra wall time
per scan or frame over physics only) and by their micro-benchmarks (tools/bench_ir.py,
tools/bench_raycast.py, tools/bench_camera.py) where those exist.

A sensor row appears only when the scenario schema has the sensor (`robots.<r>.ir_sensors`,
`robots.<r>.camera`); physics only turns every sensor off.
"""

import argparse
import dataclasses as dc
import importlib.util
import platform
import statistics
import time
from pathlib import Path

from corobot_drake.analysis import bench_raycast
from corobot_drake.config import scenario as sc
from corobot_drake.config.scenario import load_scenario
from corobot_drake.simulation import Simulation, quiet_drake_warnings

TOOLS = Path(__file__).resolve().parent
DEFAULT_SCENARIO = TOOLS.parent / "scenarios" / "corobot.yaml"
ROBOT = "corobot"
DRIVING = (f"robots: {{{ROBOT}: {{commands: [!SetPower {{left: 1.0, right: 0.6}}, "
           "!Wait {seconds: 3}, !SetPower {left: 0.6, right: 1.0}, !Wait {seconds: 3}, "
           "!SetPower {left: -1.0, right: 1.0}]}}")
IR_RATE_HZ = 20.0
CAMERA_FPS = 30.0


def _robot_fields() -> set[str]:
    return {f.name for f in dc.fields(sc.Robot)}


def has_ir() -> bool:
    return "ir_sensors" in _robot_fields()


def has_camera() -> bool:
    return "camera" in _robot_fields()


def _ir_names() -> list[str]:
    return list(sc.Robot().ir_sensors) if has_ir() else []


def sensor_overrides(robot: str = ROBOT, ir: bool = False, camera: bool = False) -> list[str]:
    """Overrides that turn the robot's IR sensors and camera on (at the bench rates) or off.

    Fields the scenario schema does not have yet are left out."""
    out = []
    if has_ir():
        sensors = ", ".join(
            f"{n}: {{enabled: {str(ir).lower()}, scan_rate_hz: {IR_RATE_HZ}}}"
            for n in _ir_names())
        out.append(f"robots: {{{robot}: {{ir_sensors: {{{sensors}}}}}}}")
    if has_camera():
        out.append(f"robots: {{{robot}: {{camera: {{rgb: {str(camera).lower()}, "
                   f"fps: {CAMERA_FPS}}}}}}}")
    return out


def physics_only_overrides(robot: str = ROBOT) -> list[str]:
    """No camera, no IR: the physics and the drive alone."""
    return sensor_overrides(robot, ir=False, camera=False)


def realtime_factor(overrides: list[str], seconds: float,
                    scenario: Path = DEFAULT_SCENARIO) -> tuple[float, float]:
    """(wall, CPU) simulated seconds per second, building excluded."""
    sim = Simulation(load_scenario(scenario, overrides=[DRIVING, *overrides]))
    wall, cpu = time.perf_counter(), time.process_time()
    sim.advance(seconds)
    return seconds / (time.perf_counter() - wall), seconds / (time.process_time() - cpu)


STACKS = {
    "physics only": dict(ir=False, camera=False),
    f"+ 2 IR at {IR_RATE_HZ:g} Hz": dict(ir=True, camera=False),
    f"+ camera at {CAMERA_FPS:g} Hz": dict(ir=False, camera=True),
    "full stack (IR + camera)": dict(ir=True, camera=True),
}
PLANTS = {
    "hydroelastic 10 ms (default)": "plant_config: {time_step: 0.01, contact_model: "
                                        "hydroelastic_with_fallback}",
    "hydroelastic 5 ms": "plant_config: {time_step: 0.005, contact_model: "
                                   "hydroelastic_with_fallback}",
    "hydroelastic 2 ms": "plant_config: {time_step: 0.002, contact_model: "
                         "hydroelastic_with_fallback}",
    "hydroelastic 1 ms": "plant_config: {time_step: 0.001, contact_model: "
                         "hydroelastic_with_fallback}",
    "point 10 ms": "plant_config: {time_step: 0.01, contact_model: point}",
}
DEFAULT_PLANT = "hydroelastic 10 ms (default)"


def available_stacks() -> dict:
    out = {}
    for name, flags in STACKS.items():
        if (flags["ir"] and not has_ir()) or (flags["camera"] and not has_camera()):
            continue
        out[name] = flags
    return out


def _load_tool(name: str):
    path = TOOLS / f"{name}.py"
    if not path.exists():
        return None
    spec = importlib.util.spec_from_file_location(f"_bench_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def machine() -> str:
    import os
    from importlib.metadata import version

    cpu = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (f"{os.cpu_count()} cores ({cpu}), no GPU, {platform.system()} {platform.release()}, "
            f"Python {platform.python_version()}, drake {version('drake')}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="simulated s per run")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--stacks", help="only stacks containing this text")
    parser.add_argument("--plants", help="only plant settings containing this text")
    parser.add_argument("--no-micro", action="store_true",
                        help="skip the IR and camera micro-benchmarks")
    args = parser.parse_args()
    quiet_drake_warnings()
    print(f"machine: {machine()}", flush=True)
    print(f"{args.seconds:g} s of driving per run, median of {args.repeats}; wall real-time "
          "factor (CPU-time one in parentheses)\n", flush=True)
    stacks = {k: v for k, v in available_stacks().items()
              if not args.stacks or args.stacks in k}
    plants = {k: v for k, v in PLANTS.items() if not args.plants or args.plants in k}
    results = {}
    lines = ["| stack | " + " | ".join(plants) + " |", "|---|" + "---|" * len(plants)]
    print(lines[0] + "\n" + lines[1], flush=True)
    for stack, flags in stacks.items():
        cells = []
        for plant, plant_override in plants.items():
            runs = [realtime_factor([plant_override, *sensor_overrides(ROBOT, **flags)],
                                    args.seconds) for _ in range(args.repeats)]
            wall = statistics.median(r[0] for r in runs)
            cpu = statistics.median(r[1] for r in runs)
            results[stack, plant] = (wall, cpu)
            cells.append(f"{wall:.2f}x ({cpu:.2f}x)")
        line = f"| {stack} | " + " | ".join(cells) + " |"
        lines.append(line)
        print(line, flush=True)

    print()
    base = results.get(("physics only", DEFAULT_PLANT))
    for stack, per_second, unit in (
            (f"+ 2 IR at {IR_RATE_HZ:g} Hz", IR_RATE_HZ, "scan (2 sensors)"),
            (f"+ camera at {CAMERA_FPS:g} Hz", CAMERA_FPS, "frame")):
        rtf = results.get((stack, DEFAULT_PLANT))
        if base and rtf:
            wall, cpu = ((1 / rtf[i] - 1 / base[i]) / per_second * 1000 for i in (0, 1))
            print(f"in place: {wall:.2f} ms wall, {cpu:.2f} ms CPU per {unit} "
                  f"(extra time over physics only, {DEFAULT_PLANT}; noisy on a busy machine)")
    if args.no_micro:
        return
    ir = _load_tool("bench_ir")
    if ir is not None and hasattr(ir, "station_scan_cost_seconds"):
        print(f"micro-benchmark: IR scan of both default sensors (2 x 6 rays) in the station: "
              f"{ir.station_scan_cost_seconds() * 1000:.4f} ms (tools/bench_ir.py)", flush=True)
    print(f"micro-benchmark: IR scan, 2 sensors x 6 rays: "
          f"{bench_raycast.scan_cost_seconds() * 1000:.4f} ms (tools/bench_raycast.py)", flush=True)
    camera = _load_tool("bench_camera")
    if camera is not None and hasattr(camera, "camera_frame_ms"):
        print(f"micro-benchmark: the robot's camera, one 320x240 frame: "
              f"{camera.camera_frame_ms():.2f} ms (tools/bench_camera.py)", flush=True)
        return
    camera = _load_tool("camera_cost")
    if camera is not None and hasattr(camera, "camera_frame_ms"):
        print(f"micro-benchmark: camera frame 320x240: {camera.camera_frame_ms():.2f} ms "
              f"(tools/camera_cost.py, render call only)", flush=True)


if __name__ == "__main__":
    main()
