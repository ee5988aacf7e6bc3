"""The command line and scenario files: every scenario runs; bad files give one clear line."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO
from corobot_drake.cli import main
from corobot_drake.resources import DEFAULT_SCENARIO, SCENARIOS_DIR

SCENARIOS = sorted(SCENARIOS_DIR.glob("*.yaml"))


@pytest.mark.parametrize("scenario", SCENARIOS, ids=lambda p: p.name)
def test_every_scenario_runs_headless(scenario, tmp_path):
    summary = tmp_path / "summary.json"
    assert main([str(scenario), "--headless", "--duration", "0.5",
                 "--summary", str(summary)]) == 0
    data = json.loads(summary.read_text())
    assert data["time"] == pytest.approx(0.5)
    for robot in data["robots"].values():
        assert {"pose", "velocity", "max_tilt_deg", "wheels", "commands"} <= robot.keys()
        assert robot["max_tilt_deg"] < 5.0


def _summary(tmp_path, name, *extra):
    path = tmp_path / name
    assert main([str(DEFAULT_SCENARIO), "--headless", "--duration", "2",
                 "--summary", str(path), *extra]) == 0
    data = json.loads(path.read_text())
    for key in ("realtime_factor", "wall_seconds"):
        data.pop(key)
    return data


def test_same_scenario_twice_gives_identical_summaries(tmp_path):
    script = ("--override", "robots: {corobot: {commands: [!SetPower {left: 0.5, right: 1.0}, "
              "!Wait {seconds: 1.0}, !SetSpeed {left: -0.2, right: 0.2}]}}")
    first = _summary(tmp_path, "a.json", *script)
    second = _summary(tmp_path, "b.json", *script)
    assert json.dumps(first, sort_keys=True) == json.dumps(second, sort_keys=True)
    assert first["robots"]["corobot"]["pose"]["x"] > 0.2  # it did drive
    commands = [c["command"] for c in first["robots"]["corobot"]["commands"]]
    assert commands == ["SetPower", "Wait", "SetSpeed"]


def test_script_runs_in_order(tmp_path):
    data = _summary(tmp_path, "s.json", "--override",
                    "robots: {corobot: {commands: [!Wait {seconds: 1.0}, "
                    "!SetPower {left: 1.0, right: 1.0}]}}")
    set_power = data["robots"]["corobot"]["commands"][1]
    assert set_power["start_time"] == pytest.approx(1.0)
    # 1 s at full power after the wait, less the 0.34 s ramp: ~0.5 m.
    assert data["robots"]["corobot"]["pose"]["x"] == pytest.approx(0.51, abs=0.03)


def test_several_robots(tmp_path):
    path = tmp_path / "s.json"
    two = ("robots: {corobot: {commands: [!SetPower {left: 1, right: 1}]}, second: "
           "{pose: {translation: [0, 1.5, 0]}, commands: [!SetPower {left: -1, right: -1}]}}")
    assert main(["--headless", "--duration", "1.5", "--override", two,
                 "--summary", str(path)]) == 0
    robots = json.loads(path.read_text())["robots"]
    assert robots["corobot"]["pose"]["x"] > 0.3
    assert robots["second"]["pose"]["x"] < -0.3
    assert robots["second"]["pose"]["y"] == pytest.approx(1.5, abs=0.01)


BAD_FILES = {
    "unknown_field.yaml": ("robots:\n  corobot:\n    colour: red\n",
                           ":3: robots.corobot.colour: unknown field"),
    "wrong_type.yaml": ("robots:\n  corobot:\n    drive: {slew_rate: fast}\n",
                        ":3: robots.corobot.drive.slew_rate: expected a number, got 'fast'"),
    "bad_yaml.yaml": ("robots: [\n", "not valid YAML"),
    "duplicate.yaml": ("robots:\n  corobot: {}\n  corobot: {}\n",
                       ":3: robots.corobot: duplicate name"),
    "bad_tag.yaml": ("robots:\n  corobot:\n    commands: [!Fly {}]\n",
                     "robots.corobot.commands[0]: unknown tag !Fly"),
    "out_of_range.yaml": ("robots:\n  corobot:\n    drive:\n      slew_rate: -1\n",
                          ":4: robots.corobot.drive.slew_rate: must be in (0, 10000] rad/s^2"),
    "old_camera.yaml": ("robots:\n  corobot:\n    camera: {rgb: false}\n",
                        ":3: robots.corobot.camera: replaced by `cameras`, a map of cameras by "
                        "name: write `cameras: {front: {...}}` (front: the Corobot's own camera)"),
    "old_pose.yaml": ("robots:\n  corobot:\n    pose: {x: 1.0, yaw_deg: 90}\n",
                      ":3: robots.corobot.pose.x: unknown field; Transform has base_frame, "
                      "translation, rotation"),
    "short_translation.yaml": ("world:\n  bodies:\n    box:\n      pose:\n"
                               "        translation: [1.0, 2.0]\n",
                               ":5: world.bodies.box.pose.translation: needs 3 numbers, got 2"),
    "body_base_frame.yaml": ("world:\n  bodies:\n    box:\n      pose: {base_frame: box}\n",
                             ":4: world.bodies.box.pose.base_frame: a pose in the world has "
                             "no base_frame"),
    "random_pose.yaml": ("robots:\n  corobot:\n    pose: {rotation: !Uniform {}}\n",
                         ":3: robots.corobot.pose: must be a fixed pose"),
    "camera_frame.yaml": ("robots:\n  corobot:\n    cameras:\n      front:\n        X_PB:\n"
                          "          base_frame: tail\n",
                          ":6: robots.corobot.cameras.front.X_PB.base_frame: 'tail' is not a link"),
}


@pytest.mark.parametrize("name", BAD_FILES)
def test_bad_scenario_gives_one_clear_line(name, tmp_path, capsys):
    text, expected = BAD_FILES[name]
    path = tmp_path / name
    path.write_text(text)
    assert main([str(path), "--headless"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert str(path) in err[0] and expected in err[0]


def test_missing_file(tmp_path, capsys):
    path = tmp_path / "nowhere.yaml"
    assert main([str(path), "--headless"]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert str(path) in line and "cannot read" in line


def test_bad_file_has_no_traceback(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("robots: {corobot: {drive: {slew_rate: [1, 2]}}}\n")
    result = subprocess.run([sys.executable, "-m", "corobot_drake", str(path), "--headless"],
                            capture_output=True, text=True, cwd=REPO)
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert result.stderr.strip() == (f"error: {path}:1: robots.corobot.drive.slew_rate: "
                                     "expected a number, got a list")


def test_the_interactive_run_keeps_a_window_of_run_log(tmp_path, monkeypatch, capsys):
    """The Meshcat run (left running, it could fill the memory) keeps the newest
    `LIVE_RUN_LOG_WINDOW` s of run log, as a served one does; its summary at exit and a
    --summary still come. Here a 2 s window over 15 simulated s: at most the window plus one
    chunk the sink still holds (`RUN_LOG_CHUNK` samples, 10 s), against the 1500 samples kept
    headless."""
    import pydrake.geometry
    from pydrake.geometry import Meshcat

    from corobot_drake import cli
    from corobot_drake.systems.runlog import LOG_PERIOD, RUN_LOG_CHUNK

    kept = {}

    def fast_interactive(sim, meshcat, duration):  # the real one paces at real time
        while sim.time < duration - 1e-9:
            sim.advance_to(min(duration, sim.time + 1.0 / 30.0))
        kept["rows"] = len(sim.robot().run_log())

    monkeypatch.setattr(pydrake.geometry, "StartMeshcat", Meshcat)
    monkeypatch.setattr(cli, "_run_interactive", fast_interactive)
    monkeypatch.setattr(cli, "LIVE_RUN_LOG_WINDOW", 2.0)
    summary = tmp_path / "s.json"
    assert main(["--duration", "15", "--summary", str(summary), "--override",
                 "robots: {corobot: {cameras: {front: {rgb: false}}}}"]) == 0
    assert 2.0 / LOG_PERIOD <= kept["rows"] <= 2.0 / LOG_PERIOD + RUN_LOG_CHUNK + 1
    assert json.loads(summary.read_text())["time"] == pytest.approx(15.0)
    assert "simulated 15.00 s" in capsys.readouterr().out
    assert cli.run_log_window(cli._parser().parse_args(["--log", "x.csv"])) is None
    assert cli.run_log_window(cli._parser().parse_args(["--headless"])) is None


@pytest.fixture
def stop_signals(monkeypatch):
    """The entry point's SIGINT and SIGTERM handlers (`cli.ctrl_c_stops`) in this process for
    one test; the handlers and the recorded signal put back after it."""
    import signal

    from corobot_drake import cli

    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    monkeypatch.setattr(cli, "STOPPED_BY", None)
    cli.ctrl_c_stops()
    yield cli
    for signum, handler in before.items():
        signal.signal(signum, handler)


def test_a_signal_while_the_outputs_are_written_lets_them_finish(tmp_path, capsys,
                                                                   monkeypatch, stop_signals):
    """SIGTERM in the middle of writing a finished run's outputs (here between the run log
    and the summary): every output is still written whole, one line says so, exit 143."""
    import signal

    cli = stop_signals
    write_logs = cli._write_logs

    def write_logs_then_sigterm(sim, path):
        write_logs(sim, path)
        signal.raise_signal(signal.SIGTERM)  # handled here, between two bytecodes

    monkeypatch.setattr(cli, "_write_logs", write_logs_then_sigterm)
    log, summary = tmp_path / "r.csv", tmp_path / "s.json"
    assert main(["--headless", "--duration", "0.5", "--override", NO_CAMERA,
                 "--log", str(log), "--summary", str(summary)]) == 128 + signal.SIGTERM
    assert json.loads(summary.read_text())["time"] == pytest.approx(0.5)
    assert len(log.read_text().splitlines()) == 1 + 51  # header, then 0 to 0.5 s at 100 Hz
    assert ("stopped by SIGTERM while the outputs were written: they were finished first"
            in capsys.readouterr().err)


def test_ctrl_c_while_the_scenario_loads_is_one_line(capsys, monkeypatch, stop_signals):
    """Ctrl-C before the run exists (here while the scenario is read): one line, exit 130."""
    import signal

    cli = stop_signals

    def interrupted(*args, **kwargs):
        signal.raise_signal(signal.SIGINT)

    monkeypatch.setattr(cli, "load_scenario", interrupted)
    assert main(["--headless"]) == 130
    assert capsys.readouterr().err.strip() == "stopped before the run started"


def test_ctrl_c_stops_a_run_started_with_sigint_ignored():
    """A background job of a non-interactive shell (a CI script) starts with SIGINT ignored,
    and Python keeps it so: the entry point restores Ctrl-C, so SIGINT still ends a run
    cleanly (exit 0, the closing line) rather than never."""
    import signal
    import subprocess
    import sys

    run = subprocess.Popen(  # a server: it runs until stopped
        [sys.executable, "-m", "corobot_drake", "--headless", "--serve", "--port", "0",
         "--override", "robots: {corobot: {cameras: {front: {rgb: false}}}}"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN))
    try:
        assert run.stdout.readline().startswith("serving ")  # up and simulating
        run.send_signal(signal.SIGINT)
        _, err = run.communicate(timeout=60)
    finally:
        if run.poll() is None:
            run.kill()
            run.wait(5)
    assert run.returncode == 0, err
    assert "simulated " in err  # its closing line


NO_CAMERA = "robots: {corobot: {cameras: {front: {rgb: false}}}}"


@pytest.mark.parametrize("signame, foxglove", [("SIGINT", False), ("SIGTERM", True)])
def test_a_stopped_headless_run_writes_every_output_whole(tmp_path, signame, foxglove):
    """SIGINT or SIGTERM mid-run: one line, no traceback, exit 128 + the signal, and every
    requested output holds the run so far (the MCAP file finished and readable)."""
    import signal

    from mcap.reader import make_reader

    out = {name: tmp_path / name for name in ("s.json", "r.html", "r.mcap", "r.csv", "r.yaml")}
    run = subprocess.Popen(
        [sys.executable, "-m", "corobot_drake", "--headless", "--duration", "600",
         "--override", NO_CAMERA, "--summary", str(out["s.json"]), "--record", str(out["r.html"]),
         "--mcap", str(out["r.mcap"]), "--log", str(out["r.csv"]),
         "--save-scenario", str(out["r.yaml"]), *(["--foxglove", "0"] if foxglove else [])],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        seen = ""
        while "t = " not in seen:  # the progress line: the run is under way
            character = run.stderr.read(1)
            assert character, seen
            seen += character
        run.send_signal(getattr(signal, signame))
        _, err = run.communicate(timeout=120)
    finally:
        if run.poll() is None:
            run.kill()
            run.wait(5)
    assert run.returncode == 128 + getattr(signal, signame), err
    assert "Traceback" not in err
    assert f"stopped by {signame} at t = " in err
    time = json.loads(out["s.json"].read_text())["time"]
    assert 0 < time < 600
    with open(out["r.mcap"], "rb") as f:
        assert make_reader(f).get_summary().statistics.message_count > 0
    assert out["r.html"].read_text().rstrip().endswith("</html>")
    assert len(out["r.csv"].read_text().splitlines()) > 1
    assert "robots:" in out["r.yaml"].read_text()


def test_outputs_that_are_fifos_or_devices_are_refused_before_the_run(tmp_path, capsys):
    import os

    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for flag in ("--summary", "--record", "--mcap", "--log", "--save-scenario"):
        for path, kind in ((fifo, "a FIFO"), ("/dev/null", "a device")):
            assert main(["--headless", flag, str(path)]) == 2
            assert capsys.readouterr().err == (f"error: {flag}: {path}: is {kind}; name a "
                                               "regular file\n")


def test_a_full_disk_ends_in_one_line_naming_the_file(tmp_path, capsys, monkeypatch):
    """The output, then its fallback in the temporary directory, both on full disks."""
    import errno
    import tempfile

    from corobot_drake import cli

    def full(path):
        raise OSError(errno.ENOSPC, os_strerror(errno.ENOSPC))

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    assert not cli.write_output("--summary", "/x/s.json", full)
    assert capsys.readouterr().err == ("error: --summary: /x/s.json: cannot write (No space "
                                       "left on device); nor to the temporary directory (No "
                                       "space left on device): lost\n")


def os_strerror(code: int) -> str:
    import os

    return os.strerror(code)


def test_an_mcap_file_on_a_full_disk_is_named(tmp_path):
    """A 64 KiB tmpfs, nearly full (as root; else skipped): the MCAP writer fails as it
    finishes the file; the summary goes to its fallback."""
    import os

    disk = tmp_path / "disk"
    disk.mkdir()
    if os.geteuid() != 0 or subprocess.run(
            ["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(disk)],
            capture_output=True).returncode != 0:
        pytest.skip("needs root to mount a small tmpfs")
    try:
        (disk / "filler").write_bytes(bytes(60 << 10))  # 4 KiB left
        run = subprocess.run(
            [sys.executable, "-m", "corobot_drake", "--headless", "--duration", "1",
             "--override", NO_CAMERA, "--mcap", str(disk / "r.mcap"),
             "--summary", str(disk / "s.json")], capture_output=True, text=True, timeout=300,
            env=dict(os.environ, TMPDIR=str(tmp_path)))  # where the fallback goes
    finally:
        subprocess.run(["umount", str(disk)], check=True)
    assert run.returncode == 1
    assert "Traceback" not in run.stderr
    assert f"error: --mcap: {disk}/r.mcap: cannot write (" in run.stderr
    assert f"error: --summary: {disk}/s.json: cannot write (No space left on device); " \
           f"written to {tmp_path}/corobot-summary-" in run.stderr
    (fallback,) = tmp_path.glob("corobot-summary-*.json")
    assert json.loads(fallback.read_text())["time"] == pytest.approx(1.0)


def test_a_foxglove_server_started_before_a_failing_mcap_file_is_stopped(tmp_path, capsys,
                                                                          monkeypatch):
    """--foxglove and --mcap, the MCAP file failing as it is made (after the live server
    started: a taken port must leave no file behind): one line, exit 2, and the server this
    process started no longer listens."""
    import os
    import time

    from corobot_drake.recording import mcap_log
    from lab.processes import listening_sockets, sockets_held

    def cannot_make(path, context):
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(mcap_log, "McapLog", cannot_make)
    before = sockets_held(os.getpid()) & listening_sockets()
    assert main(["--headless", "--foxglove", "0", "--mcap", str(tmp_path / "r.mcap")]) == 2
    assert capsys.readouterr().err.strip().splitlines()[-1].startswith("error: --mcap: ")
    deadline = time.monotonic() + 5.0  # the server's socket closes on its own thread
    while sockets_held(os.getpid()) & listening_sockets() - before:
        assert time.monotonic() < deadline, "the Foxglove server still listens"
        time.sleep(0.05)


@pytest.mark.parametrize("port", ["0", "8765"])
def test_foxglove_without_the_extra_is_one_line_on_any_port(port, monkeypatch, capsys):
    """Port 0 (a free one) asks for the [record] extra like any other port."""
    monkeypatch.setitem(sys.modules, "foxglove", None)  # as if not installed
    assert main(["--headless", "--foxglove", port]) == 2
    assert capsys.readouterr().err == (
        "error: --foxglove needs the [record] extra: pip install '.[record]' in corobot-drake's "
        "clone or unpacked sdist (it is not on PyPI; tools/setup installs every extra)\n")


def test_the_closing_line_says_the_time_simulated_not_the_end_time(capsys):
    """A run from t = 3 s (a resumed saved scenario starts where it was saved) for 0.5 s."""
    assert main(["--headless", "--duration", "0.5", "--override", NO_CAMERA,
                 "--override", "simulator_config: {start_time: 3.0}"]) == 0
    assert capsys.readouterr().out.startswith("simulated 0.50 s (t = 3.00 to 3.50 s) at ")
    assert main(["--headless", "--duration", "0.5", "--override", NO_CAMERA]) == 0
    assert capsys.readouterr().out.startswith("simulated 0.50 s at ")


def test_help_names_the_program_as_it_was_invoked():
    """The console script's --help says `corobot-drake`, `python -m`'s says `python -m ...`;
    the description is the module's whole first sentence."""
    script = Path(sys.executable).with_name("corobot-drake")
    if not script.exists():
        pytest.skip("no corobot-drake console script in this environment")
    for argv, prog in (([str(script)], "corobot-drake"),
                       ([sys.executable, "-m", "corobot_drake"], "python -m corobot_drake")):
        run = subprocess.run([*argv, "--help"], capture_output=True, text=True, timeout=120)
        assert run.returncode == 0, run.stderr
        assert run.stdout.startswith(f"usage: {prog} [-h]")
        text = " ".join(run.stdout.split())
        assert f"`{prog} [SCENARIO]`: run a scenario in Meshcat or headless." in text
        if prog == "corobot-drake":
            assert "python -m" not in text
