"""The study engine: the study file, its expansion into runs, and studies run on Ray (a local
instance shared by the module's tests, and a separately started head joined by address)."""

import csv
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
    ("scenario: x.yaml\nseeds: 0\n", ":2: seeds: must be >= 1"),
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


# --- studies on Ray ------------------------------------------------------------------------

def test_a_study_joins_a_separately_started_ray_head(tmp_path):
    ray = pytest.importorskip("ray")
    from ray.cluster_utils import Cluster

    assert not ray.is_initialized()
    cluster = Cluster(initialize_head=True, head_node_args={
        "num_cpus": 2, "include_dashboard": False})
    try:
        study_file = write_study(tmp_path, scalings="10.16")
        table = rows(engine.run_study(study_file, tmp_path / "out", address=cluster.address,
                                      progress=False))
        assert [r["status"] for r in table] == ["ok", "ok"]
        assert not ray.is_initialized()  # the study disconnected; the head is still ours
    finally:
        cluster.shutdown()


@pytest.fixture(scope="module")
def local_ray():
    """One local Ray instance (2 CPUs, no dashboard) for the module; stopped at its end."""
    ray = pytest.importorskip("ray")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False,
             configure_logging=False)
    yield
    ray.shutdown()


def test_a_tiny_study_end_to_end(tmp_path, local_ray):
    study_file = write_study(tmp_path)
    out = tmp_path / "out"
    table = rows(engine.run_study(study_file, out, workers=2, progress=False))
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


def test_one_and_two_workers_give_the_same_rows(tmp_path, local_ray):
    study_file = write_study(tmp_path)
    one = rows(engine.run_study(study_file, tmp_path / "one", workers=1, progress=False))
    two = rows(engine.run_study(study_file, tmp_path / "two", workers=2, progress=False))
    assert without_timing(one) == without_timing(two)


def test_a_bad_run_is_an_error_row_and_the_others_complete(tmp_path, local_ray):
    study_file = write_study(tmp_path, scalings="-1.0, 10.16")
    table = rows(engine.run_study(study_file, tmp_path / "out", workers=2, progress=False))
    assert [r["status"] for r in table] == ["error", "error", "ok", "ok"]
    assert "motor_torque_scaling: must be > 0" in table[0]["error"]
    assert table[2]["corobot.x"] != ""


def test_resume_simulates_only_the_missing_runs(tmp_path, local_ray):
    study_file = write_study(tmp_path)
    out = tmp_path / "out"
    full = rows(engine.run_study(study_file, out, workers=2, progress=False))
    kept = [dict(r, wall_seconds="12345") for r in full if r["run"] in ("0", "3")]
    with (out / "runs.csv").open("w", newline="") as f:  # as if stopped after runs 0 and 3
        writer = csv.DictWriter(f, list(full[0]))
        writer.writeheader()
        writer.writerows(kept)
    resumed = rows(engine.run_study(study_file, out, workers=2, resume=True, progress=False))
    assert without_timing(resumed) == without_timing(full)
    assert [r["wall_seconds"] == "12345" for r in resumed] == [True, False, False, True]


def test_the_command_line_writes_the_study(tmp_path, local_ray, capsys):
    from corobot_drake.study.__main__ import main

    study_file = write_study(tmp_path, scalings="10.16")
    assert main([str(study_file), "--out", str(tmp_path / "o"), "--quiet"]) == 0
    assert "2 runs (0 errors)" in capsys.readouterr().out
    assert main([str(tmp_path / "missing.yaml")]) == 2
    assert "cannot read the file" in capsys.readouterr().err


def test_the_drive_test_study_and_the_drive_test_tool_agree(tmp_path, local_ray):
    from corobot_drake.analysis import drive_test

    table = drive_test.run_study_of_seeds([1], 1, "closed_loop", 0.2, tmp_path, workers=1)
    alone = drive_test.run(1, 1, "closed_loop", verbose=False)
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


def test_ctrl_c_keeps_the_finished_rows_and_stops_ray(tmp_path):
    """Ctrl-C (SIGINT) mid-study: exit 130, the finished rows kept, every process the study
    started gone; --resume then runs only the rest."""
    import signal
    import subprocess
    import sys
    import time

    study_file = tmp_path / "long.yaml"
    study_file.write_text(TINY.format(scenario=DEFAULT_SCENARIO, scalings="10.16").replace(
        "seeds: 2", "seeds: 12").replace("duration: 0.3", "duration: 1.5"))
    out = tmp_path / "out"
    command = [sys.executable, "-m", "corobot_drake.study", str(study_file), "--out", str(out),
               "--workers", "1", "--quiet"]
    study = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 90
        while not ((out / "runs.csv").exists() and len(rows(out / "runs.csv")) >= 2):
            assert time.monotonic() < deadline and study.poll() is None, "no rows written"
            time.sleep(0.2)
        started = _descendants(study.pid)
        study.send_signal(signal.SIGINT)
        _, err = study.communicate(timeout=60)
    finally:
        if study.poll() is None:
            study.kill()
    assert study.returncode == 130, err
    assert "--resume" in err
    kept = rows(out / "runs.csv")
    assert 2 <= len(kept) < 12 and all(r["status"] == "ok" for r in kept)
    time.sleep(1.0)
    assert not [pid for pid in started if _alive(pid)]  # Ray's processes went with it
    done = subprocess.run([*command, "--resume"], capture_output=True, text=True, timeout=180)
    assert done.returncode == 0, done.stderr
    resumed = rows(out / "runs.csv")
    assert [r["run"] for r in resumed] == [str(i) for i in range(12)]
    assert [r["wall_seconds"] for r in resumed[:len(kept)]] == [r["wall_seconds"] for r in kept]
