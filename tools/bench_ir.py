"""Benchmark: what the IR sensors cost, per scan and inside the running default scene.

Run: ``.venv/bin/python tools/bench_ir.py [--seconds 10] [--repeats 5]``. It prints

1. the cost of one scan of both default sensors (2 sensors x 6 rays) in the built station:
   each IrSensor's own periodic-update handler (chassis pose from the QueryObject, posing the
   rays, the exact cast, the output model, writing the state), called directly in a loop
   (median and best batch, CPU and wall);
2. the same handlers timed in place: called by the Simulator in the default scene driving
   (caches cold after each physics step), median per scan of both sensors, CPU;
3. the ray cast alone (``tools/bench_raycast.py``'s stand-alone scene);
4. the default scene driving (tools/bench.py's figure of eight, camera off) with no IR, and
   at 20 Hz and 200 Hz with two *no-op* IR sensors (the same events, state and ports, a
   handler that does nothing: what Drake's event machinery and the extra simulator steps at
   scan times cost) and with the 2 default sensors: the real-time factor, CPU ms per
   simulated second and simulator steps per simulated second, medians of ``--repeats`` runs
   taken in turn; and from those the in-place cost of one scan of both sensors (extra CPU per
   simulated second / scans per second), split into Drake's part (no-op minus no IR) and the
   handlers' (IR minus no-op). At 20 Hz that cost is a few percent of the physics, within
   the run-to-run noise of a shared machine; 200 Hz multiplies it by ten.

The no-op sensor lives here, not in the package: it is a measuring device.

Importable (for tools/bench.py): :func:`station_scan_cost_seconds`,
:func:`realtime_factor`, :data:`CONFIGURATIONS` (name -> scenario overrides).
"""

import argparse
import contextlib
import dataclasses as dc
import itertools
import os
import statistics
import time
from pathlib import Path
from typing import ClassVar

from pydrake.systems.framework import EventStatus

from corobot_drake.analysis.bench_raycast import scan_cost_seconds
from corobot_drake.config import scenario as sc
from corobot_drake.config.scenario import load_scenario
from corobot_drake.sensors import ir_sensor
from corobot_drake.simulation import Simulation, quiet_drake_warnings

DEFAULT_SCENARIO = Path(__file__).resolve().parent.parent / "scenarios" / "corobot.yaml"
DRIVING = ("robots: {corobot: {commands: [!SetPower {left: 1.0, right: 0.6}, !Wait {seconds: 3},"
           " !SetPower {left: 0.6, right: 1.0}, !Wait {seconds: 3}, !SetPower {left: -1.0,"
           " right: 1.0}]}}")
NO_CAMERA = (["robots: {corobot: {camera: {rgb: false}}}"]
             if "camera" in {f.name for f in dc.fields(sc.Robot)} else [])
NO_IR = "robots: {corobot: {ir_sensors: {front: {enabled: false}, rear: {enabled: false}}}}"
IR_200_HZ = ("robots: {corobot: {ir_sensors: {front: {scan_rate_hz: 200}, "
             "rear: {scan_rate_hz: 200}}}}")

CONFIGURATIONS = {
    "physics + drive, no IR, no camera": [*NO_CAMERA, NO_IR],
    "physics + drive + 2 IR at 20 Hz, no camera": [*NO_CAMERA],
    "physics + drive + 2 IR at 200 Hz, no camera": [*NO_CAMERA, IR_200_HZ],
}
"""Scenario overrides (on top of the default scene and DRIVING) of each RTF configuration."""

NO_OP = "physics + drive + 2 no-op IR at 20 Hz, no camera"
NO_OP_200 = "physics + drive + 2 no-op IR at 200 Hz, no camera"


class NoOpIrSensor(ir_sensor.IrSensor):
    """An IrSensor whose scans do nothing: the same events, state and ports, so a run with it
    measures what Drake's event dispatch (and the extra simulator steps the scan times add)
    costs without any of the sensor's own work."""

    def _initial_scan(self, context, discrete_state) -> None:
        pass

    def _periodic_scan(self, context, discrete_state) -> None:
        pass


