"""`python -m corobot_drake [SCENARIO]`: run a scenario in Meshcat or headless.

Exit status: 0 on success, 2 for a bad scenario or bad arguments (one line on stderr).
"""

import argparse
import contextlib
import json
import math
import sys
import time
import warnings
from pathlib import Path

from corobot_drake.config.scenario import ScenarioError, load_scenario
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.sensors.camera import RendererUnavailableError
from corobot_drake.simulation import Simulation, quiet_drake_warnings

CAMERA_DELAY_SHARE = 0.9
"""--camera-rate HZ caps the cameras' output_delay at this share of a frame, 1/HZ."""

DEFAULT_FOXGLOVE_PORT = 8765
"""Foxglove's own default WebSocket port (`recording.foxglove_live.DEFAULT_PORT`)."""
HEADLESS_DEFAULT_DURATION = 10.0
PROGRESS_AFTER = 3.0
"""Wall-clock seconds after which a headless run starts printing progress."""


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m corobot_drake", description=__doc__.splitlines()[0])
    p.add_argument("scenario", nargs="?", default=str(DEFAULT_SCENARIO),
                   help="scenario YAML (default: scenarios/corobot.yaml)")
    p.add_argument("--headless", action="store_true",
                   help="no Meshcat; run as fast as possible")
    p.add_argument("--duration", type=float, default=None,
                   help="simulated seconds (default: the scenario's simulation_duration; "
                   f"headless with none: {HEADLESS_DEFAULT_DURATION:g})")
    p.add_argument("--override", action="append", default=[], metavar="YAML_TEXT",
                   help="YAML merged over the scenario (repeatable)")
    p.add_argument("--summary", metavar="PATH", help="write the run's summary JSON here")
    p.add_argument("--serve", action="store_true",
                   help="run in real time with the HTTP services, dashboard and webcam page "
                   "(Meshcat too unless --headless); Ctrl-C stops")
    p.add_argument("--port", type=int, default=50000,
                   help="--serve: TCP port (default 50000; 0 picks a free one)")
    p.add_argument("--host", default="127.0.0.1",
                   help="--serve, --foxglove: address to listen on (default 127.0.0.1)")
    p.add_argument("--save-camera", metavar="DIR",
                   help="write each robot's camera frames as PNG: "
                   "DIR/<robot>/frame_000000.png, ...")
    p.add_argument("--camera-rate", type=float, metavar="HZ",
                   help="render (and save) camera frames at this rate (default: the scenario's "
                   f"camera fps, 30); output delays are capped at {CAMERA_DELAY_SHARE} of a frame")
    p.add_argument("--save-scenario", metavar="PATH",
                   help="at the end, write a scenario YAML of the current state (poses, "
                   "velocities, settings, commands still to run): running it continues from there")
    p.add_argument("--log", metavar="CSV",
                   help="write the run log (time, power, encoder ticks, pose; docs/tuning.md) "
                   "here; with several robots, one file per robot: CSV with the name inserted")
    p.add_argument("--record", metavar="FILE.html",
                   help="at the end, write the run as a Meshcat replay: one self-contained HTML "
                   "file with a timeline, opens offline (also with --headless)")
    p.add_argument("--mcap", metavar="FILE.mcap",
                   help="write the run's Foxglove topics (/tf, /odom, /joint_states, /ir/..., "
                   "/camera/image/compressed, /commands; README: Coming from ROS 2) as MCAP")
    p.add_argument("--foxglove", nargs="?", type=int, const=DEFAULT_FOXGLOVE_PORT,
                   metavar="PORT",
                   help="serve the same topics live to Foxglove (WebSocket) on --host, in real "
                   f"time (PORT default {DEFAULT_FOXGLOVE_PORT}; 0 picks a free one)")
    return p


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
        if self._printed:
            print(file=sys.stderr)


def _run_interactive(sim: Simulation, meshcat, duration: float) -> None:
    from corobot_drake.serving.teleop import MeshcatTeleop

    teleop = MeshcatTeleop(meshcat, sim)
    sim.simulator.set_target_realtime_rate(1.0)
    print(f"Meshcat: {meshcat.web_url()}  (hold the arrows to drive, Space stops, E enables, F "
          "follows; Ctrl-C quits)", flush=True)
    end = sim.time + duration
    try:
        while sim.time < end:
            teleop.poll()
            sim.advance_to(min(end, sim.time + 1.0 / 30.0))
    except KeyboardInterrupt:
        print("\nstopped", file=sys.stderr)


def _write_logs(sim: Simulation, path: Path) -> None:
    """One robot: `path`; several: `path` with `.<robot>` before the suffix."""
    for name, robot in sim.robots.items():
        robot.write_log(path if len(sim.robots) == 1
                        else path.with_name(f"{path.stem}.{name}{path.suffix}"))


