"""`python -m corobot_drake [SCENARIO] --serve`: the processes. The simulation process runs the
simulation in real time in one thread (`runner.SimRunner`); the HTTP server (`webapp`) runs in
a child process of its own, joined by a pipe (`transport`).

Why a second process: the simulation's Python systems give up and re-take Python's GIL many
times per step, so in one process a busy HTTP thread makes the simulation wait at every one
of those hand-overs. With the server in its own process the simulation thread shares its GIL
with nothing busy, and the HTTP process runs at a lower priority (nice), so under load the
pages slow down, not the simulation (docs/services.md, "Tests and measured figures"). Each
process ends when the other does: the HTTP process by the kernel's parent-death signal, the
simulation process by watching the HTTP process's handle.

Meshcat starts too unless `--headless`; its teleop buttons keep working, polled by the
simulation thread. `--port 0` picks a free port; the first line printed to stdout is always
`serving http://HOST:PORT` once the server listens (tests and scripts read it).
`ServerProcess` runs all of it as a child process, for tests and scripts.
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading

from corobot_drake.limits import LIVE_RUN_LOG_WINDOW
from corobot_drake.serving.security import is_loopback, other_machines_line, reachable_host

SWITCH_INTERVAL = 0.001
"""s. Python's GIL hand-over interval in the simulation process while serving. The
simulation's Python systems re-take the GIL many times a step; the transport's threads are
mostly idle, but at the default 5 ms each of their wake-ups could hold the simulation up."""

HTTP_NICENESS = 10
"""The HTTP process's nice increment: under CPU contention the simulation comes first."""

HTTP_STOP_TIMEOUT = 10.0
"""s the HTTP process has, once the simulation stops, to answer the requests in flight (503)
and exit before it is terminated (called from Python, a second Ctrl-C terminates it at once;
`python -m corobot_drake` takes only the first signal). It takes under a second on an idle
machine; niced (HTTP_NICENESS) on a busy one, a few."""

SERVE_RUN_LOG_WINDOW = LIVE_RUN_LOG_WINDOW
"""s of run log a served simulation keeps in memory: serving runs for days, and nothing it
serves reads the run log (`limits.LIVE_RUN_LOG_WINDOW`)."""

SERVE_CAMERA_FPS = 10.0
"""Hz: the camera's render rate when serving, unless --camera-rate says otherwise. The
dashboard and the webcam page show a few frames a second; rendering 30 would cost a
third of the simulation's time budget."""


