"""`python -m corobot_drake [SCENARIO]`: run a scenario in Meshcat or headless.

Exit status: 0 on success, 2 for a bad scenario or bad arguments (one line on stderr, before
anything is built), 1 when an output could not be written at the end (it went to a fallback
file, named on stderr) or camera frames could not be written during the run (they went to a
fallback directory, named on stderr).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import TYPE_CHECKING

from pydrake.systems.sensors import CameraConfig

from corobot_drake.config.bounds import DRAKE_BOUNDS
from corobot_drake.config.scenario import ScenarioError, load_scenario
from corobot_drake.limits import DURATION, LIVE_RUN_LOG_WINDOW, SIMULATION_DURATION, Range
from corobot_drake.resources import DEFAULT_SCENARIO, scenario_path

if TYPE_CHECKING:  # imported when a run starts: a bad input stops before pydrake's systems load
    from corobot_drake.simulation import Simulation

CAMERA_DELAY_SHARE = 0.9
"""--camera-rate HZ caps the cameras' output_delay at this share of a frame, 1/HZ."""

DEFAULT_FOXGLOVE_PORT = 8765
"""Foxglove's own default WebSocket port (`recording.foxglove_live.DEFAULT_PORT`)."""
HEADLESS_DEFAULT_DURATION = 10.0
PROGRESS_AFTER = 3.0
"""Wall-clock seconds after which a headless run starts printing progress."""


class _ArgumentParser(argparse.ArgumentParser):
    def error(self, message):
        """One line, like every bad input (argparse's usage line goes to --help)."""
        self.exit(2, f"error: {message}\n")


class ArgumentError(Exception):
    """A bad command line value: `str()` is `--flag: what is wrong and what is allowed`."""


def program_name() -> str:
    """How this program was invoked, for its --help: `python -m corobot_drake`, or the console
    script's name (`corobot-drake`)."""
    name = Path(sys.argv[0]).name
    return "python -m corobot_drake" if name in ("__main__.py", "") else name


def _parser() -> argparse.ArgumentParser:
    prog = program_name()
    p = _ArgumentParser(prog=prog, description=__doc__.split("\n\n")[0].replace(
        "python -m corobot_drake", prog))
    p.add_argument("scenario", nargs="?", default=str(DEFAULT_SCENARIO),
                   help="scenario YAML, or a shipped scenario's name (maze.yaml) from any "
                   "folder (default: scenarios/corobot.yaml)")
    p.add_argument("--headless", action="store_true",
                   help="no Meshcat; run as fast as possible")
    p.add_argument("--duration", type=float, default=None,
                   help="simulated seconds (default: the scenario's simulation_duration; "
                   f"headless with none: {HEADLESS_DEFAULT_DURATION:g})")
    p.add_argument("--override", action="append", default=[], metavar="YAML_TEXT",
                   help="YAML merged over the scenario (repeatable)")
    p.add_argument("--summary", metavar="PATH", help="write the run's summary JSON here")
    p.add_argument("--serve", action="store_true",
                   help="run in real time (or at --rate) with the HTTP services, dashboard and "
                   "webcam page (Meshcat too unless --headless); Ctrl-C stops")
    p.add_argument("--port", type=int, default=50000,
                   help="--serve: TCP port (default 50000; 0 picks a free one)")
    p.add_argument("--host", default="127.0.0.1",
                   help="--serve, --foxglove: address to listen on (default 127.0.0.1, "
                   "loopback only; anywhere else needs a token, docs/services.md)")
    p.add_argument("--token", default=None,
                   help="--serve, --foxglove: the token clients must send (default: none on "
                   "loopback; off loopback one is generated and printed; both servers share it)")
    p.add_argument("--rate", metavar="X", default=1.0,
                   help="--serve, --ros2: simulated s per wall-clock s (default 1: real time; "
                   "e.g. 0.5, 4), or `max`: as fast as the machine can; with --ros2 /clock is the "
                   "only time, Meshcat and --serve follow it")
    p.add_argument("--save-camera", metavar="DIR",
                   help="write the robots' camera frames as PNG: "
                   "DIR/<robot>/frame_000000.png, ... (another camera than front: "
                   "DIR/<robot>/<camera>/...)")
    p.add_argument("--camera-rate", type=float, metavar="HZ",
                   help="render (and save) every camera's frames at this rate (default: the "
                   f"scenario's fps, 30); output delays are capped at {CAMERA_DELAY_SHARE} of "
                   "a frame")
    p.add_argument("--save-scenario", metavar="PATH",
                   help="at the end, write a scenario YAML of the current state (poses, "
                   "velocities, settings, commands still to run): running it continues from there")
    p.add_argument("--log", metavar="CSV",
                   help="write the run log (time, power, encoder ticks, pose; docs/tuning.md) "
                   "here; with several robots, one file per robot: CSV with the name inserted. An "
                   f"interactive run without it keeps the last {LIVE_RUN_LOG_WINDOW:g} s")
    p.add_argument("--record", metavar="FILE.html",
                   help="at the end, write the run as a Meshcat replay: one self-contained HTML "
                   "file with a timeline, opens offline (also with --headless)")
    p.add_argument("--mcap", metavar="FILE.mcap",
                   help="write the run's Foxglove topics (/tf, /odom, /joint_states, /ir/..., "
                   "/camera/image/compressed, /commands; docs/recording.md) as MCAP")
    p.add_argument("--foxglove", nargs="?", type=int, const=DEFAULT_FOXGLOVE_PORT,
                   metavar="PORT",
                   help="serve the same topics live to Foxglove (WebSocket) on --host, in real "
                   f"time (PORT default {DEFAULT_FOXGLOVE_PORT}; 0 picks a free one)")
    _add_ros2_arguments(p)
    return p