class TimedIrSensor(ir_sensor.IrSensor):
    """An IrSensor that records the CPU time of each periodic scan (sensor name, time,
    seconds) in `TimedIrSensor.log` (class-wide: both sensors of a station)."""

    log: ClassVar[list] = []

    def _periodic_scan(self, context, discrete_state) -> None:
        start = time.thread_time()
        super()._periodic_scan(context, discrete_state)
        TimedIrSensor.log.append(
            (self.sensor_name, context.get_time(), time.thread_time() - start))


@contextlib.contextmanager
def _sensor_class(cls):
    """Builds stations with `cls` in place of IrSensor (add_ir_sensors looks it up)."""
    real = ir_sensor.IrSensor
    ir_sensor.IrSensor = cls
    try:
        yield
    finally:
        ir_sensor.IrSensor = real


def station_scan_cost_seconds(repeats: int = 4000, batch: int = 50,
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
        out = sensor.AllocateDiscreteVariables()
        out.SetFrom(context.get_discrete_state())  # as Drake does before calling the handler
        jobs.append((sensor, context, out))

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


def in_place_scan_cost_seconds(seconds: float = 10.0) -> tuple[float, dict[str, float]]:
    """Median CPU time of one scan of both default sensors as the Simulator calls their
    handlers in the default scene driving (the handlers only, not Drake's dispatch), and the
    median of each sensor's handler by name."""
    TimedIrSensor.log = []
    with _sensor_class(TimedIrSensor):
        sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[DRIVING, *NO_CAMERA]))
    sim.advance(seconds)
    per_scan: dict[float, float] = {}
    per_sensor: dict[str, list[float]] = {}
    for name, t, cost in TimedIrSensor.log:
        per_scan[t] = per_scan.get(t, 0.0) + cost
        per_sensor.setdefault(name, []).append(cost)
    return (statistics.median(per_scan.values()),
            {name: statistics.median(costs) for name, costs in per_sensor.items()})


def pose_update_probe_seconds(seconds: float = 5.0) -> tuple[float, float]:
    """Whether the SceneGraph pose update a scan triggers is the plant's own work done early:
    the median wall time of ``query_object.GetPoseInWorld(chassis)`` probed at the end of
    (steps that took a scan, plant steps that didn't). The first is a cache hit (the scan
    computed the poses of the current plant state and nothing invalidated them, so the next
    plant step reuses them); the second is the pose update itself."""
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[DRIVING, *NO_CAMERA]))
    sensor = sim.station.robots["corobot"].ir_sensors["front"]
    period, h = sensor.period, sim.scenario.plant_config.time_step
    probes: list[tuple[float, float]] = []

    def monitor(root_context):
        context = sensor.GetMyContextFromRoot(root_context)
        start = time.perf_counter()
        sensor.get_input_port(0).Eval(context).GetPoseInWorld(sensor._frame_id)
        probes.append((root_context.get_time(), time.perf_counter() - start))
        return EventStatus.Succeeded()

    sim.simulator.set_monitor(monitor)
    sim.advance(seconds)
    after_scan, after_plant = [], []
    for (t_events, _), (_, cost) in itertools.pairwise(probes):
        # The step that ends at probe i+1 handled the events due at probe i's time.
        if t_events > 0 and abs(t_events / period - round(t_events / period)) < 1e-9:
            after_scan.append(cost)
        elif round(t_events / h) * h == t_events:
            after_plant.append(cost)
    return statistics.median(after_scan), statistics.median(after_plant)


@dc.dataclass
class Run:
    realtime_factor: float
    cpu_per_second: float
    """CPU seconds (this process) per simulated second."""
    steps_per_second: float


def run_configuration(overrides: list[str], seconds: float = 10.0, sensor=None) -> Run:
    """The default scene driving with `overrides` for `seconds` (sensor: an IrSensor
    subclass to build the station with)."""
    with _sensor_class(sensor or ir_sensor.IrSensor):
        sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[DRIVING, *overrides]))
    steps = sim.simulator.get_num_steps_taken()
    wall, cpu = time.perf_counter(), time.process_time()
    sim.advance(seconds)
    cpu = time.process_time() - cpu
    wall = time.perf_counter() - wall
    steps = sim.simulator.get_num_steps_taken() - steps
    return Run(seconds / wall, cpu / seconds, steps / seconds)