def serve(make_sim, host: str = "127.0.0.1", port: int = 50000, meshcat: bool = False,
          log_level: str = "warning", label: str = "", token: str | None = None,
          rate: float = 1.0, attach=None, paused: bool = False) -> int:
    """Builds the simulation (`make_sim(meshcat)`, in the simulation thread, with a Meshcat
    made there too when `meshcat`: Meshcat must be used from the thread that made it) and
    serves it until Ctrl-C. The HTTP server runs in a child process (see the module
    docstring), behind `security.Access.for_host(host, token)` (off loopback a token is
    needed: `token`, or one made and printed). `rate`: simulated s per wall-clock s (a rate
    the machine cannot keep runs as fast as it can; tools/bench_memory.py; `runner.MAX_RATE`
    asks for that; `paused`: start paused, for the ROS 2 node to play). Returns the exit
    status: 2 when the port, the token or the simulation cannot be had. `attach(runner)`, if
    given, is called with the runner before it starts (another front end taking commands
    through it: the ROS 2 node, `ros2.run.Ros2Front.attach`)."""
    import multiprocessing

    from corobot_drake.serving.security import Access
    from corobot_drake.serving.transport import SimSide

    try:
        access = Access.for_host(host, token)
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    ctx = multiprocessing.get_context("spawn")
    conn, child_conn = ctx.Pipe()
    # The kernel's parent-death signal follows the thread that starts the child: only the
    # main thread lives as long as this process.
    parent = os.getpid() if threading.current_thread() is threading.main_thread() else None
    http = ctx.Process(target=http_main, name="corobot-http", daemon=True, args=(
        child_conn, access, port, log_level, HTTP_NICENESS, parent))
    http.start()
    child_conn.close()  # this process's copy: the pipe ends when the HTTP process does
    value = _listening_port(http, conn)
    if value is None:
        return 2
    sys.setswitchinterval(SWITCH_INTERVAL)
    runner = sim_runner(make_sim, meshcat, rate, paused=paused)
    if attach is not None:
        attach(runner)
    if not _started(runner, http, label):
        return 2
    bridge = SimSide(runner, conn)
    shown = f"http://{reachable_host(host)}:{value}"
    stats, lost = runner.stats(), False
    try:  # a Ctrl-C from the first line printed on stops cleanly
        _announce(shown, host, value, access, runner)
        while http.is_alive() and runner.alive and not bridge.closed.is_set():
            http.join(0.5)  # wakes at once when the HTTP process ends
            stats = runner.stats()
        lost = runner.alive  # the simulation runs on: the HTTP side went away
    except KeyboardInterrupt:
        pass
    finally:
        runner.stop()  # fails the requests still waiting on the simulation: 503
        bridge.close()  # their answers go out, then the HTTP process sees the pipe close
        with contextlib.suppress(KeyboardInterrupt):  # a second Ctrl-C: terminate it now
            http.join(HTTP_STOP_TIMEOUT)
        if http.is_alive():
            print(f"warning: the HTTP server process ({http.pid}) did not stop within "
                  f"{HTTP_STOP_TIMEOUT:g} s: terminated", file=sys.stderr)
            http.terminate()
            http.join(5)
    from corobot_drake.cli import simulated_line

    print(f"{simulated_line(runner.sim.time, runner.started_sim)} at "
          f"{stats['realtime_factor'] or 0:.2f}x real time ({stats['slips']} slips)",
          file=sys.stderr)
    if lost:
        print(f"error: the HTTP server process ({http.pid}) {_ended(http.exitcode)}: the "
              f"simulation stopped with it", file=sys.stderr)
    return 0 if runner.error is None and not lost else 1


def _listening_port(http, conn) -> int | None:
    """The port the HTTP process listens on, once it reports it; None, its error printed,
    when it cannot listen or ends first."""
    try:
        kind, value = conn.recv()
    except EOFError:
        http.join(5)
        print(f"error: the HTTP server process ({http.pid}) {_ended(http.exitcode)} before "
              "it listened", file=sys.stderr)
        return None
    except KeyboardInterrupt:
        _end(http)
        raise
    if kind == "error":
        http.join(5)
        print(f"error: {value}", file=sys.stderr)
        return None
    return value


def _started(runner, http, label: str) -> bool:
    """Starts the simulation thread (`runner`, which builds the simulation); False, the
    error printed and the HTTP process ended, when the simulation cannot be built."""
    from corobot_drake.sensors.camera import RendererUnavailableError

    try:
        runner.start()
    except (ValueError, RendererUnavailableError) as e:  # e.g. a non-finite number
        _end(http)
        print(f"error: {label + ': ' if label else ''}{e}", file=sys.stderr)
        return False
    except KeyboardInterrupt:  # while the simulation is built (the runner has stopped)
        _end(http)
        raise
    return True


def _end(http) -> None:
    """Ends the HTTP process (SIGTERM) before it serves: it has nothing to finish."""
    http.terminate()
    http.join(5)


def _ended(exitcode: int | None) -> str:
    """How a process ended, from its `multiprocessing` exit code."""
    import signal

    if exitcode is None:
        return "closed its end of the pipe"
    if exitcode < 0:
        return f"was killed by {signal.Signals(-exitcode).name}"
    return f"exited with status {exitcode}"


def _die_with_parent(parent: int | None) -> bool:
    """Asks the kernel (Linux's PR_SET_PDEATHSIG) to send this process SIGTERM when the
    simulation process `parent` dies, however it dies (SIGKILL included; the closed pipe
    tells the HTTP server too, but only once it is connected). False when `parent` is
    already gone."""
    import ctypes
    import signal

    if parent is None or not sys.platform.startswith("linux"):
        return True
    pr_set_pdeathsig = 1
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(pr_set_pdeathsig, signal.SIGTERM, 0, 0, 0)
    return os.getppid() == parent  # it may have died before the request