# --- ROS 2 (corobot_drake/ros2/; docs/ros2.md) ---------------------------------------------------


def _add_ros2_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--ros2", action="store_true",
                   help="run in real time as the ROS 2 node corobot_drake (topics, /cmd_vel, "
                   "actions, services; docs/ros2.md); discovery stays on this machine unless "
                   "ROS_AUTOMATIC_DISCOVERY_RANGE or --ros2-network says otherwise; ROS's own "
                   "arguments follow --ros-args (remaps, namespace, -p, --params-file)")
    p.add_argument("--ros2-network", action="store_true",
                   help="--ros2: discovery on the local network (SUBNET): any ROS 2 node there "
                   "with the same ROS_DOMAIN_ID can read the topics and drive the robot")
    p.add_argument("--paused", action="store_true",
                   help="--ros2: start paused (play, step and reset with the ROS 2 Simulation "
                   "Interfaces: docs/ros2.md)")
    p.add_argument("--rosbag", metavar="DIR",
                   help="write the ROS 2 topics as a rosbag2 directory (MCAP, CDR) that `ros2 "
                   "bag play` replays; headless at simulation speed, no ROS needed")


def check_ros2_arguments(args) -> None:
    """--ros2 and --rosbag: the extra installed (one line naming it), the bag's directory new;
    --paused only with --ros2 (only the ROS 2 node can play: the HTTP API has no such call)."""
    if not args.ros2:
        if args.paused:
            raise ArgumentError("--paused: only with --ros2")
        if args.ros2_network:
            raise ArgumentError("--ros2-network: only with --ros2")
        if getattr(args, "ros_args", None):
            raise ArgumentError("--ros-args: only with --ros2")
    if not (args.ros2 or args.rosbag is not None):
        return
    from corobot_drake.ros2.run import missing, rosbag_problem

    if args.ros2:
        problem = missing("--ros2", live=True)
        if problem:
            raise ArgumentError(problem)
    if args.rosbag is not None:
        problem = missing("--rosbag", live=False) or rosbag_problem(args.rosbag)
        if problem:
            raise ArgumentError(problem if problem.startswith("--rosbag")
                                else f"--rosbag: {args.rosbag}: {problem}")


RATE = Range(0.0, 1000.0, low_open=True, why="simulated s per wall-clock s; or max")


def run_rate(text) -> float:
    """--rate: a number in `RATE`, or `max` (`serving.runner.MAX_RATE`: as fast as it
    can); ArgumentError naming the flag otherwise."""
    if isinstance(text, float):
        return text
    if text.strip().lower() == "max":
        return math.inf
    try:
        value = float(text)
    except ValueError:
        raise ArgumentError(f"--rate: expected a number or max, got {text!r}") from None
    _check("--rate", value, RATE)
    return value


