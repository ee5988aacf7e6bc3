"""Benchmark: what the IR sensors cost, per scan and inside the running default scene.

Run: ``.venv/bin/python tools/bench_ir.py [--seconds 10] [--repeats 3]``. It prints

1. the cost of one scan of both default sensors (2 sensors x 6 rays) in the built station:
   each IrSensor's own periodic-update handler (chassis pose from the QueryObject, posing the
   rays, the exact cast, the output model, writing the state), called directly;
2. the same 12 rays through ``tools/bench_raycast.py``'s stand-alone scene (one cast);
3. the real-time factor of the default scene driving (tools/bench.py's figure of eight) with
   no IR sensor and with the 2 default sensors at 20 Hz (the camera off in both, so the
   difference is the sensors' whole in-diagram cost), median of ``--repeats``.

Importable (for tools/bench.py): :func:`station_scan_cost_seconds`,
:func:`realtime_factor`, :data:`CONFIGURATIONS` (name -> scenario overrides).
"""

import argparse
import dataclasses as dc
import os
import statistics
import time
from pathlib import Path

from corobot_drake import scenario as sc
from corobot_drake.scenario import load_scenario
from corobot_drake.simulation import Simulation, quiet_drake_warnings

DEFAULT_SCENARIO = Path(__file__).resolve().parent.parent / "scenarios" / "corobot.yaml"
DRIVING = ("robots: {corobot: {commands: [!SetPower {left: 1.0, right: 0.6}, !Wait {seconds: 3},"
           " !SetPower {left: 0.6, right: 1.0}, !Wait {seconds: 3}, !SetPower {left: -1.0,"
           " right: 1.0}]}}")
NO_CAMERA = (["robots: {corobot: {camera: {rgb: false}}}"]
             if "camera" in {f.name for f in dc.fields(sc.Robot)} else [])
NO_IR = "robots: {corobot: {ir_sensors: {front: {enabled: false}, rear: {enabled: false}}}}"

CONFIGURATIONS = {
    "physics + drive, no IR, no camera": [*NO_CAMERA, NO_IR],
    "physics + drive + 2 IR at 20 Hz, no camera": [*NO_CAMERA],
    "physics + drive + 2 IR at 200 Hz, no camera": [
        *NO_CAMERA, "robots: {corobot: {ir_sensors: {front: {scan_rate_hz: 200}, "
        "rear: {scan_rate_hz: 200}}}}"],
}
"""Scenario overrides (on top of the default scene and DRIVING) of each RTF configuration."""


def station_scan_cost_seconds(repeats: int = 2000, batch: int = 50,
                              timer=time.process_time, best: bool = False) -> float:
    """Median (or, with `best`, smallest) cost per batch-averaged call of one scan of both
    default IR sensors (2 x 6 rays) in the built default station: each sensor's periodic-update
    handler, as the Simulator runs it (minus Drake's event dispatch), against a QueryObject the
    physics step has already posed. `timer`: process CPU time by default (robust on a shared,
    loaded machine); pass time.perf_counter for wall time."""
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=NO_CAMERA))
    sim.advance(0.1)
    jobs = []
    for sensor in sim.station.robots["corobot"].ir_sensors.values():
        context = sensor.GetMyContextFromRoot(sim.context)
        jobs.append((sensor, context, sensor.AllocateDiscreteVariables()))

    def scan():
        for sensor, context, out in jobs:
            sensor._periodic_scan(context, out)

    scan()  # warm up (builds the RayCasters)
    samples = []
    for _ in range(max(1, repeats // batch)):
        start = timer()
        for _ in range(batch):
            scan()
        samples.append((timer() - start) / batch)
    return min(samples) if best else statistics.median(samples)


def realtime_factor(overrides: list[str], seconds: float = 10.0) -> float:
    """Simulated seconds per wall second of the default scene driving with `overrides`."""
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[DRIVING, *overrides]))
    start = time.perf_counter()
    sim.advance(seconds)
    return seconds / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="simulated s per RTF run")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    quiet_drake_warnings()
    from bench_raycast import scan_cost_seconds

    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(f"IR scan, 2 sensors x 6 rays, in the station: "
          f"{station_scan_cost_seconds() * 1e6:.1f} us CPU (median batch), "
          f"{station_scan_cost_seconds(best=True) * 1e6:.1f} us CPU (best batch), "
          f"{station_scan_cost_seconds(timer=time.perf_counter) * 1e6:.1f} us wall (median)")
    print(f"the same 12 rays, one cast (tools/bench_raycast.py): "
          f"{scan_cost_seconds() * 1e6:.1f} us (median)")
    print("| configuration | real-time factor (median) |")
    print("|---|---|")
    for name, overrides in CONFIGURATIONS.items():
        rtfs = [realtime_factor(overrides, args.seconds) for _ in range(args.repeats)]
        print(f"| {name} | {statistics.median(rtfs):.2f}x |", flush=True)


if __name__ == "__main__":
    main()