def _announce(shown: str, host: str, port: int, access, runner) -> None:
    """The lines that say where the server is (and, beyond loopback, the warning). A server
    on every address (0.0.0.0) is shown on loopback, and also by this machine's name, which
    other machines may reach it by (any of its addresses does too)."""
    print(f"serving {shown}", flush=True)
    print(f"  dashboard {access.page_url(shown)}  services {shown}/services  API {shown}/docs"
          + (f"  Meshcat {runner.meshcat_url}" if runner.meshcat_url else ""), flush=True)
    others = other_machines_line(access, lambda name: access.page_url(f"http://{name}:{port}"))
    if others:
        print(others, flush=True)
    if access.token:
        print(f"  token {access.token}  (send 'Authorization: Bearer <token>'; the dashboard "
              "link carries it)", flush=True)
    if not is_loopback(host):
        print(f"warning: serving on {host}: anyone who can reach it and has the token can "
              "drive the robot", file=sys.stderr, flush=True)


def sim_runner(make_sim, meshcat: bool, rate: float = 1.0,
               run_log_window: float | None = SERVE_RUN_LOG_WINDOW, paused: bool = False):
    """A `SimRunner` (not started) whose simulation thread makes the Meshcat (if `meshcat`),
    the simulation (`make_sim(meshcat or None)`) and the Meshcat teleop. When `make_sim`
    takes a `scenario=` keyword, the runner can `rebuild` the simulation of another scenario
    (ROS 2's SpawnEntity) in the same Meshcat."""
    import inspect

    from corobot_drake.serving.runner import SimRunner

    rebuilds = "scenario" in inspect.signature(make_sim).parameters

    def build():
        viewer = None
        if meshcat:
            from pydrake.geometry import StartMeshcat

            viewer = StartMeshcat()
            runner.meshcat_url = viewer.web_url()
        sim = make_sim(viewer)
        sim.run_log_window = run_log_window
        if viewer is not None:
            from corobot_drake.serving.teleop import MeshcatTeleop

            teleop = MeshcatTeleop(viewer, sim)
            # Bound to this simulation: after a rebuild (a spawn) the buttons rest.
            runner.hooks.append(lambda s, first=sim: teleop.poll() if s is first else None)
        if rebuilds:
            runner.rebuild = lambda scenario: _rebuilt(make_sim, viewer, scenario,
                                                       run_log_window)
        return sim

    runner = SimRunner(build, rate=rate, paused=paused)
    return runner


def _rebuilt(make_sim, viewer, scenario, run_log_window: float | None):
    sim = make_sim(viewer, scenario=scenario)
    sim.run_log_window = run_log_window
    return sim


def http_main(conn, access, port: int, log_level: str, niceness: int,
              parent: int | None = None) -> None:
    """The HTTP process: listen on `access.host`, report the port, wait for the simulation,
    serve behind `access` (`security.Access`); end when the simulation process `parent`
    ends, however it ends."""
    import signal

    # A Ctrl-C at a terminal reaches this process too: the simulation process stops it
    # (closing the pipe, or SIGTERM before it serves), so it need not print a traceback.
    if threading.current_thread() is threading.main_thread():  # (a test runs it in a thread)
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    if not _die_with_parent(parent):
        return
    import uvicorn

    from corobot_drake.serving.http_limits import (
        MAX_CONNECTIONS,
        connection_cap,
        file_limit,
        http_config,
        raise_file_limit,
    )
    from corobot_drake.serving.transport import RemoteRunner
    from corobot_drake.serving.webapp import create_app

    if niceness:
        with contextlib.suppress(OSError):
            os.nice(niceness)
    raise_file_limit()
    cap = connection_cap()
    if cap < MAX_CONNECTIONS:  # (the simulation process prints its lines on stdout)
        print(f"note: the HTTP server holds at most {cap} connections at once: this process "
              f"may open {file_limit()} files (ulimit -n)", file=sys.stderr, flush=True)
    sock = _listen(conn, access.host, port)
    if sock is None:
        return
    server_box: list = []
    gone = threading.Event()

    def closed() -> None:  # the simulation process went away: stop serving
        gone.set()
        if server_box:
            server_box[0].should_exit = True

    try:
        runner = RemoteRunner(conn, on_close=closed)
    except (TimeoutError, EOFError, OSError):
        return
    config = http_config(create_app(runner, access), log_level=log_level,
                         max_connections=cap, timeout_graceful_shutdown=1)
    server = uvicorn.Server(config)
    server_box.append(server)
    if gone.is_set():  # it stopped while the app was built (this niced process is slow to start)
        return
    with contextlib.suppress(KeyboardInterrupt):
        server.run(sockets=[sock])