def _ros2_front(args, scenario):
    """The run's ROS 2 node and bag (`ros2.run.Ros2Front`), or an empty block."""
    if not (args.ros2 or args.rosbag is not None):
        return contextlib.nullcontext()
    from corobot_drake.ros2.run import Ros2Front

    try:
        return Ros2Front(args, list(scenario.robots))
    except ValueError as e:  # a ROS parameter's value (`ros2.parameters`)
        raise ArgumentError(f"--ros-args: {e}") from None


def split_ros_args(argv: list[str]) -> tuple[list[str], list[str]]:
    """The command line without ROS's part, and ROS's: what follows `--ros-args` up to a lone
    `--` (rcl's convention: remaps `-r`, `-p` parameters, `--params-file`, ...), for --ros2."""
    if "--ros-args" not in argv:
        return argv, []
    start = argv.index("--ros-args")
    end = argv.index("--", start) if "--" in argv[start:] else len(argv)
    return argv[:start] + argv[end + 1:], argv[start + 1:end]


class _HeadlessProgress:
    """A progress line on stderr, once a run has taken PROGRESS_AFTER wall-clock seconds."""

    def __init__(self, total: float):
        self._total = total
        self._start = self._last = time.perf_counter()
        self._printed = False

    def __call__(self, sim: Simulation) -> None:
        now = time.perf_counter()
        if now - self._start < PROGRESS_AFTER or now - self._last < 1.0:
            return
        self._last, self._printed = now, True
        print(f"\rt = {sim.time:7.2f} / {self._total:.2f} s  ({sim.realtime_factor:.1f}x "
              "real time)", end="", file=sys.stderr, flush=True)

    def finish(self) -> None:
        """Ends the progress line (once)."""
        if self._printed:
            print(file=sys.stderr)
            self._printed = False


def run_log_window(args) -> float | None:
    """s of run log kept in memory: the interactive Meshcat run may be left running, so it
    keeps the newest `LIVE_RUN_LOG_WINDOW` unless --log asks for the whole run; a headless
    run ends by itself and keeps it all (`Simulation.run_log_window`)."""
    if args.headless or args.log is not None:
        return None
    return LIVE_RUN_LOG_WINDOW


def _run_interactive(sim: Simulation, meshcat, duration: float) -> None:
    from corobot_drake.serving.teleop import MeshcatTeleop

    teleop = MeshcatTeleop(meshcat, sim)
    sim.simulator.set_target_realtime_rate(1.0)
    end = sim.time + duration
    try:  # a Ctrl-C from the first line printed on stops cleanly
        print(f"Meshcat: {meshcat.web_url()}  (hold the arrows to drive, Space stops, E enables, "
              "F follows; Ctrl-C quits)", flush=True)
        while sim.time < end:
            teleop.poll()
            sim.advance_to(_next_view_stop(sim, end))
    except KeyboardInterrupt:
        print("\nstopped", file=sys.stderr)


def _next_view_stop(sim: Simulation, end: float) -> float:
    """s: where the interactive view stops next: a frame (1/30 s) on, or `end`; on a
    continuous plant, on its last physics step before that (at least the next one), so that
    the view changes nothing of the motion (`Simulation.stop_time`)."""
    t = sim.time + 1.0 / 30.0
    if sim.continuous:
        t = max(sim.stop_time(t), sim.time + sim.physics_step)
    return min(end, t)


# --- checks of the command line, before anything is built ------------------------------------

PORT = Range(0, 65535, why="0 picks a free one")
HEADLESS_DURATION = Range(0.0, DURATION.high, low_open=True, unit="s",
                          why="a headless run ends by itself")

OUTPUT_FLAGS = {"summary": "file", "save_scenario": "file", "log": "file",
                "save_camera": "directory", "record": "file", "mcap": "file"}
"""The flags that name an output (argparse dest -> `file` or `directory`): each is checked
before the run (`check_outputs`). A new output flag joins here."""