def realtime_factor(overrides: list[str], seconds: float = 10.0) -> float:
    """Simulated seconds per wall second of the default scene driving with `overrides`."""
    return run_configuration(overrides, seconds).realtime_factor


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="simulated s per RTF run")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    quiet_drake_warnings()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(f"IR scan, 2 sensors x 6 rays, both handlers called directly: "
          f"{station_scan_cost_seconds() * 1e6:.1f} us CPU (median batch), "
          f"{station_scan_cost_seconds(best=True) * 1e6:.1f} us CPU (best batch), "
          f"{station_scan_cost_seconds(timer=time.perf_counter) * 1e6:.1f} us wall (median)")
    both, each = in_place_scan_cost_seconds(args.seconds)
    print(f"the same handlers in place (called by the Simulator, default scene driving): "
          f"{both * 1e6:.1f} us CPU (median per scan; "
          + ", ".join(f"{name} {cost * 1e6:.1f} us" for name, cost in each.items()) + ")")
    hit, update = pose_update_probe_seconds()
    print(f"SceneGraph pose query probed after a step: {hit * 1e6:.1f} us after a step that "
          f"took a scan (cache hit: the next plant step reuses the scan's pose update), "
          f"{update * 1e6:.1f} us after a plant step without one (the pose update itself)")
    print(f"the ray cast alone, both sensors (tools/bench_raycast.py): "
          f"{scan_cost_seconds() * 1e6:.1f} us wall (median)", flush=True)

    runs: dict[str, list[Run]] = {}
    no_ir, ir_20, ir_200 = CONFIGURATIONS
    named = {  # name: (overrides, sensor class)
        no_ir: (CONFIGURATIONS[no_ir], None),
        NO_OP: (CONFIGURATIONS[ir_20], NoOpIrSensor),
        ir_20: (CONFIGURATIONS[ir_20], None),
        NO_OP_200: (CONFIGURATIONS[ir_200], NoOpIrSensor),
        ir_200: (CONFIGURATIONS[ir_200], None),
    }
    for _ in range(args.repeats):  # configurations in turn: slow drifts of the load spread
        for name, (overrides, sensor) in named.items():
            runs.setdefault(name, []).append(run_configuration(overrides, args.seconds, sensor))
    print("| configuration | real-time factor | CPU ms per simulated s (min-max) "
          "| steps per simulated s |")
    print("|---|---|---|---|")
    med = {}
    for name, rs in runs.items():
        med[name] = Run(*(statistics.median(getattr(r, f.name) for r in rs)
                          for f in dc.fields(Run)))
        m = med[name]
        cpu = [r.cpu_per_second * 1e3 for r in rs]
        print(f"| {name} | {m.realtime_factor:.2f}x | {m.cpu_per_second * 1e3:.1f} "
              f"({min(cpu):.0f}-{max(cpu):.0f}) | {m.steps_per_second:.1f} |")
    for rate, noop, ir in ((20, med[NO_OP], med[ir_20]), (200, med[NO_OP_200], med[ir_200])):
        base = med[no_ir]

        def per_scan(a: Run, b: Run, rate=rate) -> str:
            return f"{(a.cpu_per_second - b.cpu_per_second) / rate * 1e3:.3f} ms"

        print(f"in place at {rate} Hz, per scan of both sensors (CPU per simulated s): "
              f"{per_scan(ir, base)} (IR - no IR) = {per_scan(noop, base)} Drake's events and "
              f"the {noop.steps_per_second - base.steps_per_second:.1f} extra simulator steps "
              f"per simulated s (no-op - no IR) + {per_scan(ir, noop)} the handlers (IR - no-op); "
              f"from the real-time factors (wall): "
              f"{(1 / ir.realtime_factor - 1 / base.realtime_factor) / rate * 1e3:.3f} ms")
    print(f"(the median of {args.repeats} runs of {args.seconds:g} simulated s each; "
          f"load average now {os.getloadavg()[0]:.1f})")

if __name__ == "__main__":
    main()