def _listen(conn, host: str, port: int):
    """A socket listening on host:port, its port reported on `conn` ("listening", port);
    None, with ("error", message) reported, when the port cannot be had."""
    import socket

    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
        sock.listen(2048)
    except OSError as e:
        conn.send(("error", f"cannot listen on {host}:{port}: {e.strerror}"))
        return None
    conn.send(("listening", sock.getsockname()[1]))
    return sock


def serve_camera_rate(scenario, fps: float = SERVE_CAMERA_FPS) -> None:
    """Caps every robot camera's rate at `fps`."""
    for robot in scenario.robots.values():
        for camera in robot.cameras.values():
            camera.fps = min(camera.fps, fps)


class ServerProcess:
    """`python -m corobot_drake ... --serve --port 0` in a child process, for tests and
    scripts: `with ServerProcess(["--headless"]) as server: server.url`."""

    def __init__(self, args: list[str] = (), startup_timeout: float = 120.0,
                 stderr_path: str | None = None, file_limit: int | None = None):
        self.args = list(args)
        self.file_limit = file_limit
        """The files each of the server's processes may open (`ulimit -n`; None: as is)."""
        self.startup_timeout = startup_timeout
        self.stderr_path = stderr_path
        self.url: str | None = None
        self.token: str | None = (self.args[self.args.index("--token") + 1]
                                  if "--token" in self.args else None)
        """The token given with --token (None: none given)."""
        self.lines: list[str] = []
        """What the server printed on stdout after its first line."""
        self.process = None

    def __enter__(self) -> ServerProcess:
        import subprocess
        import threading

        stderr = open(self.stderr_path, "w") if self.stderr_path else subprocess.DEVNULL
        command = [sys.executable, "-m", "corobot_drake", *self.args, "--serve", "--port", "0"]
        if self.file_limit is not None:  # the shell's ulimit, then the server in its place
            command = ["sh", "-c", f'ulimit -n {int(self.file_limit)} && exec "$@"', "sh",
                       *command]
        self.process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=stderr,
                                        text=True)
        line: list[str] = []
        reader = threading.Thread(target=lambda: line.append(self.process.stdout.readline()),
                                  daemon=True)
        reader.start()
        reader.join(self.startup_timeout)
        if not line or not line[0].startswith("serving "):
            self.__exit__(None, None, None)
            raise RuntimeError(f"the server did not start: {line[0] if line else 'timeout'}")
        self.url = line[0].split()[1]
        # Keep reading stdout (into `lines`) so the child never blocks on a full pipe.
        threading.Thread(target=lambda: self.lines.extend(self.process.stdout), daemon=True
                         ).start()
        return self

    def printed_token(self, timeout: float = 10.0) -> str | None:
        """The token the server printed (`  token <token> ...`; None if it printed none
        within `timeout` s of its start)."""
        import time

        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for text in list(self.lines):
                if text.startswith("  token "):
                    return text.split()[1]
            if any(text.startswith("  dashboard") for text in self.lines) and not any(
                    "#token=" in text for text in self.lines):
                return None
            time.sleep(0.05)
        return None

    def __exit__(self, *exc) -> None:
        import signal
        import subprocess

        if self.process is None or self.process.poll() is not None:
            return
        self.process.send_signal(signal.SIGINT)
        try:
            self.process.wait(15)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(5)
