"""The study file: a typed YAML `Study`, loaded like a scenario (one-line errors with the
file, the line and the field), and its expansion into runs.

    scenario: ../corobot.yaml       # relative to the study file
    duration: 8.0                   # simulated seconds per run (a cap with `until: commands`)
    seeds: 4                        # runs per grid point (random_seed 1..N), or a list
    grid:                           # cartesian product; keys are dotted scenario paths
      robots.corobot.drive.motor_torque_scaling: [6.0, 10.16]
    random:                         # drawn per run from the run's seed
      robots.corobot.contact.friction: !Uniform {min: 0.4, max: 0.6}
    overrides:                      # YAML merged into every run, as --override
      - "robots: {corobot: {commands: [!SetPower {left: 1.0, right: 0.8}]}}"
    metrics: [x, y, speed, max_tilt_deg]

A grid or random path is one of three kinds (`path_kind`): a scenario path
(`robots.corobot.drive.slew_rate`), merged as an --override; a scenario path through a list
index (`robots.corobot.commands.0.distance`: the first command's distance), set on the loaded
scenario and checked again; or a program field (`box_approach.power`), set on the study's
program for the run (`programs`).
"""


import dataclasses as dc
import hashlib
import itertools
import json
import math
import sys
from pathlib import Path

import numpy as np

from corobot_drake.config.scenario import read_text
from corobot_drake.config.validate import LayerChecks, load_layer
from corobot_drake.limits import Range, bounded
from corobot_drake.resources import shipped_scenario
from corobot_drake.study.programs import PROGRAMS, BoxApproach, DriveTest

UNTIL = ("duration", "commands")
MAX_RUNS = 100_000
"""Most runs a study may expand to (grid points x seeds): the largest shipped has 128, and a
run takes seconds; 10^7 runs would take a year and their list alone gigabytes."""
RUN_DURATION = Range(0.0, 1e5, low_open=True, unit="s", why="simulated per run; a day at most")
SETTLE = Range(0.0, 1e3, unit="s")
SEED = Range(0, 2**31 - 1, why="a run's random_seed")


@dc.dataclass
class Uniform:
    """A value drawn uniformly from [min, max)."""

    min: float = 0.0
    max: float = 1.0
    """max >= min, both finite."""


@dc.dataclass
class Normal:
    """A value drawn from a normal distribution."""

    mean: float = 0.0
    sd: float = bounded(1.0, Range(0.0, 1e300, why="a standard deviation"))


GridValue = bool | int | float | str | None
"""A grid or `!Choice` value as the file has it. null loads too, so that each value is checked
in order against its field's own type (`resolve.value_problem`): the first wrong one is named,
not a null further on as no scalar at all."""


@dc.dataclass
class Choice:
    """One of `values`, equally likely."""

    values: list[GridValue] = dc.field(default_factory=list)


Distribution = Uniform | Normal | Choice
Scalar = bool | int | float | str


@dc.dataclass
class Study:
    """A batch of runs of one scenario (see the module docstring for a file)."""

    scenario: str = ""
    """The scenario file, relative to the study file (or absolute)."""
    duration: float = bounded(10.0, RUN_DURATION)
    """Simulated seconds per run; with `until: commands`, the most a run may take."""
    until: str = "duration"
    """`duration`: every run lasts `duration`; `commands`: a run ends `settle` s after every
    robot's last command has ended (or at `duration`)."""
    settle: float = bounded(1.0, SETTLE)
    """s simulated after the last command ends (`until: commands`), so the robot is at rest."""
    seeds: list[int] | int = 1
    """Runs per grid point: N gives random_seed 1..N; a list gives those seeds."""
    grid: dict[str, list[GridValue]] = dc.field(default_factory=dict)
    """Dotted scenario path -> values; every combination is a grid point."""
    random: dict[str, Distribution] = dc.field(default_factory=dict)
    """Dotted scenario path -> distribution, drawn per run from its seed."""
    overrides: list[str] = dc.field(default_factory=list)
    """YAML texts merged over the scenario in every run (after the file, before the grid)."""
    metrics: list[str] = dc.field(default_factory=lambda: ["x", "y", "yaw_deg"])
    """Names from the metrics registry (`corobot_drake.study.metrics.METRICS`), or your own
    as `module:function` (the module beside the study file or importable), per robot."""
    drive_test: DriveTest | None = None
    """The book's drive test as each run's script for one robot (`{loops, power, robot}`):
    random legs drawn from the run's seed, replacing that robot's commands."""
    box_approach: BoxApproach | None = None
    """Drive into the box behind the robot (`{direction, angle_deg, power, robot}`): turns
    the robot and replaces its commands."""
    cameras: bool = False
    """Render the robots' cameras (off by default: no metric reads them, and they cost)."""


