"""The study engine: the study file, its expansion into runs, and studies run on Ray (a
separately started head, conftest's `ray_head`, joined by address or connected to)."""

import csv
import math
import re
from pathlib import Path

import pytest

from corobot_drake.config.scenario import ScenarioError
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.study import engine
from corobot_drake.study.spec import Normal, Uniform, draw, expand, load_study
from lab.processes import alive, descendants

TINY = """\
scenario: {scenario}
duration: 0.3
seeds: 2
grid:
  robots.corobot.drive.motor_torque_scaling: [{scalings}]
random:
  robots.corobot.contact.friction: !Uniform {{min: 0.45, max: 0.55}}
overrides:
  - "robots: {{corobot: {{commands: [!SetPower {{left: 1.0, right: 1.0}}]}}}}"
metrics: [x, speed, max_tilt_deg, ir]
"""


def write_study(tmp_path: Path, scalings: str = "6.0, 10.16", name: str = "tiny.yaml") -> Path:
    path = tmp_path / name
    path.write_text(TINY.format(scenario=DEFAULT_SCENARIO, scalings=scalings))
    return path


def rows(path: Path) -> list[dict]:
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


def without_timing(table: list[dict]) -> list[dict]:
    return [{k: v for k, v in r.items() if k not in engine.TIMING_COLUMNS} for r in table]


# --- the study file, without Ray ---------------------------------------------------------

def test_expand_is_grid_points_then_seeds_with_draws_fixed_by_seed(tmp_path):
    study = load_study(write_study(tmp_path))
    runs = expand(study)
    assert [(r.index, r.point, r.seed) for r in runs] == [(0, 0, 1), (1, 0, 2), (2, 1, 1),
                                                          (3, 1, 2)]
    assert [dict(r.params)["robots.corobot.drive.motor_torque_scaling"] for r in runs] == [
        6.0, 6.0, 10.16, 10.16]
    friction = [dict(r.params)["robots.corobot.contact.friction"] for r in runs]
    assert friction[0] == friction[2] != friction[1] == friction[3]  # same seed, same draw
    assert all(0.45 <= f < 0.55 for f in friction)


def test_draws_are_deterministic_and_distributed():
    values = [draw(Uniform(1.0, 2.0), seed, "a.b") for seed in range(2000)]
    assert values == [draw(Uniform(1.0, 2.0), seed, "a.b") for seed in range(2000)]
    assert min(values) >= 1.0 and max(values) < 2.0
    assert abs(sum(values) / len(values) - 1.5) < 0.03  # 5 sd of the mean of 2000 uniforms
    normal = [draw(Normal(0.0, 1.0), seed, "c") for seed in range(2000)]
    assert abs(sum(normal) / 2000) < 0.12  # 5 sd of the mean


def test_seeds_may_be_a_list(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text(f"scenario: {DEFAULT_SCENARIO}\nseeds: [7, 3]\n")
    assert [r.seed for r in expand(load_study(path))] == [7, 3]


@pytest.mark.parametrize("text, expected", [
    ("scenario: x.yaml\nduration: fast\n", ":2: duration: expected a number"),
    ("scenario: x.yaml\nseeds: 0\n", ":2: seeds: must be in [1, 100000]"),
    ("scenario: x.yaml\nmetrics: [x, wobble]\n", ":2: metrics[1]: unknown metric 'wobble'"),
    ("scenario: x.yaml\nrandom: {a.b: !Gauss {}}\n", ":2: random.a.b: unknown tag !Gauss"),
    ("scenario: x.yaml\ngrid: {a.b: []}\n", ":2: grid.a.b: needs at least one value"),
    ("scenario: x.yaml\nuntil: forever\n", "until: 'forever' is not one of"),
    ("scenario: x.yaml\nduratoin: 3\n", ":2: duratoin: unknown field"),
])
def test_a_bad_study_is_one_line_naming_the_field(tmp_path, text, expected):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ScenarioError) as e:
        load_study(path)
    message = str(e.value)
    assert message.startswith(str(path)) and expected in message and "\n" not in message


S = f"scenario: {DEFAULT_SCENARIO}\n"