def _check(flag: str, value, bound: Range) -> None:
    problem = bound.problem(value)
    if problem:
        raise ArgumentError(f"{flag}: {problem}")


def file_problem(path: Path) -> str | None:
    """Why a file cannot be written at `path` (its directory must exist), else None. A FIFO
    or a device is refused: writing would wait for a reader, or go nowhere."""
    directory = path.parent
    if path.is_dir():
        return "is a directory; name a file"
    if path.exists() and not path.is_file():
        kind = "a FIFO" if path.is_fifo() else "a device" if (
            path.is_char_device() or path.is_block_device()) else "not a regular file"
        return f"is {kind}; name a regular file"
    if not directory.is_dir():
        return f"the directory {directory} does not exist"
    if path.exists() and not os.access(path, os.W_OK):
        return "the file is not writable"
    if not os.access(directory, os.W_OK | os.X_OK):
        return f"the directory {directory} is not writable"
    return None


def directory_problem(path: Path) -> str | None:
    """Why files cannot be written under `path` (made when needed), else None."""
    if path.exists() and not path.is_dir():
        return "is a file, not a directory"
    ancestor = path  # the first that exists: the directories below it can be made
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        return f"{ancestor} is not a directory"
    if not os.access(ancestor, os.W_OK | os.X_OK):
        return f"{ancestor} is not writable"
    return None


def check_outputs(args) -> None:
    """Every output path can be written (its directory exists and is writable), before a
    run that would otherwise end without its results; ArgumentError names the flag."""
    for dest, kind in OUTPUT_FLAGS.items():
        value = getattr(args, dest, None)
        if value is not None:
            problem = (file_problem if kind == "file" else directory_problem)(Path(value))
            if problem:
                raise ArgumentError(f"--{dest.replace('_', '-')}: {value}: {problem}")


def shared_token(args) -> str | None:
    """The token --serve and --foxglove ask for (`serving.security.Access.for_host`): --token;
    else none on loopback; else one made here, so that both servers on --host share it."""
    from corobot_drake.serving.security import Access

    if not args.serve and args.foxglove is None:
        return args.token
    try:
        return Access.for_host(args.host, args.token).token
    except ValueError as e:
        raise ArgumentError(str(e)) from None  # "--token must not be empty"


def check_arguments(args) -> None:
    """The command line's numbers within their bounds and its outputs writable."""
    if args.duration is not None:
        _check("--duration", args.duration,
               HEADLESS_DURATION if args.headless and not (args.serve or args.ros2)
               else SIMULATION_DURATION)
    if args.camera_rate is not None:
        _check("--camera-rate", args.camera_rate, DRAKE_BOUNDS[CameraConfig]["fps"])
    if args.serve:
        _check("--port", args.port, PORT)
    args.rate = run_rate(args.rate)
    if args.rate != 1.0 and not (args.serve or args.ros2):  # a run's pace: a live one's only
        raise ArgumentError("--rate: only with --serve or --ros2")
    if args.foxglove is not None:
        _check("--foxglove", args.foxglove, PORT)
    if args.record and args.serve:
        raise ArgumentError("--record: not with --serve (the replay is written when a run ends)")
    check_extras(args)
    check_outputs(args)
    check_ros2_arguments(args)


def check_extras(args) -> None:
    """Each front end the command line asks for has its extra installed."""
    from corobot_drake.extras import MissingExtraError, require

    wanted = {"--serve": ("serve", args.serve), "--foxglove": ("record", args.foxglove),
              "--mcap": ("record", args.mcap)}
    try:
        for flag, (extra, value) in wanted.items():
            if value is not None and value is not False:  # `--foxglove 0` asks too (0 == False)
                require(extra, flag)
    except MissingExtraError as e:
        raise ArgumentError(str(e)) from None


# --- writing the results ---------------------------------------------------------------------


def _write_logs(sim: Simulation, path: Path) -> None:
    """One robot: `path`; several: `path` with `.<robot>` before the suffix."""
    for name, robot in sim.robots.items():
        robot.write_log(path if len(sim.robots) == 1
                        else path.with_name(f"{path.stem}.{name}{path.suffix}"))