@dc.dataclass(frozen=True)
class Run:
    """One simulation of a study: its index, seed and parameter values by dotted path."""

    index: int
    seed: int
    point: int
    """Index of its grid point (runs of one point differ only in seed and random draws)."""
    params: tuple[tuple[str, Scalar], ...]

    def overrides(self) -> list[str]:
        """The run's scenario parameters without a list index, as --override YAML texts (JSON
        is YAML), and its seed."""
        texts = [json.dumps(_nest(path, value)) for path, value in self.params
                 if path_kind(path) == "override"]
        return [*texts, json.dumps({"random_seed": self.seed})]

    def indexed(self) -> list[tuple[str, Scalar]]:
        """The run's scenario parameters through a list index (`set_path` sets them)."""
        return [(p, v) for p, v in self.params if path_kind(p) == "indexed"]

    def program(self, study: Study, name: str):
        """The study's program `name` with this run's values of its fields, or None."""
        program = getattr(study, name)
        if program is None:
            return None
        prefix = name + "."
        values = {p[len(prefix):]: v for p, v in self.params if p.startswith(prefix)}
        return dc.replace(program, **values) if values else program


def path_kind(path: str) -> str:
    """`program` (its first key is a program field of the study), `indexed` (a key is a list
    index) or `override`."""
    keys = path.split(".")
    if keys[0] in PROGRAMS:
        return "program"
    return "indexed" if any(k.isdigit() for k in keys) else "override"


def load_study(filename: str | Path) -> Study:
    """Reads and checks a study file, as a scenario is read, and against its scenario
    (`resolve`); ScenarioError (one line with the file, the line and the field) for anything
    wrong."""
    study, checks = load_layer(str(filename), read_text(filename, kind="a study is a YAML file"),
                               Study)
    checks.validate(study)  # every number against its bound (`bounded`), floats finite
    _validate(study, checks)
    from corobot_drake.study.resolve import check_against_scenario

    check_against_scenario(study, filename, checks)
    return study


def _validate(study: Study, checks: LayerChecks) -> None:
    """Checks of meaning, failing at the field's line (`checks.fail`)."""
    from corobot_drake.study.metrics import METRICS, NEEDS_SECONDS, load_user_metrics

    if not study.scenario:
        checks.fail("scenario", "name the scenario file")
    if study.until not in UNTIL:
        checks.fail("until", f"{study.until!r} is not one of {', '.join(UNTIL)}")
    _check_runs(study, checks)
    for path, dist in study.random.items():
        if path in study.grid:
            checks.fail(f"random.{path}", "is also a grid parameter")
        if isinstance(dist, Uniform) and not dist.min <= dist.max:
            checks.fail(f"random.{path}.max", f"must be >= min ({dist.min:g}); got {dist.max:g}")
        if isinstance(dist, Uniform) and not math.isfinite(dist.max - dist.min):
            checks.fail(f"random.{path}.max", f"max - min must be a finite number (at most "
                        f"{sys.float_info.max:.3g}); got {dist.max:g} - {dist.min:g}")
        if isinstance(dist, Choice) and not dist.values:
            checks.fail(f"random.{path}.values", "needs at least one value")
    for name in PROGRAMS:
        program = getattr(study, name)
        if program is not None and (problem := program.check()):
            checks.fail(name, problem)
    if study.drive_test is not None and study.box_approach is not None:
        checks.fail("box_approach", "a study has a drive_test or a box_approach, not both: "
                    "each replaces the robot's commands (split the study)")
    for section, paths in (("grid", study.grid), ("random", study.random)):
        for path in paths:
            _check_program_path(study, checks, f"{section}.{path}", path)
    for i, name in enumerate(study.metrics):
        if name not in METRICS and ":" not in name:
            checks.fail(f"metrics[{i}]", f"unknown metric {name!r}; known: "
                        + ", ".join(sorted(METRICS)) + "; or your own, module:function")
        try:
            load_user_metrics([name], Path(checks.source).parent)
        except ValueError as e:
            checks.fail(f"metrics[{i}]", str(e))
        if study.duration < NEEDS_SECONDS.get(name, 0.0):  # every run would be an error row
            checks.fail(f"metrics[{i}]", f"{name} needs runs of at least "
                        f"{NEEDS_SECONDS[name]:g} s; this study's last {study.duration:g} s "
                        "(`duration`)")


