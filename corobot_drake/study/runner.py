"""One run of a study, as a Ray worker does it: load the run's scenario, simulate, measure.

`StudyWorker` is the worker's state (a Ray actor): the study and its scenario file. A run that
fails (a bad override, a simulation error) becomes an error row; it never stops the study.
"""

from __future__ import annotations

import math
import time
from collections import OrderedDict
from pathlib import Path

from corobot_drake.config.scenario import load_scenario, one_line
from corobot_drake.simulation import Simulation, diagram_key, quiet_drake_warnings
from corobot_drake.study.metrics import measure
from corobot_drake.study.spec import Run, Study

CACHE_SIZE = 3
"""Simulations a worker keeps built (each holds a diagram and its Context)."""
CHECK_PERIOD = 0.1
"""s of simulated time between checks whether every command has ended (`until: commands`)."""


def run_scenario(study: Study, scenario_file: Path, run: Run):
    """The run's scenario: the file, the study's overrides, then the run's parameters and
    seed; the cameras off unless the study asks for them."""
    scenario = load_scenario(scenario_file, overrides=[*study.overrides, *run.overrides()])
    if study.drive_test is not None:
        robot = scenario.robots.get(study.drive_test.robot)
        if robot is None:
            raise ValueError(f"drive_test: the scenario has no robot {study.drive_test.robot!r}")
        robot.commands = study.drive_test.commands(run.seed)
    if not study.cameras:
        for robot in scenario.robots.values():
            robot.camera.rgb = False
    return scenario


class SimulationCache:
    """The last few simulations a worker built, by `diagram_key`: a run whose diagram is
    already built resets it (`Simulation.reset`) instead of building again."""

    def __init__(self, size: int = CACHE_SIZE):
        self.size = size
        self._sims: OrderedDict[str, Simulation] = OrderedDict()

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
             cache: SimulationCache | None = None) -> dict:
    """The run's row: run, seed, parameters, metrics, status, error, and the timing columns
    (setup: built or reset; setup_seconds; wall_seconds, the whole run)."""
    start = time.perf_counter()
    row: dict = {"run": run.index, "seed": run.seed, **dict(run.params)}
    try:
        scenario = run_scenario(study, scenario_file, run)
        sim, row["setup"] = (cache or SimulationCache(0)).get(scenario)
        row["setup_seconds"] = round(time.perf_counter() - start, 4)
        starts = {name: (r.pose(), r.heading()) for name, r in sim.robots.items()}
        advance(sim, study)
        row.update(measure(sim, starts, study.metrics))
        row.update(status="ok", error="")
    except Exception as e:  # any failure is this run's error row
        row.update(status="error", error=one_line(e))
    row["wall_seconds"] = round(time.perf_counter() - start, 3)
    return row


class StudyWorker:
    """A worker's side of a study (a Ray actor: `ray.remote(StudyWorker)`)."""

    def __init__(self, study: Study, scenario_file: str):
        quiet_drake_warnings()
        self.study, self.scenario_file = study, Path(scenario_file)
        self.cache = SimulationCache()

    def run(self, run: Run) -> dict:
        return simulate(self.study, self.scenario_file, run, self.cache)


def finite_or_text(value):
    """CSV cell text: numbers in full precision (repr), NaN as empty."""
    if isinstance(value, float):
        return "" if math.isnan(value) else repr(value)
    return value