def write_output(flag: str, path: str, write) -> bool:
    """`write(path)`; if that fails (the disk filled, the directory went), `write` into a
    fallback file in the temporary directory, named in the one-line error. False then (and
    when the fallback fails too: its own line)."""
    try:
        write(Path(path))
        return True
    except OSError as e:
        problem = f"error: {flag}: {path}: cannot write ({e.strerror})"
    try:
        fd, fallback = tempfile.mkstemp(prefix=f"corobot-{flag.strip('-')}-",
                                        suffix=Path(path).suffix)
        os.close(fd)
        write(Path(fallback))
    except OSError as e:
        print(f"{problem}; nor to the temporary directory ({e.strerror}): lost",
              file=sys.stderr)
        return False
    print(f"{problem}; written to {fallback} instead", file=sys.stderr)
    return False


def _write_results(sim: Simulation, args, summary: dict) -> int:
    """The run's outputs; exit status 1 when one went to its fallback file."""
    outputs = (
        ("--log", args.log, lambda p: _write_logs(sim, p)),
        ("--summary", args.summary, lambda p: p.write_text(json.dumps(summary, indent=2) + "\n")),
        ("--save-scenario", args.save_scenario, sim.save_scenario),
        ("--record", args.record, sim.save_recording),
    )
    written = [write_output(flag, path, write) for flag, path, write in outputs if path]
    for robot in sim.robots.values():  # written as the run went: a full disk is said here
        for problem in robot.camera_save_problems():
            print(f"error: --save-camera: {problem}", file=sys.stderr)
            written.append(False)
    return 0 if all(written) else 1


class _FoxgloveSinks(contextlib.ExitStack):
    """--mcap and --foxglove: one foxglove Context with its MCAP file and live server,
    closed (the file finished, the server stopped) on leaving the block; `finished` False
    when the MCAP file could not be finished (one line said so)."""

    def __init__(self, args):
        super().__init__()
        self.context, self.finished = None, True
        if args.mcap is None and args.foxglove is None:
            return
        try:
            self._open(args)
        except BaseException:  # the MCAP file cannot be made, a Ctrl-C: the server stops
            self.close()
            raise

    def _open(self, args) -> None:
        import foxglove

        from corobot_drake.recording.foxglove_live import FoxgloveLive
        from corobot_drake.recording.mcap_log import McapLog
        from corobot_drake.serving.security import is_loopback, other_machines_line

        self.context = foxglove.Context()
        if args.foxglove is not None:  # first: a taken port leaves no file behind
            live = self.enter_context(FoxgloveLive(args.foxglove, args.host, self.context,
                                                   token=args.token))
            # stderr: --serve's first stdout line is its URL (scripts read it)
            print(f"Foxglove: {live.url}  (Foxglove: Open connection > Foxglove WebSocket)",
                  file=sys.stderr, flush=True)
            others = other_machines_line(live.access, live.url_on)  # on 0.0.0.0, as --serve
            if others:
                print(others, file=sys.stderr, flush=True)
            if not is_loopback(args.host):
                print(f"warning: Foxglove on {args.host}: anyone who can reach it and has the "
                      "token sees every topic", file=sys.stderr, flush=True)
        if args.mcap is not None:
            log = McapLog(args.mcap, self.context)
            self.callback(self._finish, log)

    def _finish(self, log) -> None:
        try:
            log.close()
        except OSError as e:
            self.finished = False
            print(f"error: --mcap: {log.path}: cannot write ({e}); the file is incomplete",
                  file=sys.stderr)


def _one_line_warning(message, category, filename, lineno, line=None) -> str:
    return f"warning: {message}\n"


STOPPED_BY: int | None = None
"""The signal that stopped this process's run (`ctrl_c_stops`), else None."""


_WRITING_OUTPUTS = False
"""True while a run's outputs are written (`_finish`): a signal then is recorded, not raised."""


def _stop(signum, frame) -> None:
    """The first SIGINT or SIGTERM raises KeyboardInterrupt where the program is (unless the
    outputs are being written: it is recorded, and they are finished); later ones are
    ignored, so that the outputs of the run so far are written whole."""
    global STOPPED_BY
    if STOPPED_BY is None:
        STOPPED_BY = signum
        if not _WRITING_OUTPUTS:
            raise KeyboardInterrupt