def _output_path_error(args) -> str | None:
    """The first output flag (--record, --mcap) whose file cannot be written there: its one-line
    error, or None."""
    for flag in ("record", "mcap"):
        path = getattr(args, flag)
        if path is None:
            continue
        if Path(path).is_dir():
            return f"--{flag}: {path} is a directory; give a file name"
        if not Path(path).resolve().parent.is_dir():
            return f"--{flag}: {path}: no such directory {Path(path).parent}"
    if args.record and args.serve:
        return "--record: not with --serve (the replay is written when a run ends)"
    return None


class _FoxgloveSinks(contextlib.ExitStack):
    """--mcap and --foxglove: one foxglove Context with its MCAP file and live server,
    closed (the file finished, the server stopped) on leaving the block."""

    def __init__(self, args):
        super().__init__()
        self.context = None
        if args.mcap is None and args.foxglove is None:
            return
        import foxglove

        from corobot_drake.recording.foxglove_live import FoxgloveLive
        from corobot_drake.recording.mcap_log import McapLog

        self.context = foxglove.Context()
        if args.foxglove is not None:  # first: a taken port leaves no file behind
            live = self.enter_context(FoxgloveLive(args.foxglove, args.host, self.context))
            # stderr: --serve's first stdout line is its URL (scripts read it)
            print(f"Foxglove: {live.url}  (Foxglove: Open connection > Foxglove WebSocket)",
                  file=sys.stderr, flush=True)
        if args.mcap is not None:
            self.enter_context(McapLog(args.mcap, self.context))


def _one_line_warning(message, category, filename, lineno, line=None) -> str:
    return f"warning: {message}\n"


def main(argv: list[str] | None = None) -> int:
    warnings.formatwarning = _one_line_warning  # for a user, not a developer: no source lines
    args = _parser().parse_args(argv)
    try:
        scenario = load_scenario(args.scenario, overrides=args.override)
    except ScenarioError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    if args.duration is not None and not (args.duration >= 0):
        print(f"error: --duration must be >= 0, got {args.duration}", file=sys.stderr)
        return 2
    if args.camera_rate is not None:
        if not (args.camera_rate > 0 and math.isfinite(args.camera_rate)):
            print(f"error: --camera-rate must be > 0, got {args.camera_rate}", file=sys.stderr)
            return 2
        for robot in scenario.robots.values():
            robot.camera.fps = args.camera_rate
            # A frame's output delay must stay under one frame (Drake's RgbdSensorAsync).
            robot.camera.output_delay = min(robot.camera.output_delay,
                                            CAMERA_DELAY_SHARE / args.camera_rate)
    duration = args.duration if args.duration is not None else scenario.simulation_duration
    if (problem := _output_path_error(args)) is not None:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    quiet_drake_warnings()
    try:
        sinks = _FoxgloveSinks(args)
    except (OSError, RuntimeError) as e:  # the port is taken, the file can't be made
        print(f"error: --{'foxglove' if isinstance(e, RuntimeError) else 'mcap'}: "
              f"{str(e).splitlines()[0]}", file=sys.stderr)
        return 2
    with sinks:
        return _run(args, scenario, duration, sinks.context)


def _run(args, scenario, duration: float, foxglove) -> int:
    """Builds the simulation and runs it (served, in Meshcat or headless), then writes the
    requested outputs; `foxglove`: the Context the run's topics go to (or None)."""
    if args.serve:  # Meshcat is made in the simulation thread (it must be used from there)
        from corobot_drake.serving.serve import serve, serve_camera_rate

        if args.camera_rate is None:
            serve_camera_rate(scenario)
        return serve(lambda meshcat: Simulation(scenario, meshcat, foxglove=foxglove),
                     host=args.host, port=args.port, meshcat=not args.headless,
                     label=args.scenario)
    meshcat = None
    if not args.headless:
        from pydrake.geometry import StartMeshcat

        meshcat = StartMeshcat()
    try:
        sim = Simulation(scenario, meshcat, save_camera=args.save_camera,
                         record=args.record is not None, foxglove=foxglove)
    except (ValueError, RendererUnavailableError) as e:  # e.g. a non-finite number in a command
        print(f"error: {args.scenario}: {e}", file=sys.stderr)
        return 2
    if args.headless:
        if math.isinf(duration):
            duration = HEADLESS_DEFAULT_DURATION
        progress = _HeadlessProgress(duration)
        if args.foxglove is not None:  # live: watched as it happens
            sim.simulator.set_target_realtime_rate(1.0)
        sim.run(duration, progress=progress)
        progress.finish()
    else:
        _run_interactive(sim, meshcat, duration)
    summary = sim.summary()
    print(f"simulated {summary['time']:.2f} s at {summary['realtime_factor']:.1f}x real time")
    if args.log:
        _write_logs(sim, Path(args.log))
    if args.summary:
        Path(args.summary).write_text(json.dumps(summary, indent=2) + "\n")
    if args.save_scenario:
        sim.save_scenario(args.save_scenario)
    if args.record:
        sim.save_recording(args.record)
    return 0


if __name__ == "__main__":
    sys.exit(main())
