"""The study engine: the study file, its expansion into runs, and studies run on Ray (a local
instance shared by the module's tests, and a separately started head joined by address)."""

import csv
import math
from pathlib import Path

import pytest

from corobot_drake.config.scenario import ScenarioError
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.study import engine
from corobot_drake.study.spec import Normal, Uniform, draw, expand, load_study

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
    ("scenario: x.yaml\nmetrics: [x, wobble]\n", ":2: metrics: unknown metric 'wobble'"),
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
        return robot.camera.rgb, sorted(s.enabled for s in robot.ir_sensors.values())

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

@pytest.fixture(scope="module")
def ray_head():
    """A separately started Ray head (2 CPUs, no dashboard, its own processes), shut down
    through its handle at the module's end; the module's studies run on it."""
    ray = pytest.importorskip("ray")
    from ray.cluster_utils import Cluster

    assert not ray.is_initialized()
    cluster = Cluster(initialize_head=True, head_node_args={
        "num_cpus": 2, "include_dashboard": False})
    yield cluster
    if ray.is_initialized():
        ray.shutdown()
    cluster.shutdown()


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
    """This process connected to the module's head: a study then uses the caller's session
    (as in a notebook) instead of starting its own."""
    import ray

    ray.init(address=ray_head.address, log_to_driver=False, configure_logging=False)
    yield


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


def test_a_bad_run_is_an_error_row_and_the_others_complete(tmp_path, connected, capsys):
    from corobot_drake.study.__main__ import main

    study_file = write_study(tmp_path, scalings="-1.0, 10.16")
    assert main([str(study_file), "--out", str(tmp_path / "out"), "--quiet"]) == 1
    captured = capsys.readouterr()
    assert "4 runs (2 errors)" in captured.out and "run 0: " in captured.err
    table = rows(tmp_path / "out" / "runs.csv")
    assert [r["status"] for r in table] == ["error", "error", "ok", "ok"]
    assert "motor_torque_scaling: must be in (0, 200] rad/s; got -1" in table[0]["error"]
    assert table[2]["corobot.x"] != ""
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


def test_the_drive_test_study_and_the_drive_test_tool_agree(tmp_path, connected):
    from lab import drive_test

    # Power 1: the loop's legs in a third of the simulated time of the tool's default 0.2.
    table = drive_test.run_study_of_seeds([1], 1, "closed_loop", 1.0, tmp_path, workers=1)
    alone = drive_test.run(1, 1, "closed_loop", power=1.0, verbose=False)
    assert table[0]["failures"] == [] and alone["failures"] == []
    assert table[0]["drift_mm"] == [alone["drift"][0] * 1000.0]  # the same run, bit for bit
    assert 0.0 < alone["drift"][0] < 0.01  # a closed-loop loop comes back within 10 mm


def _descendants(pid: int) -> set[int]:
    """The PIDs of `pid`'s process tree now (from /proc)."""
    children: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        children.setdefault(int(fields[1]), []).append(int(stat.parent.name))
    found, todo = set(), [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.add(child)
            todo.append(child)
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


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
        started = _descendants(study.pid)
        study.send_signal(signal.SIGINT)
        _, err = study.communicate(timeout=60)
    finally:
        if study.poll() is None:
            study.kill()
    assert study.returncode == 130, err
    assert "--resume" in err
    kept = rows(out / "runs.csv")
    assert 1 <= len(kept) < 6 and all(r["status"] == "ok" for r in kept)
    time.sleep(1.0)
    assert not [pid for pid in started if _alive(pid)]  # Ray's processes went with it
    # Resumed from the command line (in this process, on the module's Ray head).
    assert main([str(study_file), "--out", str(out), "--resume", "--quiet"]) == 0
    assert "6 runs (0 errors)" in capsys.readouterr().out
    resumed = rows(out / "runs.csv")
    assert [r["run"] for r in resumed] == [str(i) for i in range(6)]
    assert [r["wall_seconds"] for r in resumed[:len(kept)]] == [r["wall_seconds"] for r in kept]


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