def ctrl_c_stops() -> None:
    """Makes SIGINT (Ctrl-C) and SIGTERM (`kill`, a service manager) raise KeyboardInterrupt in
    this process, once (`_stop`), even when it was started with SIGINT ignored (a background
    job of a non-interactive shell, e.g. a CI script, inherits SIG_IGN, and Python then keeps
    it): a run stops cleanly and writes what was asked. For a program's entry point only
    (`python -m corobot_drake`, `python -m corobot_drake.study`)."""
    import signal

    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, _stop)


def stopped_status() -> int:
    """The exit status of a run a signal stopped: 128 + the signal (130 for Ctrl-C)."""
    import signal

    return 128 + (STOPPED_BY or signal.SIGINT)


def _stopped_line(sim: Simulation, duration: float) -> None:
    import signal

    name = signal.Signals(STOPPED_BY or signal.SIGINT).name
    print(f"stopped by {name} at t = {sim.time:.2f} s of {duration:.2f} s; writing the "
          "outputs of the run so far", file=sys.stderr, flush=True)


def main(argv: list[str] | None = None) -> int:
    warnings.formatwarning = _one_line_warning  # for a user, not a developer: no source lines
    argv, ros_args = split_ros_args(sys.argv[1:] if argv is None else list(argv))
    args = _parser().parse_args(argv)
    args.ros_args = ros_args
    try:
        return _main(args)
    except KeyboardInterrupt:  # before the run started (loading, building): nothing to write
        print("stopped before the run started", file=sys.stderr)
        return stopped_status()