def _check_runs(study: Study, checks: LayerChecks) -> None:
    """Seeds and grid values that make at least one run and at most MAX_RUNS."""
    if isinstance(study.seeds, int) and not 1 <= study.seeds <= MAX_RUNS:
        checks.fail("seeds", f"must be in [1, {MAX_RUNS}] (runs per grid point), or a list "
                    f"of seeds; got {study.seeds}")
    if isinstance(study.seeds, list):
        if not study.seeds:
            checks.fail("seeds", "an empty list; list at least one seed")
        if len(set(study.seeds)) != len(study.seeds):
            checks.fail("seeds", "a seed is listed twice")
        for i, seed in enumerate(study.seeds):
            if problem := SEED.problem(seed):
                checks.fail(f"seeds[{i}]", problem)
    runs = len(seeds(study)) if isinstance(study.seeds, list) else study.seeds
    for path, values in study.grid.items():
        if not values:
            checks.fail(f"grid.{path}", "needs at least one value")
        runs *= len(values)
        if runs > MAX_RUNS:
            checks.fail(f"grid.{path}", f"the study expands to more than {MAX_RUNS} runs "
                        "(grid points x seeds), the most a study may have; split it")


def _check_program_path(study: Study, checks: LayerChecks, where: str, path: str) -> None:
    """A program path names a field of a program the study has (and each grid value of it
    passes the program's check)."""
    if path_kind(path) != "program":
        return
    name, _, field = path.partition(".")
    program = getattr(study, name)
    if program is None:
        checks.fail(where, f"the study has no {name}: add `{name}: {{}}` to vary its fields")
    names = [f.name for f in dc.fields(program)]
    if field not in names:
        checks.fail(where, f"{name} has no field {field!r}; fields: {', '.join(names)}")
    for i, value in enumerate(study.grid.get(path, [])):  # in order, each at its line
        if problem := dc.replace(program, **{field: value}).check():
            checks.fail(f"{where}[{i}]", problem)


def scenario_path(study: Study, study_file: str | Path) -> Path:
    """The study's scenario file: `scenario` relative to the study file, else, for a bare
    file name that is not there, the shipped scenario of that name (`maze.yaml`), as the
    command line finds it (`resources.scenario_path`)."""
    beside = (Path(study_file).resolve().parent / study.scenario).resolve()
    return beside if beside.exists() else shipped_scenario(study.scenario) or beside


DIGEST_COLUMN = "study_digest"
"""The runs.csv column holding each row's `study_digest`."""
_PER_ROW = ("scenario", "seeds", "grid", "random")
"""Study fields a row's own cells say (its seed and parameter values), or the digest holds
otherwise (the scenario file's content, not its path)."""


def study_digest(study: Study, study_file: str | Path) -> str:
    """What makes a run's row this study's beyond its run index, seed and parameter values
    (which `--resume` compares cell by cell): the scenario file's content, the overrides, the
    run length, the metrics, the programs and the cameras. 12 hex digits of their SHA-256."""
    fields = {k: v for k, v in dc.asdict(study).items() if k not in _PER_ROW}
    digest = hashlib.sha256(json.dumps(fields, sort_keys=True, default=repr).encode())
    digest.update(scenario_path(study, study_file).read_bytes())
    return digest.hexdigest()[:12]


def study_path(name: str | Path) -> Path:
    """The study file `name` names: a path as it is when it exists, else, for a bare file
    name, the shipped study of that name (`tiny.yaml` from any folder, also from a wheel)."""
    path = Path(name)
    return path if path.exists() else shipped_scenario(str(name), "studies") or path


def seeds(study: Study) -> list[int]:
    return list(range(1, study.seeds + 1)) if isinstance(study.seeds, int) else study.seeds


def expand(study: Study) -> list[Run]:
    """Every run of the study, in a fixed order: grid points (cartesian, keys in file order),
    then seeds. Random draws depend only on the seed and the parameter's path."""
    keys = list(study.grid)
    runs = []
    for point, values in enumerate(itertools.product(*(study.grid[k] for k in keys))):
        for seed in seeds(study):
            params = list(zip(keys, values, strict=True))
            params += [(path, draw(dist, seed, path)) for path, dist in study.random.items()]
            runs.append(Run(len(runs), seed, point, tuple(params)))
    return runs


def draw(dist: Distribution, seed: int, path: str) -> Scalar:
    """The value of `dist` for this seed and parameter: the same on any worker or machine."""
    digest = hashlib.sha256(f"{seed}:{path}".encode()).digest()
    rng = np.random.default_rng(int.from_bytes(digest[:8], "little"))
    if isinstance(dist, Uniform):
        return float(rng.uniform(dist.min, dist.max))
    if isinstance(dist, Normal):
        return float(rng.normal(dist.mean, dist.sd))
    return dist.values[int(rng.integers(len(dist.values)))]


def _nest(path: str, value: Scalar) -> dict:
    """`a.b.c`, v -> {"a": {"b": {"c": v}}}."""
    nested: object = value
    for key in reversed(path.split(".")):
        nested = {key: nested}
    return nested
