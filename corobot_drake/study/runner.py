"""One run of a study, as a Ray worker does it: load the run's scenario, simulate, measure.

`StudyWorker` is the worker's state (a Ray actor): the study and its scenario file. A run that
fails (a bad override, a simulation error) becomes an error row; it never stops the study.
"""

from __future__ import annotations

import dataclasses as dc
import math
import time
from collections import OrderedDict
from pathlib import Path

from corobot_drake.config.scenario import load_scenario, one_line
from corobot_drake.config.validate import LayerChecks
from corobot_drake.sensors.registry import KINDS
from corobot_drake.simulation import Simulation, diagram_key, quiet_drake_warnings
from corobot_drake.study.metrics import measure, reads_ir
from corobot_drake.study.programs import PROGRAMS
from corobot_drake.study.spec import Run, Scalar, Study

CACHE_SIZE = 3
"""Simulations a worker keeps built (each holds a diagram and its Context)."""
TIMING_COLUMNS = ("setup", "setup_seconds", "wall_seconds", "cpu_seconds", "finished_seconds")
"""Columns that depend on the clock or the worker (everything else is deterministic)."""
CHECK_PERIOD = 0.1
"""s of simulated time between checks whether every command has ended (`until: commands`)."""


def study_scenario(study: Study, scenario_file: Path):
    """What every run of the study starts from: the file, then the study's overrides."""
    return load_scenario(scenario_file, overrides=study.overrides)


def run_scenario(study: Study, scenario_file: Path, run: Run, base=None, user=None):
    """The run's scenario: the file, the study's overrides (`base`, their `study_scenario`, if
    given: a worker reads them once), then the run's parameters and seed, the study's
    programs, then the run's parameters through a list index (checked as a scenario is); the
    cameras off unless the study asks for them, every other sensor off (`SensorKind.off`)
    unless a metric reads the sensors (`metrics.reads_ir`, of the study's `user` metrics too:
    nothing else in a scripted run does, and their scans cost a few per cent of a run)."""
    # yaml_load_typed merges a layer into a deep copy of `base`: the run never changes it.
    if base is None:
        base = study_scenario(study, scenario_file)
    scenario = load_scenario(overrides=run.overrides(), defaults=base)
    for name in PROGRAMS:
        program = run.program(study, name)
        if program is not None:
            if problem := program.check():
                raise ValueError(f"{name}: {problem}")
            program.apply(scenario, run.seed)
    indexed = run.indexed()
    for path, value in indexed:
        set_path(scenario, path, value)
    if indexed:
        # The values come from the study's grid, not from a line of YAML.
        LayerChecks.of_object("study grid").validate(scenario)
    reads = reads_ir(study.metrics, user)
    for robot in scenario.robots.values():
        for kind in KINDS:
            # An image kind renders as the study says; the others, for a metric that reads.
            if kind.off is None or (study.cameras if kind.renders else reads):
                continue
            for sensor in getattr(robot, kind.field).values():
                for field, value in kind.off.items():
                    setattr(sensor, field, value)
    return scenario


def set_path(scenario, path: str, value: Scalar) -> None:
    """Sets the field at a dotted path (keys, attributes, list indices) of a loaded scenario;
    ValueError (one line naming the path) when the path or the value's type does not fit."""
    *keys, last = path.split(".")
    node = scenario
    for depth, key in enumerate(keys):
        node = _child(node, key, ".".join(keys[:depth + 1]))
    old = _child(node, last, path)
    if isinstance(old, float) and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    if type(old) is not type(value):
        raise ValueError(f"{path}: expected {type(old).__name__}, got {value!r}")
    if isinstance(node, list):
        node[int(last)] = value
    elif isinstance(node, dict):
        node[last] = value
    else:
        setattr(node, last, value)


def _child(node, key: str, where: str):
    if isinstance(node, list):
        if not (key.isdigit() and int(key) < len(node)):
            raise ValueError(f"{where}: the list has {len(node)} items (index from 0)")
        return node[int(key)]
    if isinstance(node, dict):
        if key not in node:
            raise ValueError(f"{where}: no such key; keys: {', '.join(map(str, node))}")
        return node[key]
    if not dc.is_dataclass(node) or key not in {f.name for f in dc.fields(node)}:
        raise ValueError(f"{where}: {type(node).__name__} has no field {key!r}")
    return getattr(node, key)


