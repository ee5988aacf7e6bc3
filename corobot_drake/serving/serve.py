"""`python -m corobot_drake [SCENARIO] --serve`: the simulation in real time in one thread, the
HTTP services (`corobot_drake.serving.webapp`) beside it.

Meshcat starts too unless `--headless`; its teleop buttons keep working, polled by the
simulation thread. `--port 0` picks a free port; the first line printed to stdout is always
`serving http://HOST:PORT` once the server listens (tests and scripts read it).
"""

from __future__ import annotations

import sys

SWITCH_INTERVAL = 0.001
"""s. Python's GIL hand-over interval in the simulation process while serving. The
simulation's Python systems re-take the GIL many times a step; the bridge's threads are
mostly idle, but at the default 5 ms each of their wake-ups could hold the simulation up."""


def serve(make_sim, host: str = "127.0.0.1", port: int = 50000, meshcat: bool = False,
          log_level: str = "warning", label: str = "") -> int:
    """Builds the simulation (`make_sim(meshcat)`, in the simulation thread, with a Meshcat
    made there too when `meshcat`: Meshcat must be used from the thread that made it) and
    serves it until Ctrl-C. The HTTP server runs in a child process (`corobot_drake.serving.bridge`
    says why). Returns the exit status: 2 when the port or the simulation cannot be had."""
    import multiprocessing

    from corobot_drake.sensors.camera import RendererUnavailableError
    from corobot_drake.serving.bridge import SimSide, http_main
    from corobot_drake.serving.services import SimRunner

    ctx = multiprocessing.get_context("spawn")
    conn, child_conn = ctx.Pipe()
    url_box: list = []
    http = ctx.Process(target=http_main, name="corobot-http", daemon=True, args=(
        child_conn, host, port, log_level, HTTP_NICENESS))
    http.start()
    kind, value = conn.recv()
    if kind == "error":
        http.join(5)
        print(f"error: {value}", file=sys.stderr)
        return 2
    bound = value
    sys.setswitchinterval(SWITCH_INTERVAL)
    runner: SimRunner

    def build():
        viewer = None
        if meshcat:
            from pydrake.geometry import StartMeshcat

            viewer = StartMeshcat()
            url_box.append(viewer.web_url())
        sim = make_sim(viewer)
        if viewer is not None:
            from corobot_drake.serving.teleop import MeshcatTeleop

            teleop = MeshcatTeleop(viewer, sim)
            runner.hooks.append(lambda s: teleop.poll())
        return sim

    runner = SimRunner(build)
    try:
        runner.start()
    except (ValueError, RendererUnavailableError) as e:  # e.g. a non-finite number
        http.terminate()
        print(f"error: {label + ': ' if label else ''}{e}", file=sys.stderr)
        return 2
    meshcat_url = url_box[0] if url_box else None
    runner.meshcat_url = meshcat_url
    bridge = SimSide(runner, conn)
    shown = f"http://[{host}]:{bound}" if ":" in host else f"http://{host}:{bound}"
    print(f"serving {shown}", flush=True)
    print(f"  dashboard {shown}/dashboard  services {shown}/services  API {shown}/docs"
          + (f"  Meshcat {meshcat_url}" if meshcat_url else ""), flush=True)
    stats = runner.stats()
    try:
        while http.is_alive() and runner.alive and not bridge.closed.is_set():
            http.join(0.5)
            stats = runner.stats()
    except KeyboardInterrupt:
        pass
    finally:
        runner.stop()
        if http.is_alive():
            http.terminate()
            http.join(5)
    print(f"simulated {runner.sim.time:.2f} s at {stats['realtime_factor'] or 0:.2f}x real "
          f"time ({stats['slips']} slips)", file=sys.stderr)
    return 0 if runner.error is None else 1


HTTP_NICENESS = 10
"""The HTTP process's nice increment: under CPU contention the simulation comes first."""


SERVE_CAMERA_FPS = 10.0
"""Hz: the camera's render rate when serving, unless --camera-rate says otherwise. The
dashboard and the webcam page show a few frames a second; rendering 30 would cost a
third of the simulation's time budget."""


def serve_camera_rate(scenario, fps: float = SERVE_CAMERA_FPS) -> None:
    """Caps each robot's camera rate at `fps` (robots without a camera are left alone)."""
    for robot in scenario.robots.values():
        camera = getattr(robot, "camera", None)
        if camera is not None and getattr(camera, "fps", 0) > fps:
            camera.fps = fps


class ServerProcess:
    """`python -m corobot_drake ... --serve --port 0` in a child process, for tests and
    scripts: `with ServerProcess(["--headless"]) as server: server.url`."""

    def __init__(self, args: list[str] = (), startup_timeout: float = 120.0,
                 stderr_path: str | None = None):
        self.args = list(args)
        self.startup_timeout = startup_timeout
        self.stderr_path = stderr_path
        self.url: str | None = None
        self.process = None

    def __enter__(self) -> ServerProcess:
        import subprocess
        import threading

        stderr = open(self.stderr_path, "w") if self.stderr_path else subprocess.DEVNULL
        self.process = subprocess.Popen(
            [sys.executable, "-m", "corobot_drake", *self.args, "--serve", "--port", "0"],
            stdout=subprocess.PIPE, stderr=stderr, text=True)
        line: list[str] = []
        reader = threading.Thread(target=lambda: line.append(self.process.stdout.readline()),
                                  daemon=True)
        reader.start()
        reader.join(self.startup_timeout)
        if not line or not line[0].startswith("serving "):
            self.__exit__(None, None, None)
            raise RuntimeError(f"the server did not start: {line[0] if line else 'timeout'}")
        self.url = line[0].split()[1]
        # Keep draining stdout so the child never blocks on a full pipe.
        threading.Thread(target=self.process.stdout.read, daemon=True).start()
        return self

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