@pytest.mark.parametrize("text, expected", [
    # the scenario and the overrides, read at load with the study file's line
    ("scenario: nowhere.yaml\n", r":1: scenario: .*nowhere.yaml: cannot read the file \(No such"),
    (S + "overrides:\n  - 'robots: {corobot: {drive: {slew_rate: -1}}}'\n",
     r":3: overrides\[0\]: robots.corobot.drive.slew_rate: must be in \(0, 10000\]"),
    # every grid and random path resolved against the scenario, each value typed and bounded
    (S + "grid: {robots.corobot.drive.slew_rtae: [1]}\n",
     r":2: grid.robots.corobot.drive.slew_rtae: robots.corobot.drive \(Drive\) has no field "
     r"'slew_rtae' \(did you mean 'slew_rate'\?\); fields: motor_torque_scaling, slew_rate"),
    (S + "random: {robots.corbot.contact.friction: !Uniform {}}\n",
     r":2: random.robots.corbot.contact.friction: robots has no 'corbot' \(did you mean "
     r"'corobot'\?\); it has: corobot"),
    (S + "grid: {robots.corobot.commands.0.power: [0.5]}\n",
     r"grid.robots.corobot.commands.0.power: robots.corobot.commands: the list has 0 items"),
    (S + "grid:\n  robots.corobot.drive.slew_rate:\n    - 5\n    - true\n",
     r":5: grid.robots.corobot.drive.slew_rate\[1\]: expected a number, got True"),
    (S + "grid: {robots.corobot.drive.slew_rate: [5, -1]}\n",
     r"slew_rate\[1\]: must be in \(0, 10000\] rad/s\^2; got -1"),
    (S + "grid: {robots.corobot.drive.slew_rate: [[1]]}\n",
     r"slew_rate\[0\]: expected true or false, an integer, a number or text, got a list"),
    (S + "grid: {plant_config.time_step: [0.001, 0.5]}\n",
     r"plant_config.time_step\[1\]: must be 0 .*or in \[0.0001, 0.02\] s"),
    (S + "grid: {robots.corobot.pose: [1]}\n",
     r"robots.corobot.pose is a Transform, not a single value"),
    (S + "random: {robots.corobot.ir_sensors.front.samples: !Uniform {min: 1, max: 3}}\n",
     r"a !Uniform draws a number, and the field takes an integer: use a !Choice"),
    (S + "random: {robots.corobot.contact.friction: !Uniform {min: -1e308, max: 1.7e308}}\n",
     r"friction.max: max - min must be a finite number"),
    # what the study sets itself
    (S + "grid: {random_seed: [1, 2]}\n", r"grid.random_seed: a study sets random_seed itself"),
    (S + "grid: {simulation_duration: [1, 2]}\n",
     r"grid.simulation_duration: a study sets simulation_duration itself: every run lasts the "
     r"study's `duration`"),
    (S + "seeds: [3, -1]\n", r"seeds\[1\]: must be in \[0, 2147483647\]"),
    # programs: bounded and typed fields, one at a time
    (S + "drive_test: {loops: 1000000}\n", r":2: drive_test.loops: must be in \[1, 100\]"),
    (S + "drive_test: {}\ngrid: {drive_test.loops: [1, 2.5]}\n",
     r":3: grid.drive_test.loops\[1\]: loops: expected an integer, got 2.5"),
    (S + "drive_test: {}\nbox_approach: {}\n", r":3: box_approach: a study has a drive_test or "
     r"a box_approach, not both"),
    # a program's robot, and each grid value of it, is one of the scenario's
    (S + "drive_test: {robot: nobody}\n",
     r":2: drive_test.robot: the scenario has no robot 'nobody'; it has: corobot"),
    (S + "box_approach: {}\ngrid:\n  box_approach.robot:\n    - corobot\n    - nobody\n",
     r":6: grid.box_approach.robot\[1\]: the scenario has no robot 'nobody'"),
    # mixed grid values: each against the field's own type, in order (the first wrong one;
    # a null further on was named first, as no scalar at all)
    (S + "grid:\n  robots.corobot.drive.motor_torque_scaling: [10.0, fast, null, true]\n",
     r":3: grid.robots.corobot.drive.motor_torque_scaling\[1\]: expected a number, got 'fast'$"),
    (S + "grid:\n  robots.corobot.drive.motor_torque_scaling: [10.0, null, fast]\n",
     r":3: grid.robots.corobot.drive.motor_torque_scaling\[1\]: expected a number, got null$"),
    (S + "random: {robots.corobot.drive.slew_rate: !Choice {values: [5, null]}}\n",
     r":2: random.robots.corobot.drive.slew_rate.values\[1\]: expected a number, got null$"),
    (S + "drive_test: {}\ngrid: {drive_test.robot: [corobot, null]}\n",
     r":3: grid.drive_test.robot\[1\]: robot: expected text, got null$"),
    # a date (no scalar a field takes), at its line
    (S + "grid:\n  robots.corobot.drive.motor_torque_scaling:\n    - 10.0\n    - 2026-01-01\n",
     r":5: grid.robots.corobot.drive.motor_torque_scaling\[1\]: .* got a date \('2026-01-01'\)"),
    # a metric a run of the study's duration cannot give
    (S + "duration: 0.3\nmetrics: [x, steady_speed]\n",
     r":3: metrics\[1\]: steady_speed needs runs of at least 1 s; this study's last 0.3 s"),
    (S + "until: 5\n", r":2: until: expected text, got a number \('5'\); quote it for text"),
    # user metrics: module:function, loaded at load
    (S + "metrics: [x, no_such_module:f]\n",
     r"metrics\[1\]: no_such_module:f: cannot import 'no_such_module' \(No module named"),
    (S + "metrics: [math:no_such_function]\n", r"math .* has no function 'no_such_function'"),
])
def test_a_study_is_checked_against_its_scenario_at_load(tmp_path, text, expected):
    """Everything a run would find wrong with the scenario, its overrides, a path or a value
    of one path stops the study as it loads, at its line: no worker starts."""
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ScenarioError) as e:
        load_study(path)
    message = str(e.value)
    assert message.startswith(str(path)) and "\n" not in message
    assert re.search(expected, message), message