class SimulationCache:
    """What a worker keeps between the runs of a study: the study's scenario (`base`) and the
    last few simulations it built, by `diagram_key`: a run whose diagram is already built
    resets it (`Simulation.reset`) instead of building again."""

    def __init__(self, size: int = CACHE_SIZE):
        self.size = size
        self._sims: OrderedDict[str, Simulation] = OrderedDict()
        self._base = None

    def base(self, study: Study, scenario_file: Path):
        """`study_scenario`, read once (its error too: every run's error row says it)."""
        if self._base is None:
            try:
                self._base = study_scenario(study, scenario_file)
            except Exception as e:
                self._base = e
        if isinstance(self._base, Exception):
            raise self._base
        return self._base

    def get(self, scenario) -> tuple[Simulation, str]:
        """A simulation at the start of `scenario`, and `reset` or `built`."""
        key = diagram_key(scenario)
        sim = self._sims.pop(key, None)
        if sim is not None:
            sim.reset(scenario, key=key)
            how = "reset"
        else:
            sim, how = Simulation(scenario), "built"
        self._sims[key] = sim
        while len(self._sims) > self.size:
            self._sims.popitem(last=False)
        return sim, how


def commands_ended(sim: Simulation) -> bool:
    """True once every robot has started and ended all of its scripted commands."""
    for name, robot in sim.robots.items():
        log = robot.command_log()
        if len(log) < len(sim.scenario.robots[name].commands):
            return False
        if any(r.end_time is None for r in log):
            return False
    return True


def advance(sim: Simulation, study: Study) -> None:
    end = sim.time + study.duration
    if study.until == "duration":
        sim.advance_to(end)
        return
    while sim.time < end - 1e-12 and not commands_ended(sim):
        sim.advance_to(min(end, sim.time + CHECK_PERIOD))
    sim.advance_to(min(end, sim.time + study.settle))


def simulate(study: Study, scenario_file: Path, run: Run,
             cache: SimulationCache | None = None, user=None) -> dict:
    """The run's row: run, seed, parameters, metrics, status, error, and the timing columns
    (setup: built or reset; setup_seconds; wall_seconds, the whole run; cpu_seconds, the
    worker process's CPU time for the whole run, which a loaded machine changes less);
    `user`: the study's own metrics (`metrics.load_user_metrics`)."""
    start, cpu_start = time.perf_counter(), time.process_time()
    row: dict = {"run": run.index, "seed": run.seed, **dict(run.params)}
    try:
        cache = cache or SimulationCache(0)
        scenario = run_scenario(study, scenario_file, run, cache.base(study, scenario_file),
                                user)
        sim, row["setup"] = cache.get(scenario)
        row["setup_seconds"] = round(time.perf_counter() - start, 4)
        starts = {name: (r.pose(), r.heading()) for name, r in sim.robots.items()}
        advance(sim, study)
        row.update(measure(sim, starts, study.metrics, user))
        row.update(status="ok", error="")
    except Exception as e:  # any failure is this run's error row
        row.update(error_row(run, one_line(e)))
    row["wall_seconds"] = round(time.perf_counter() - start, 3)
    row["cpu_seconds"] = round(time.process_time() - cpu_start, 3)
    return row


def error_row(run: Run, error: str) -> dict:
    """The row of a run that failed: its run, seed and parameters, `error` (one line)."""
    return {"run": run.index, "seed": run.seed, **dict(run.params), "status": "error",
            "error": error}


class StudyWorker:
    """A worker's side of a study (a Ray actor: `ray.remote(StudyWorker)`)."""

    def __init__(self, study: Study, scenario_file: str, user=None):
        quiet_drake_warnings()
        self.study, self.scenario_file, self.user = study, Path(scenario_file), user
        self.cache = SimulationCache()

    def run(self, run: Run) -> dict:
        return simulate(self.study, self.scenario_file, run, self.cache, self.user)


def finite_or_text(value):
    """CSV cell text: numbers in full precision (repr), NaN as empty."""
    if isinstance(value, float):
        return "" if math.isnan(value) else repr(float(value))  # numpy's repr names its type
    return value
