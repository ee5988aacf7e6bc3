"""What the IR sensors cost, per scan and inside the running default scene (`tools/bench_ir.py`).

- :func:`station_scan_cost_seconds`: one scan of both default sensors (2 sensors x 6 rays) in
  the built station: each IrSensor's own periodic-update handler (chassis pose from the
  QueryObject, posing the rays, the exact cast, the output model, writing the state), called
  directly in a loop;
- :func:`in_place_scan_cost_seconds`: the same handlers timed as the Simulator calls them in
  the default scene driving (caches cold after each physics step);
- :func:`pose_update_probe_seconds`: whether the SceneGraph pose update a scan triggers is
  the plant's own work done early;
- :func:`run_configuration`: the default scene driving (the benchmarks' figure of eight,
  camera off) with the overrides of a :data:`CONFIGURATIONS` entry, optionally with
  :class:`NoOpIrSensor` (the same events, state and ports, a handler that does nothing: what
  Drake's event machinery and the extra simulator steps at scan times cost).

The no-op sensor lives here, not with the sensors: it is a measuring device.
"""

import contextlib
import dataclasses as dc
import itertools
import statistics
import time
from typing import ClassVar

from pydrake.systems.framework import EventStatus

from corobot_drake.config.scenario import load_scenario, physics_step
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.sensors import ir_sensor
from corobot_drake.simulation import Simulation
from lab.bench import DRIVING, NO_CAMERA, physics_only_overrides

IR_200_HZ = ("robots: {corobot: {ir_sensors: {front: {scan_rate_hz: 200}, "
             "rear: {scan_rate_hz: 200}}}}")

CONFIGURATIONS = {
    "physics + drive, no IR, no camera": physics_only_overrides(),
    "physics + drive + 2 IR at 20 Hz, no camera": [NO_CAMERA],
    "physics + drive + 2 IR at 200 Hz, no camera": [NO_CAMERA, IR_200_HZ],
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
    """Builds stations with `cls` in place of IrSensor (add_ir_sensor looks it up)."""
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
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[NO_CAMERA]))
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
        sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[DRIVING, NO_CAMERA]))
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
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[DRIVING, NO_CAMERA]))
    sensor = sim.station.robots["corobot"].ir_sensors["front"]
    period, h = sensor.period, physics_step(sim.scenario.plant_config,
                                             sim.scenario.simulator_config)
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


WITHOUT_IR, WITH_IR_20, WITH_IR_200 = CONFIGURATIONS
RUNS = {
    WITHOUT_IR: (CONFIGURATIONS[WITHOUT_IR], None),
    NO_OP: (CONFIGURATIONS[WITH_IR_20], NoOpIrSensor),
    WITH_IR_20: (CONFIGURATIONS[WITH_IR_20], None),
    NO_OP_200: (CONFIGURATIONS[WITH_IR_200], NoOpIrSensor),
    WITH_IR_200: (CONFIGURATIONS[WITH_IR_200], None),
}
"""The real-time factor table's rows: name -> (overrides, IrSensor subclass or None)."""


def configuration_runs(repeats: int, seconds: float) -> dict[str, list[Run]]:
    """`repeats` runs of each of :data:`RUNS`, taken in turn (slow drifts of the load spread
    over all of them)."""
    runs: dict[str, list[Run]] = {}
    for _ in range(repeats):
        for name, (overrides, sensor) in RUNS.items():
            runs.setdefault(name, []).append(run_configuration(overrides, seconds, sensor))
    return runs


def median_run(runs: list[Run]) -> Run:
    """Each figure's median over `runs`."""
    return Run(*(statistics.median(getattr(r, f.name) for r in runs) for f in dc.fields(Run)))