def test_the_command_line_ends_a_study_wrong_for_its_scenario_in_one_line(tmp_path, capsys):
    """A program's robot the scenario lacks is found as the study loads (it was a ValueError
    out of the command line): one line naming the file, the line and the field, exit 2."""
    from corobot_drake.study.__main__ import main

    path = tmp_path / "bad.yaml"
    path.write_text(S + "duration: 0.3\ndrive_test: {robot: nobody}\n")
    assert main([str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err == (f"error: {path}:3: drive_test.robot: the scenario has no robot 'nobody'; "
                   "it has: corobot\n")
    assert not (tmp_path / "out").exists()


def test_a_study_s_plots_have_a_title_and_units(tmp_path, monkeypatch):
    """Each plot is titled with the study and the metric; its axes carry the metric's unit
    (the registry's) and the parameter's (its scenario field's bound's)."""
    from matplotlib.figure import Figure

    from corobot_drake.study import report
    from corobot_drake.study.resolve import parameter_units

    saved = {}
    monkeypatch.setattr(Figure, "savefig", lambda fig, path, **_: saved.update({
        Path(path).name: fig}))
    study_file = write_study(tmp_path)
    study = load_study(study_file)
    table = [{"run": str(r.index), "seed": str(r.seed), **{k: str(v) for k, v in r.params},
              "corobot.speed": str(0.3 + r.index), "corobot.ir.rear": "0.7", "status": "ok",
              "error": ""} for r in expand(study)]
    report.plot(tmp_path, table, study, "tiny", parameter_units(study, study_file))
    speed, ir = saved["corobot.speed.png"], saved["corobot.ir.rear.png"]
    assert speed.get_suptitle() == "tiny: corobot.speed (4 runs)"
    assert speed.axes[0].get_xlabel() == "motor_torque_scaling (rad/s)"
    assert speed.axes[0].get_ylabel() == "corobot.speed (m/s)"
    assert ir.axes[0].get_ylabel() == "corobot.ir.rear (m)"
    no_grid = load_study(study_file)
    no_grid.grid = {}
    report.plot(tmp_path, table, no_grid, "tiny")  # a histogram over the runs
    assert saved["corobot.speed.png"].axes[0].get_xlabel() == "corobot.speed (m/s)"


USER_METRICS = """\
import math

def lateral_speed(run):
    return run.robot.velocity().lateral

def front_ir(run):
    return run.robot.ir("front").raw
front_ir.reads_ir = True
"""


def test_a_user_metric_is_module_colon_function(tmp_path):
    """`module:function` beside the study file: loaded at load, measured like a registered
    metric (a column per robot), the IR sensors kept on when it says it reads them."""
    from corobot_drake.study.metrics import load_user_metrics
    from corobot_drake.study.runner import run_scenario, simulate

    (tmp_path / "my_metrics.py").write_text(USER_METRICS)
    path = tmp_path / "s.yaml"
    path.write_text(S + "duration: 0.5\nmetrics: [speed, my_metrics:lateral_speed]\n"
                    "overrides: ['robots: {corobot: {commands: [!SetPower {left: 0.5, right: "
                    "0.5}]}}']\n")
    study = load_study(path)
    user = load_user_metrics(study.metrics, tmp_path)
    (run,) = expand(study)
    row = simulate(study, DEFAULT_SCENARIO, run, user=user)
    assert row["status"] == "ok", row["error"]
    assert row["corobot.speed"] > 0.1  # driving straight ahead: hardly sideways
    assert abs(row["corobot.my_metrics:lateral_speed"]) < 0.01 * row["corobot.speed"]
    sensors = run_scenario(study, DEFAULT_SCENARIO, run, user=user).robots["corobot"].ir_sensors
    assert not any(s.enabled for s in sensors.values())
    study.metrics = ["my_metrics:front_ir"]
    user = load_user_metrics(study.metrics, tmp_path)
    sensors = run_scenario(study, DEFAULT_SCENARIO, run, user=user).robots["corobot"].ir_sensors
    assert all(s.enabled for s in sensors.values())


def test_a_study_names_a_shipped_scenario_or_study_by_name_from_any_folder(tmp_path,
                                                                          monkeypatch):
    """`scenario: maze.yaml` where no such file is beside the study is the shipped scenario,
    as `python -m corobot_drake maze.yaml` finds it; a file beside the study comes first. The
    study file itself may be a shipped one's name (`tiny.yaml`)."""
    from corobot_drake.resources import SCENARIOS_DIR
    from corobot_drake.study.spec import scenario_path, study_path

    monkeypatch.chdir(tmp_path)
    path = tmp_path / "s.yaml"
    path.write_text("scenario: maze.yaml\nduration: 0.5\nmetrics: [x]\n")
    study = load_study(path)  # resolved against the maze's scenario at load
    assert scenario_path(study, path) == SCENARIOS_DIR / "maze.yaml"
    (tmp_path / "maze.yaml").write_text((SCENARIOS_DIR / "corobot.yaml").read_text())
    assert scenario_path(study, path) == tmp_path / "maze.yaml"
    assert study_path("tiny.yaml") == SCENARIOS_DIR / "studies" / "tiny.yaml"
    assert study_path("missing.yaml") == Path("missing.yaml")  # read, and refused, as a path
    with pytest.raises(ScenarioError, match=r"s\.yaml:1: scenario: .*no-such\.yaml"):
        path.write_text("scenario: no-such.yaml\nduration: 0.5\nmetrics: [x]\n")
        load_study(path)


@pytest.mark.parametrize("arguments, expected", [
    ({"workers": -1}, r"^workers must be None .* or a whole number in \[1, 1024\], got -1$"),
    ({"workers": 0}, r"got 0$"),
    ({"workers": 1025}, r"got 1025$"),
    ({"workers": 2.5}, r"^workers must be .*got 2\.5$"),
    ({"workers": True}, r"^workers must be .*got True$"),
    ({"workers": "4"}, r"^workers must be .*got '4'$"),
    ({"address": 6379}, r"^address must be None .* as a string .*got 6379$"),
    ({"resume": "no"}, r"^resume must be True or False, got 'no'$"),
    ({"progress": None}, r"^progress must be True or False, got None$"),
    ({"out_dir": None}, r"^out_dir must be a non-empty path \(str or Path\), got None$"),
    ({"study_file": ""}, r"^study_file must be a non-empty path"),
])
def test_run_study_checks_its_arguments_before_anything_runs(tmp_path, arguments, expected):
    """From Python as on the command line: a bad argument is a ValueError naming it and what
    it allows, before the study is read, the output made or Ray started."""
    call = {"study_file": write_study(tmp_path), "out_dir": tmp_path / "out", **arguments}
    with pytest.raises(ValueError, match=expected):
        engine.run_study(call.pop("study_file"), call.pop("out_dir"), **call)
    assert not (tmp_path / "out").exists()
    with pytest.raises(ValueError, match=r"^workers must be"), engine.ray_session(None, 0):
        pass  # not reached: the check comes before Ray


def test_the_engine_takes_numpy_worker_counts():
    import numpy as np

    assert engine.check_session(None, np.int64(3)) == 3
    assert type(engine.check_session(None, np.int64(3))) is int
    assert engine.check_session("10.0.0.1:6379", None) is None


def test_paths_reach_command_fields_and_programs(tmp_path):
    from corobot_drake.config.scenario import DriveDistance, SetPower
    from corobot_drake.study.runner import run_scenario

    path = tmp_path / "s.yaml"
    path.write_text(f"""scenario: {DEFAULT_SCENARIO}
grid:
  box_approach.direction: [forwards]
  box_approach.angle_deg: [30.0]
box_approach: {{power: 0.5}}
overrides: ["robots: {{corobot: {{commands: [!Wait {{}}, !DriveDistance {{}}]}}}}"]
""")
    study = load_study(path)
    (run,) = expand(study)
    assert run.overrides() == ['{"random_seed": 1}']  # program paths are not overrides
    robot = run_scenario(study, DEFAULT_SCENARIO, run).robots["corobot"]
    assert robot.commands == [SetPower(0.5, 0.5)]  # the program's script, forwards at 0.5
    yaw = robot.pose.GetDeterministicValue().rotation().ToRollPitchYaw().yaw_angle()
    assert yaw == pytest.approx(math.radians(-150.0))  # 180 + 30 deg: the box ahead, oblique
    # A list index reaches into the script (the value checked as in a scenario) ...
    study.box_approach = None
    study.grid = {"robots.corobot.commands.1.distance": [2],
                  "robots.corobot.commands.1.power": [1]}
    (run,) = expand(study)
    assert run.overrides() == ['{"random_seed": 1}'] and len(run.indexed()) == 2
    assert run_scenario(study, DEFAULT_SCENARIO, run).robots["corobot"].commands[1] == \
        DriveDistance(2.0, 1.0)  # ints become the fields' floats
    for power, error, match in (
            (1.5, ScenarioError, r"commands\[1\].power: must be in \(0, 1\]; got 1.5"),
            ("fast", ValueError, "commands.1.power: expected float, got 'fast'")):
        study.grid["robots.corobot.commands.1.power"] = [power]
        with pytest.raises(error, match=match):
            run_scenario(study, DEFAULT_SCENARIO, expand(study)[0])
    # ... and past its end is an error naming the list's length.
    study.grid = {"robots.corobot.commands.2.distance": [2]}
    with pytest.raises(ValueError, match=r"robots.corobot.commands.2: the list has 2 items"):
        run_scenario(study, DEFAULT_SCENARIO, expand(study)[0])


def test_a_runs_sensors_scan_only_when_a_metric_reads_them(tmp_path):
    from corobot_drake.study.runner import run_scenario

    path = tmp_path / "s.yaml"
    path.write_text(f"scenario: {DEFAULT_SCENARIO}\nmetrics: [x, max_tilt_deg]\n")
    study = load_study(path)
    (run,) = expand(study)

    def enabled():
        robot = run_scenario(study, DEFAULT_SCENARIO, run).robots["corobot"]
        return robot.cameras["front"].rgb, sorted(s.enabled for s in robot.ir_sensors.values())

    assert enabled() == (False, [False, False])  # no metric reads the camera or the IR
    study.metrics = ["x", "ir"]
    assert enabled() == (False, [True, True])
    study.cameras = True
    assert enabled() == (True, [True, True])


def test_a_worker_reads_the_study_scenario_once(tmp_path):
    """Runs on a worker's `study_scenario` are the runs read from the file, and a run's
    programs and grid values never reach the next run; a bad study override is every run's
    error row, read once."""
    from pydrake.common.yaml import yaml_dump_typed

    from corobot_drake.config.scenario import Scenario
    from corobot_drake.study.runner import SimulationCache, StudyWorker, run_scenario

    path = tmp_path / "s.yaml"
    path.write_text(f"""scenario: {DEFAULT_SCENARIO}
seeds: 2
grid: {{robots.corobot.commands.1.distance: [0.5, 2]}}
random: {{robots.corobot.contact.friction: !Uniform {{min: 0.4, max: 0.6}}}}
drive_test: {{loops: 1}}
overrides: ["robots: {{corobot: {{drive: {{motor_torque_scaling: 8.0}}}}}}"]
""")
    study = load_study(path)
    cache = SimulationCache()
    base = cache.base(study, DEFAULT_SCENARIO)
    before = yaml_dump_typed(base, schema=Scenario)
    for run in expand(study):
        on_base, from_file = (run_scenario(study, DEFAULT_SCENARIO, run, b)
                              for b in (cache.base(study, DEFAULT_SCENARIO), None))
        assert yaml_dump_typed(on_base, schema=Scenario) == \
            yaml_dump_typed(from_file, schema=Scenario)
        robot = on_base.robots["corobot"]
        assert robot.drive.motor_torque_scaling == 8.0 and robot.commands[1].distance == \
            run.params[0][1] and robot.contact.friction == run.params[1][1]
    assert cache.base(study, DEFAULT_SCENARIO) is base
    assert yaml_dump_typed(base, schema=Scenario) == before
    study.overrides = ["robots: {corobot: {drive: {motor_torque_scaling: -1}}}"]
    worker = StudyWorker(study, DEFAULT_SCENARIO)
    errors = [worker.run(run)["error"] for run in expand(study)]
    assert len(set(errors)) == 1 and "motor_torque_scaling: must be in" in errors[0]


@pytest.mark.parametrize("text, expected", [
    ("grid: {drive_test.power: [0.5]}\n", "grid.drive_test.power: the study has no drive_test"),
    ("grid: {box_approach.speed: [1]}\nbox_approach: {}\n",
     "box_approach has no field 'speed'; fields: direction, angle_deg, power, robot"),
    ("grid: {box_approach.direction: [up]}\nbox_approach: {}\n",
     "direction 'up' is not one of backwards, forwards"),
])
def test_a_bad_program_path_is_one_line(tmp_path, text, expected):
    path = tmp_path / "bad.yaml"
    path.write_text(f"scenario: x.yaml\n{text}")
    with pytest.raises(ScenarioError, match=expected):
        load_study(path)


# --- studies on Ray ------------------------------------------------------------------------

def test_a_study_joins_a_separately_started_ray_head(tmp_path, ray_head):
    import ray

    # Runs before `connected` (file order): the study itself joins by address and leaves.
    assert not ray.is_initialized()
    study_file = write_study(tmp_path, scalings="10.16")
    table = rows(engine.run_study(study_file, tmp_path / "out", address=ray_head.address,
                                  progress=False))
    assert [r["status"] for r in table] == ["ok", "ok"]
    assert not ray.is_initialized()  # the study disconnected; the head is still ours


@pytest.fixture(scope="module")
def connected(ray_head):
    """This process connected to the session's Ray head (conftest's `ray_head`) for the
    module: a study then uses the caller's session (as in a notebook) instead of starting its
    own."""
    import ray

    ray.init(address=ray_head.address, log_to_driver=False, configure_logging=False)
    yield
    ray.shutdown()  # disconnects; the head is the session's


@pytest.fixture(scope="module")
def tiny_study(tmp_path_factory, connected):
    """The tiny study (2 scalings x 2 seeds, 0.3 s each) run once with 2 workers: (study file,
    output directory), shared by the tests that read it."""
    tmp = tmp_path_factory.mktemp("tiny")
    study_file = write_study(tmp)
    engine.run_study(study_file, tmp / "out", workers=2, progress=False)
    return study_file, tmp / "out"


def test_a_tiny_study_end_to_end(tiny_study):
    study_file, out = tiny_study
    table = rows(out / "runs.csv")
    assert [r["status"] for r in table] == ["ok"] * 4
    # Full power for 0.3 s. Scaling 6.0 caps the axle at 6 rad/s, reached after 0.2 s at the
    # 30 rad/s^2 slew: by 0.3 s the robot rolls at 6 x R (0.362 m/s; the soft tyres' effective
    # radius is ~1% less, so 2%). Scaling 10.16 is still accelerating, and faster.
    slow, fast = [float(r["corobot.speed"]) for r in table[0:2]], [
        float(r["corobot.speed"]) for r in table[2:4]]
    assert all(abs(s / (6.0 * 0.060325) - 1) < 0.02 for s in slow)
    assert min(fast) > 1.3 * max(slow)
    assert all(float(r["corobot.ir.rear"]) > 0.6 for r in table)  # the box is behind
    summary = (out / "summary.md").read_text()
    assert "motor_torque_scaling = 10.16 (2 runs)" in summary and "| corobot.speed |" in summary
    assert (out / "plots" / "corobot.speed.png").stat().st_size > 1000
    assert (out / "tiny.yaml").read_text() == study_file.read_text()


def test_one_and_two_workers_give_the_same_rows(tmp_path, tiny_study):
    study_file, out = tiny_study
    one = rows(engine.run_study(study_file, tmp_path / "one", workers=1, progress=False))
    assert without_timing(one) == without_timing(rows(out / "runs.csv"))


PICKY = """\
def slow_only(run):
    scaling = run.sim.scenario.robots[run.robot.name].drive.motor_torque_scaling
    if scaling > 8.0:
        raise ValueError(f"too fast to measure at scaling {scaling}")
    return scaling
"""


def test_a_bad_run_is_an_error_row_and_the_others_complete(tmp_path, connected, capsys):
    """A run that fails (here its metric raises; a value the study cannot check alone, or a
    simulation error, alike) is an error row with its one line; the others complete."""
    from corobot_drake.study.__main__ import main

    (tmp_path / "picky.py").write_text(PICKY)
    study_file = write_study(tmp_path, scalings="10.16, 6.0")
    study_file.write_text(study_file.read_text().replace("metrics: [x, speed, max_tilt_deg, ir]",
                                                         "metrics: [x, picky:slow_only]"))
    assert main([str(study_file), "--out", str(tmp_path / "out"), "--quiet"]) == 1
    captured = capsys.readouterr()
    assert "4 runs (2 errors)" in captured.out and "run 0: " in captured.err
    table = rows(tmp_path / "out" / "runs.csv")
    assert [r["status"] for r in table] == ["error", "error", "ok", "ok"]
    assert table[0]["error"] == "too fast to measure at scaling 10.16"
    assert table[2]["corobot.x"] != "" and table[2]["corobot.picky:slow_only"] == "6.0"
    assert main([str(tmp_path / "missing.yaml")]) == 2
    assert "cannot read the file" in capsys.readouterr().err


def test_resume_simulates_only_the_missing_runs(tmp_path, tiny_study):
    study_file, full_out = tiny_study
    full = rows(full_out / "runs.csv")
    out = tmp_path / "out"
    out.mkdir()
    kept = [dict(r, wall_seconds="12345") for r in full if r["run"] in ("0", "3")]
    with (out / "runs.csv").open("w", newline="") as f:  # as if stopped after runs 0 and 3
        writer = csv.DictWriter(f, list(full[0]))
        writer.writeheader()
        writer.writerows(kept)
    resumed = rows(engine.run_study(study_file, out, workers=2, resume=True, progress=False))
    assert without_timing(resumed) == without_timing(full)
    assert [r["wall_seconds"] == "12345" for r in resumed] == [True, False, False, True]


def test_resume_refuses_a_runs_table_not_this_studys(tmp_path, tiny_study):
    """Another study's rows, a run the study does not have, a corrupt file or a FIFO: one
    line naming the file and the row's line, before Ray is asked for anything; the file is
    left as it was."""
    import os

    from corobot_drake.study.__main__ import main

    study_file, full_out = tiny_study
    table = (full_out / "runs.csv").read_text()
    other = write_study(tmp_path, scalings="6.0, 8.0", name="other.yaml")
    longer = tmp_path / "longer.yaml"  # the same runs, each of another length
    longer.write_text(study_file.read_text().replace("duration: 0.3", "duration: 0.5"))
    header, *lines = table.splitlines()
    digest = header.split(",").index("study_digest")
    old = "\n".join(",".join(c for i, c in enumerate(line.split(",")) if i != digest)
                    for line in [header, *lines]) + "\n"  # a table without the column
    cases = [
        (table, other, r"runs.csv:4: run 2's robots.corobot.drive.motor_torque_scaling is "
         r"'10.16', this study's is '8.0': these rows are another study's"),
        (table, longer, r"runs.csv:2: run 0's study_digest is '[0-9a-f]{12}', this study's is "
         r"'[0-9a-f]{12}' \(its scenario file, overrides, duration, until, settle, metrics, "
         r"programs or cameras differ\): these rows are another study's"),
        (old, study_file, r"runs.csv:1: no column 'study_digest': not the runs table of this "
         r"study"),
        (table.replace("\n3,", "\n7,"), study_file,
         r"runs.csv:5: run '7' is not one of this study's 4 runs"),
        (table.replace("\n3,", "\n2,"), study_file, r"runs.csv:5: run 2 is listed twice"),
        ("seed,x\n1,2\n", study_file, r"runs.csv:1: no column 'run'"),
        (table.splitlines()[0] + '\n0,1,"6.0\n', study_file,
         r"runs.csv:2: not a CSV runs table \(unexpected end of data\)"),
        (table + "4,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20,21,22,23\n", study_file,
         r"runs.csv:6: not a CSV runs table \(24 cells under \d+ columns\)"),
        (None, study_file, r"runs.csv: not a runs table \(a regular file"),
    ]
    for i, (text, study, expected) in enumerate(cases):
        out = tmp_path / f"out{i}"
        out.mkdir()
        runs_csv = out / "runs.csv"
        if text is None:
            os.mkfifo(runs_csv)
        else:
            runs_csv.write_text(text)
        with pytest.raises(engine.ResumeError, match=expected):
            engine.run_study(study, out, resume=True, progress=False)
        assert text is None or runs_csv.read_text() == text
    assert main([str(other), "--out", str(tmp_path / "out0"), "--resume", "--quiet"]) == 2


KILLER = """\
import os
import signal
from pathlib import Path

def die_once(run):
    # run 1 or 3 (seed 2), whichever comes first: its worker process is killed the first
    # time, not when the run is tried again
    marker = Path({marker!r})
    if run.sim.scenario.random_seed == 2 and not marker.exists():
        marker.write_text("killed")
        os.kill(os.getpid(), signal.SIGKILL)
    return 1.0

def die_always(run):
    if run.sim.scenario.random_seed == 1 and run.sim.scenario.robots[run.robot.name].drive\
            .motor_torque_scaling == 6.0:
        os.kill(os.getpid(), signal.SIGKILL)
    return 2.0
"""


def test_a_killed_worker_is_retried_then_an_error_row(tmp_path, connected):
    """A worker process killed under a run (SIGKILL: out of memory, a crash): Ray restarts
    it and the run is tried again; a run that kills it every time becomes an error row, and
    the study ends normally with the others."""
    (tmp_path / "killer.py").write_text(KILLER.format(marker=str(tmp_path / "killed")))
    study_file = tmp_path / "kill.yaml"
    study_file.write_text(TINY.format(scenario=DEFAULT_SCENARIO, scalings="6.0, 10.16")
                          .replace("metrics: [x, speed, max_tilt_deg, ir]",
                                   "metrics: [x, killer:die_once, killer:die_always]"))
    table = rows(engine.run_study(study_file, tmp_path / "out", workers=2, progress=False))
    assert (tmp_path / "killed").exists()  # run 1's or 3's worker was killed once
    assert [r["status"] for r in table] == ["error", "ok", "ok", "ok"], [r["error"] for r in table]
    assert re.search(r"its worker process died 2 times running it", table[0]["error"])
    assert table[1]["corobot.killer:die_once"] == "1.0" and float(table[1]["corobot.x"]) > 0


def docs_example_study() -> str:
    """The study file docs/studies.md shows (its first YAML block)."""
    docs = (Path(__file__).resolve().parents[2] / "docs" / "studies.md").read_text()
    return re.search(r"```yaml\n(scenario: .*?)```", docs, re.S).group(1)


def test_the_docs_example_study_runs(tmp_path, connected):
    """docs/studies.md's example study loads as written (it was refused, exit 2, when it
    combined two programs) and runs, shortened to one seed of 1 s."""
    text = docs_example_study()
    (tmp_path / "example.yaml").write_text(text)
    load_study(tmp_path / "example.yaml")
    short = re.sub(r"(?m)^seeds: 4 ", "seeds: 1 ", re.sub(r"(?m)^duration: 8.0 ", "duration: 1.0 ",
                                                        text))
    assert "\nseeds: 1 " in short and "\nduration: 1.0 " in short
    (tmp_path / "short.yaml").write_text(short)
    table = rows(engine.run_study(tmp_path / "short.yaml", tmp_path / "out", progress=False))
    assert [r["status"] for r in table] == ["ok", "ok"], [r["error"] for r in table]
    assert all(float(r["corobot.speed"]) > 0.1 for r in table)  # the override's SetPower


RAY_TIMEOUT = ("The current node timed out during startup. This could happen because some of "
               "the raylet failed to startup or the GCS has become overloaded.")
"""What ray.init raises (a bare Exception) when its processes start slower than it waits."""


def test_ray_s_local_start_timing_out_is_one_line(tmp_path, monkeypatch, capsys):
    """A local Ray instance that does not start in time (a loaded machine): one line saying
    so and what to do, exit status 1 (not the study's fault), no traceback."""
    import ray

    from corobot_drake.study.__main__ import main

    def timed_out(**_):
        raise Exception(RAY_TIMEOUT)  # as Ray does

    # Whatever this worker's Ray session is (the `connected` fixture's), the study starts its own.
    monkeypatch.setattr(ray, "is_initialized", lambda: False)
    monkeypatch.setattr(ray, "init", timed_out)
    monkeypatch.setattr(ray, "shutdown", lambda: None)
    study_file = write_study(tmp_path)
    assert main([str(study_file), "--out", str(tmp_path / "out"), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(
        f"error: Ray's local instance did not start ({RAY_TIMEOUT}); ")
    assert "--address" in err and "Traceback" not in err


def test_ray_s_start_up_lines_come_before_the_progress_bar(tmp_path, monkeypatch, capsys):
    """What Ray prints as it starts (token authentication's line) is printed before the
    study's progress bar is drawn, not inside it."""
    import contextlib
    import sys

    token_line = "Token authentication is enabled for this Ray cluster."

    @contextlib.contextmanager
    def session(address, workers):
        print(token_line, file=sys.stderr)
        yield 2

    def results(todo, study, scenario_file, workers, user):
        for run in todo:
            yield {"run": run.index, "seed": run.seed, **dict(run.params), "corobot.x": 1.0,
                   "status": "ok", "error": ""}

    monkeypatch.setattr(engine, "ray_session", session)
    monkeypatch.setattr(engine, "_results", results)
    engine.run_study(write_study(tmp_path), tmp_path / "out", progress=True)
    err = capsys.readouterr().err
    assert token_line in err and "4/4" in err
    assert err.index(token_line) < err.index("0/4"), err


def test_an_address_where_no_cluster_answers_is_one_line(tmp_path):
    """--address: malformed, or nothing listening there: one line naming --address, exit 2,
    nothing written (Ray itself would retry for minutes, or print a traceback)."""
    import subprocess
    import sys

    study_file = write_study(tmp_path)
    for address, expected in (("127.0.0.1:1", "no Ray cluster answers there"),
                              ("not an address", "not a Ray cluster's address; expected "
                                                 "HOST:PORT")):
        done = subprocess.run([sys.executable, "-m", "corobot_drake.study", str(study_file),
                               "--address", address, "--out", str(tmp_path / "out"),
                               "--quiet"], capture_output=True, text=True, timeout=120)
        assert done.returncode == 2, done.stderr
        assert done.stderr.startswith("error: --address") and expected in done.stderr
        assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr
    assert not (tmp_path / "out").exists()


def test_the_drive_test_study_and_the_drive_test_tool_agree(tmp_path, connected):
    from lab import drive_test

    # Power 1: the loop's legs in a third of the simulated time of the tool's default 0.2.
    table = drive_test.run_study_of_seeds([1], 1, "closed_loop", 1.0, tmp_path, workers=1)
    alone = drive_test.run(1, 1, "closed_loop", power=1.0, verbose=False)
    assert table[0]["failures"] == [] and alone["failures"] == []
    assert table[0]["drift_mm"] == [alone["drift"][0] * 1000.0]  # the same run, bit for bit
    assert 0.0 < alone["drift"][0] < 0.01  # a closed-loop loop comes back within 10 mm


def test_the_drive_test_tool_s_overrides_reach_every_run_of_its_study(tmp_path):
    """`tools/drive_test.py --override` (CENIC, say) goes into the study it writes for
    --seeds, as the study's `overrides`."""
    from corobot_drake.config.scenario import CENIC_PLANT
    from corobot_drake.study.spec import load_study
    from lab import drive_test

    cenic = CENIC_PLANT % 0.01
    study_file = tmp_path / "drive_test.yaml"
    study_file.write_text(drive_test.study_text([1, 2], 1, "closed_loop", 1.0, [cenic]))
    assert load_study(study_file).overrides == [cenic]
    study_file.write_text(drive_test.study_text([1], 1, "seed", 1.0))
    assert load_study(study_file).overrides == []


def test_ctrl_c_keeps_the_finished_rows_and_stops_ray(tmp_path, connected, capsys):
    """Ctrl-C (SIGINT) mid-study: exit 130, the finished rows kept, every process the study
    started gone (its own local Ray instance); --resume then runs only the rest."""
    import signal
    import subprocess
    import sys
    import time

    from corobot_drake.study.__main__ import main

    # 6 runs of 1 s on one worker, each a tenth of a second or more: the first row is written
    # at once, and the signal follows it within 50 ms, long before the last run.
    study_file = tmp_path / "long.yaml"
    study_file.write_text(TINY.format(scenario=DEFAULT_SCENARIO, scalings="10.16").replace(
        "seeds: 2", "seeds: 6").replace("duration: 0.3", "duration: 1.0"))
    out = tmp_path / "out"
    command = [sys.executable, "-m", "corobot_drake.study", str(study_file), "--out", str(out),
               "--workers", "1", "--quiet"]
    study = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline = time.monotonic() + 90
        while not ((out / "runs.csv").exists() and rows(out / "runs.csv")):
            assert time.monotonic() < deadline and study.poll() is None, "no rows written"
            time.sleep(0.05)
        started = set(descendants(study.pid))
        study.send_signal(signal.SIGINT)
        _, err = study.communicate(timeout=60)
    finally:
        if study.poll() is None:
            study.kill()
    assert study.returncode == 130, err
    assert "--resume" in err
    kept = rows(out / "runs.csv")
    assert 1 <= len(kept) < 6 and all(r["status"] == "ok" for r in kept)
    deadline = time.monotonic() + 15  # Ray's processes go with it, each as it is told
    while [pid for pid in started if alive(pid)] and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not [pid for pid in started if alive(pid)]
    # Resumed from the command line (in this process, on the module's Ray head).
    assert main([str(study_file), "--out", str(out), "--resume", "--quiet"]) == 0
    assert "6 runs (0 errors)" in capsys.readouterr().out
    resumed = rows(out / "runs.csv")
    assert [r["run"] for r in resumed] == [str(i) for i in range(6)]
    assert [r["wall_seconds"] for r in resumed[:len(kept)]] == [r["wall_seconds"] for r in kept]


@pytest.mark.parametrize("full", ["runs.csv", "summary.md"])
def test_a_full_disk_ends_the_study_in_one_line_naming_the_file(tmp_path, connected, capsys,
                                                                full):
    """Writes that fail as on a full disk (the file a link to /dev/full, where every write is
    ENOSPC): one line naming the file and exit status 1, never the line that reports the
    runs; runs.csv is replaced whole or not at all (no half-written file left)."""
    from corobot_drake.study.__main__ import main

    study_file = write_study(tmp_path, scalings="10.16")
    out = tmp_path / "out"
    out.mkdir()
    (out / ("runs.csv.tmp" if full == "runs.csv" else full)).symlink_to("/dev/full")
    assert main([str(study_file), "--out", str(out), "--workers", "1", "--quiet"]) == 1
    captured = capsys.readouterr()
    assert captured.err.splitlines() == [
        f"error: {out / full}: cannot write (No space left on device); the study did not finish"]
    assert "runs (" not in captured.out
    assert not (out / "runs.csv.tmp").exists()


@pytest.mark.parametrize("study_file", sorted((DEFAULT_SCENARIO.parent / "studies").glob("*.yaml")),
                         ids=lambda p: p.stem)
def test_every_shipped_study_run_is_a_valid_scenario(study_file):
    # Each run's scenario as a worker builds it, checked (no simulation): a grid value out of
    # a field's bounds would make every such run an error row (the tire-grip study's unlimited
    # motor once did).
    from corobot_drake.study.runner import run_scenario
    from corobot_drake.study.spec import scenario_path

    study = load_study(study_file)
    for run in expand(study):
        run_scenario(study, scenario_path(study, study_file), run)


def test_the_steady_rate_leaves_out_each_workers_first_run():
    from lab.bench_study import steady_rate

    # Two workers: the first two rows carry the start-ups; then 4 runs in 2 s.
    rows = [{"finished_seconds": t} for t in ("5.0", "5.5", "6.0", "6.5", "7.0", "7.5")]
    assert steady_rate(rows, 2) == pytest.approx(4 / 2.0)
    assert steady_rate(rows, 1) == pytest.approx(5 / 2.5)
    assert steady_rate(rows[:2], 2) is None  # no run after the start-ups