def _main(args) -> int:
    """`main` once the arguments are parsed."""
    try:
        check_arguments(args)
        args.token = shared_token(args)
        scenario = load_scenario(scenario_path(args.scenario), overrides=args.override)
    except (ArgumentError, ScenarioError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    if args.camera_rate is not None:
        for camera in (c for r in scenario.robots.values() for c in r.cameras.values()):
            camera.fps = args.camera_rate
            # A frame's output delay must stay under one frame (Drake's RgbdSensorAsync).
            camera.output_delay = min(camera.output_delay, CAMERA_DELAY_SHARE / args.camera_rate)
    duration = args.duration if args.duration is not None else scenario.simulation_duration
    from corobot_drake.simulation import quiet_drake_warnings

    quiet_drake_warnings()
    try:
        sinks = _FoxgloveSinks(args)
    except (OSError, RuntimeError) as e:  # the port is taken, the file can't be made
        print(f"error: --{'foxglove' if isinstance(e, RuntimeError) else 'mcap'}: "
              f"{str(e).splitlines()[0]}", file=sys.stderr)
        return 2
    try:
        with sinks, _ros2_front(args, scenario) as ros2:
            status = _run(args, scenario, duration, sinks.context, ros2)
    except ArgumentError as e:  # (only `_ros2_front` raises it)
        print(f"error: {e}", file=sys.stderr)
        return 2
    finished = sinks.finished and (ros2 is None or ros2.finished)  # a full disk: one line said
    return status if finished else max(status, 1)


def _run(args, scenario, duration: float, foxglove, ros2=None) -> int:
    """Builds the simulation and runs it (served, in Meshcat or headless), then writes the
    requested outputs; `foxglove`: the Context the run's topics go to (or None); `ros2`: the
    run's ROS 2 node and bag (`ros2.run.Ros2Front`, or None)."""
    from corobot_drake.sensors.camera import RendererUnavailableError
    from corobot_drake.simulation import PhysicsError, Simulation

    extras = ros2.extras if ros2 is not None else ()
    started_with = tuple(scenario.robots)  # a rebuild (a robot spawned) keeps their names
    if args.serve:  # Meshcat is made in the simulation thread (it must be used from there)
        from corobot_drake.serving.serve import serve, serve_camera_rate

        if args.camera_rate is None:
            serve_camera_rate(scenario)
        return serve(lambda meshcat, scenario=scenario: Simulation(
                         scenario, meshcat, foxglove=foxglove, extras=extras,
                         started_with=started_with),
                     host=args.host, port=args.port, meshcat=not args.headless,
                     label=args.scenario, token=args.token,
                     attach=ros2.attach if args.ros2 else None,
                     rate=args.rate, paused=args.paused)
    if args.ros2:
        from corobot_drake.ros2.run import run_live

        try:
            return run_live(ros2, lambda meshcat, scenario=scenario: Simulation(
                scenario, meshcat, save_camera=args.save_camera, record=args.record is not None,
                foxglove=foxglove, run_log_window=run_log_window(args), extras=extras,
                started_with=started_with),
                meshcat=not args.headless, duration=duration,
                run_log_window=run_log_window(args),
                finish=lambda sim: _finish(sim, args, ros2.realtime_factor(sim)),
                rate=args.rate, paused=args.paused)
        except (ValueError, RendererUnavailableError) as e:
            print(f"error: {args.scenario}: (top level): {e}", file=sys.stderr)
            return 2
        except PhysicsError as e:  # its outputs are written (`run_live`)
            print(f"error: {args.scenario}: {e}", file=sys.stderr, flush=True)
            return 1
    meshcat = None
    if not args.headless:
        from pydrake.geometry import StartMeshcat

        meshcat = StartMeshcat()
    try:
        sim = Simulation(scenario, meshcat, save_camera=args.save_camera,
                         record=args.record is not None, foxglove=foxglove,
                         run_log_window=run_log_window(args), extras=extras)
    except (ValueError, RendererUnavailableError) as e:  # the loader missed it: still one line
        print(f"error: {args.scenario}: (top level): {e}", file=sys.stderr)
        return 2
    try:
        _run_here(sim, meshcat, args.headless, duration, args.foxglove is not None)
    except PhysicsError as e:  # the run so far is kept: its outputs are written
        print(f"error: {args.scenario}: {e}", file=sys.stderr, flush=True)
        return max(_finish(sim, args), 1)
    return _finish(sim, args)


def _run_here(sim: Simulation, meshcat, headless: bool, duration: float, live: bool) -> None:
    """Runs `sim` for `duration` s, headless (`live`: at real time, watched in Foxglove) or
    in Meshcat."""
    if not headless:
        _run_interactive(sim, meshcat, duration)
        return
    if math.isinf(duration):
        duration = HEADLESS_DEFAULT_DURATION
    progress = _HeadlessProgress(duration)
    if live:
        sim.simulator.set_target_realtime_rate(1.0)
    try:
        sim.run(duration, progress=progress)
    except KeyboardInterrupt:  # SIGINT or SIGTERM (`ctrl_c_stops`): keep the run so far
        progress.finish()
        _stopped_line(sim, duration)
    finally:  # (also before a PhysicsError's line: the progress line ends first)
        progress.finish()


def simulated_line(end: float, start: float) -> str:
    """The closing line's start: the simulated time the run took (s), and where it began and
    ended when not at 0 (a saved scenario resumed, a `start_time`)."""
    line = f"simulated {end - start:.2f} s"
    return line + (f" (t = {start:.2f} to {end:.2f} s)" if start != 0 else "")


def _finish(sim: Simulation, args, paced: float | None = None) -> int:
    """The run's closing line and its outputs (`_write_results`), written whole even if a
    stop signal comes meanwhile (it sets the exit status). `paced`: a live run's measured
    real-time factor (`Ros2Front.realtime_factor`), said instead of the compute time's."""
    import signal

    global _WRITING_OUTPUTS
    _WRITING_OUTPUTS, stopped_before = True, STOPPED_BY
    try:
        summary = sim.summary()
        rate = summary["realtime_factor"] if paced is None else paced  # NaN: no step taken
        print(simulated_line(summary["time"], sim.scenario.simulator_config.start_time)
              + (f" at {rate:.1f}x real time" if math.isfinite(rate) else ""))
        status = _write_results(sim, args, summary)
    finally:
        _WRITING_OUTPUTS = False
    if STOPPED_BY is not None and stopped_before is None:
        print(f"stopped by {signal.Signals(STOPPED_BY).name} while the outputs were written: "
              "they were finished first", file=sys.stderr)
    return stopped_status() if STOPPED_BY is not None and status == 0 else status


if __name__ == "__main__":
    sys.exit(main())
