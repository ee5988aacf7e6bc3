"""A client for the live services (`python -m corobot_drake --serve`) with the Python API's
method names, so one orchestration script drives the in-process simulation or a server (or,
one day, a real Corobot serving the same contracts):

    from corobot_drake.serving.client import CorobotClient

    sim = CorobotClient("http://127.0.0.1:50000")   # instead of Simulation.from_file(...)
    bot = sim.robot()
    result = bot.drive_distance(0.5, power=0.2)     # blocks until the command ends
    print(result.status, bot.pose(), bot.encoders())
    sim.advance(1.0)                                # waits 1 s of simulated time

Differences from the in-process API: the server runs in real time, so `advance()` waits
instead of stepping; `drive_state()` returns the contract's JSON (a dict); errors the server
reports come back as `CorobotError` (also a `ValueError` for bad input, a `KeyError` for an
unknown robot or service). Needs only httpx (and numpy/Pillow for `camera_image`), not Drake.
"""

from __future__ import annotations

import io
import math
import time
from typing import Any

import httpx

from corobot_drake.names import unknown_robot
from corobot_drake.readings import BodyPose, BodyVelocity, CommandResult, IrReading


class CorobotError(Exception):
    """The server refused a request: `status` (HTTP) and `detail` (its message)."""

    def __init__(self, status: int, detail: str):
        super().__init__(f"{status}: {detail}")
        self.status, self.detail = status, detail


class CorobotValueError(CorobotError, ValueError):
    """Bad input (HTTP 400/422)."""


class CorobotNotFoundError(CorobotError, KeyError):
    """No such robot, service or operation (HTTP 404)."""

    def __str__(self) -> str:  # KeyError would repr() the message
        return Exception.__str__(self)


class CorobotClient:
    """The server's simulation: the `Simulation` methods that make sense over HTTP."""

    def __init__(self, url: str = "http://127.0.0.1:50000", timeout: float = 30.0,
                 token: str | None = None):
        """`token`: the server's bearer token (needed off loopback; a URL the server printed,
        `.../dashboard#token=...`, carries it too). Every request carries it, and every POST
        a JSON body, as the server requires (docs/services.md, "Security")."""
        url, _, fragment = url.partition("#")
        if token is None and fragment.startswith("token="):
            token = fragment.removeprefix("token=")
        self.url = url.rstrip("/").removesuffix("/dashboard")
        headers = {"Authorization": f"Bearer {token}"} if token else {}
        self._http = httpx.Client(base_url=self.url, timeout=timeout, headers=headers)
        self._robots: dict[str, RemoteRobot] = {}
        self._ask_robots()  # (now: a wrong URL fails here)

    @property
    def robots(self) -> dict[str, RemoteRobot]:
        """The server's robots by name, as it has them now: each use asks it (a robot spawned
        or deleted while it serves comes or goes; a robot kept keeps its `RemoteRobot`)."""
        return self._ask_robots()

    def _ask_robots(self) -> dict[str, RemoteRobot]:
        names = self._get("/robots")["robots"]
        self._robots = {name: self._robots.get(name) or RemoteRobot(self, name)
                        for name in names}
        return dict(self._robots)

    # --- plumbing ---
    def _check(self, response: httpx.Response) -> Any:
        if response.status_code >= 400:
            try:
                detail = response.json().get("detail", response.text)
            except ValueError:
                detail = response.text
            cls = (CorobotValueError if response.status_code in (400, 422) else
                   CorobotNotFoundError if response.status_code == 404 else CorobotError)
            raise cls(response.status_code, str(detail))
        return response

    def _get(self, path: str, **params) -> Any:
        return self._check(self._http.get(path, params=params or None)).json()

    def _post(self, path: str, body: dict | None = None, timeout: float | None = None):
        kwargs = {} if timeout is None else {"timeout": timeout}
        return self._check(self._http.post(path, json=body or {}, **kwargs))

    def close(self) -> None:
        """Closes the client's HTTP connections (the server runs on); leaving a `with
        CorobotClient(...)` block closes them too."""
        self._http.close()

    def __enter__(self) -> CorobotClient:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # --- the Simulation's methods ---
    def robot(self, name: str | None = None) -> RemoteRobot:
        """The named robot; without a name, the only one."""
        robots = self.robots
        if name is None:
            if len(robots) != 1:
                raise ValueError(f"the server has {len(robots)} robots "
                                 f"({', '.join(robots)}): name one")
            return next(iter(robots.values()))
        try:
            return robots[name]
        except KeyError:
            raise KeyError(unknown_robot(name, robots)) from None

    @property
    def time(self) -> float:
        """Simulated time, s."""
        return float(self._get("/simulation")["time"])

    @property
    def realtime_factor(self) -> float:
        """Simulated seconds per wall-clock second since the server started simulating (its
        `/simulation`'s); NaN when it reports none (its simulation not running)."""
        value = self._get("/simulation")["realtime_factor"]
        return math.nan if value is None else float(value)

    def advance_to(self, t: float, poll: float = 0.02) -> None:
        """Waits until the server's simulated time reaches `t`."""
        while (now := self.time) < t:
            time.sleep(min(max(t - now, 0.0), 0.25) if poll is None else poll)

    def advance(self, seconds: float) -> None:
        """Waits `seconds` of simulated time (the server runs in real time)."""
        self.advance_to(self.time + seconds)

    def services(self) -> list[dict]:
        """The service directory's entries."""
        return self._get("/services")["services"]

    def summary(self) -> dict:
        """The run's figures as the server has them now: `time` (s), `realtime_factor`,
        `wall_seconds` (s), and each robot's `RemoteRobot.summary()` by name (a subset of
        `Simulation.summary`)."""
        stats = self._get("/simulation")
        return {
            "time": stats["time"],
            "realtime_factor": stats["realtime_factor"],
            "wall_seconds": stats["wall_seconds"],
            "robots": {name: robot.summary() for name, robot in self.robots.items()},
        }


class RemoteCommandHandle:
    """A command that completes, started without waiting (the API's `CommandHandle`)."""

    def __init__(self, client: CorobotClient, operation: dict):
        self._client = client
        self._op = operation
        self.seq = operation.get("seq")
        self.status_url = operation["status_url"]

    def __repr__(self) -> str:
        """What the server last said of the command (a repr asks it nothing), e.g.
        `<RemoteCommandHandle seq 3: drive_distance running, since t = 0.500 s, as last
        fetched>`."""
        return (f"<RemoteCommandHandle seq {self.seq}: {_result(self._op).describe()}, "
                f"as last fetched>")

    def result(self) -> CommandResult:
        """How the command has gone so far (asks the server again while it runs; an ended
        command's result is kept)."""
        if self._op["status"] == "running":
            self._op = self._client._get(self.status_url)
        return _result(self._op)

    def status(self) -> str:
        """`running`, `succeeded` or `failed` (the reason: `result().reason`)."""
        return self.result().status

    def done(self) -> bool:
        """Whether the command has ended (succeeded or failed)."""
        return self.result().end_time is not None

    def wait(self, timeout: float | None = 300.0, poll: float = 0.05) -> CommandResult:
        """Waits until the command ends; TimeoutError after `timeout` simulated seconds."""
        end = math.inf if timeout is None else self._client.time + timeout
        while not self.done():
            if self._client.time >= end:
                raise TimeoutError(f"{self._op['command']} still running after {timeout} s")
            time.sleep(poll)
        return self.result()


def _result(op: dict) -> CommandResult:
    return CommandResult(op.get("seq"), op["command"], op["status"], op.get("reason", ""),
                         op["start_time"], op.get("end_time"))


class RemoteRobot:
    """One robot on the server: the Python API's `Robot` methods over HTTP."""

    def __init__(self, client: CorobotClient, name: str):
        self._client = client
        self.name = name
        self._base = f"/robots/{name}"

    # --- commands ---
    def _command(self, command: str, body: dict | None = None) -> int | None:
        return self._client._post(f"{self._base}/drive/{command}", body).json().get("seq")

    def set_power(self, left: float, right: float) -> int | None:
        """Power per side in [-1, 1]."""
        return self._command("set_power", {"left": float(left), "right": float(right)})

    def set_speed(self, left: float, right: float) -> int | None:
        """Rim speed per side, m/s."""
        return self._command("set_speed", {"left": float(left), "right": float(right)})

    def set_velocity(self, linear: float, angular: float) -> int | None:
        """Chassis velocity: linear m/s forward, angular rad/s (positive: left)."""
        return self._command("set_velocity", {"linear": float(linear),
                                              "angular": float(angular)})

    def all_stop(self) -> int | None:
        """Commands both sides to zero speed (the drive slews down to it); returns its sequence
        number."""
        return self._command("all_stop")

    def enable(self, enabled: bool = True) -> int | None:
        """Enables (True) or disables (False) the drive; returns its sequence number."""
        return self._command("enable", {"enabled": bool(enabled)})

    def _start(self, command: str, body: dict) -> RemoteCommandHandle:
        op = self._client._post(f"{self._base}/drive/{command}", {**body, "wait": False}).json()
        return RemoteCommandHandle(self._client, op)

    def _run(self, command: str, body: dict, timeout: float | None) -> CommandResult:
        """Holds the request open while the command runs (the server answers 202 if it ends
        the wait first; then poll)."""
        wait = 600.0 if timeout is None else max(0.1, min(600.0, timeout))
        response = self._client._post(f"{self._base}/drive/{command}",
                                      {**body, "wait": True, "timeout": wait},
                                      timeout=wait + 30.0)
        op = response.json()
        if op["status"] != "running":
            return _result(op)
        return RemoteCommandHandle(self._client, op).wait(timeout)

    def drive_distance_async(self, distance: float, power: float = 0.5) -> RemoteCommandHandle:
        """Starts driving straight |distance| m (negative: backwards) at `power` in (0, 1];
        returns its handle at once."""
        return self._start("drive_distance", {"distance": float(distance), "power": float(power)})

    def drive_distance(self, distance: float, power: float = 0.5,
                       timeout: float | None = 300.0) -> CommandResult:
        """Drives straight |distance| m (negative: backwards); returns how it ended."""
        return self._run("drive_distance", {"distance": float(distance), "power": float(power)},
                         timeout)

    def rotate_degrees_async(self, degrees: float, power: float = 0.5) -> RemoteCommandHandle:
        """Starts turning in place by `degrees` (positive: counter-clockwise, left) at `power` in
        (0, 1]; returns its handle at once."""
        return self._start("rotate_degrees", {"degrees": float(degrees), "power": float(power)})

    def rotate_degrees(self, degrees: float, power: float = 0.5,
                       timeout: float | None = 300.0) -> CommandResult:
        """Turns in place (positive: left); returns how it ended."""
        return self._run("rotate_degrees", {"degrees": float(degrees), "power": float(power)},
                         timeout)

    def set_pose(self, x: float, y: float, yaw_deg: float = 0.0) -> RemoteCommandHandle:
        """Teleports the robot; the handle ends once it has settled."""
        return self._start("set_pose", {"x": float(x), "y": float(y), "yaw_deg": float(yaw_deg)})

    # --- measurements ---
    def drive_state(self) -> dict:
        """The drive contract's four-wheel state (JSON)."""
        return self._client._get(f"{self._base}/drive")

    def two_wheel(self) -> dict:
        """The drive contract's two-wheel view (JSON): the first left and first right wheel (the
        Corobot's front pair, the encoded ones) as `left` and `right`, the enable level, the
        track (m), position (m), heading (rad) and the latest command."""
        return self._client._get(f"{self._base}/drive/two_wheel")

    def pose(self) -> BodyPose:
        """The chassis frame's pose in the world frame: x, y, z (m), roll, pitch, yaw (rad), as
        `Robot.pose` (from the server's latest snapshot)."""
        return BodyPose(**self.drive_state()["pose"])

    def velocity(self) -> BodyVelocity:
        """The chassis' velocity in its heading frame: forward and lateral (+ left) m/s, yaw rate
        rad/s (+ left), as `Robot.velocity`."""
        return BodyVelocity(**self.drive_state()["velocity"])

    def axle_speeds(self) -> dict[str, float]:
        """Measured axle speeds, rad/s, by wheel name."""
        return {w: s["axle_speed"] for w, s in self.drive_state()["wheels"].items()}

    def encoders(self) -> dict[str, int]:
        """Encoder counts of the encoded wheels (the first left and right: the Corobot's front
        pair), by wheel name; `/encoders`' `ticks_per_revolution` a turn."""
        e = self._client._get(f"{self._base}/encoders")
        return {w: ticks for w, ticks in e.items()
                if w not in ("time_stamp", "ticks_per_revolution")}

    def heading(self) -> float:
        """Compass: the chassis' yaw about world z, rad in (-pi, pi]."""
        return float(self._client._get(f"{self._base}/compass")["heading"])

    def position(self) -> tuple[float, float, float]:
        """GPS: the chassis frame's origin in the world frame, (x, y, z) m."""
        g = self._client._get(f"{self._base}/gps")
        return (g["x"], g["y"], g["z"])

    def is_enabled(self) -> bool:
        """Whether the drive is enabled (as its controller has it)."""
        return bool(self.drive_state()["is_enabled"])

    def ir(self, name: str) -> IrReading:
        """The named IR sensor's latest scan (`front`, `rear`, ...)."""
        r = self._client._get(f"{self._base}/{name}_ir")
        return IrReading(r["raw"], r["range"], r["normalized"], r["time_stamp"])

    def ir_distances(self) -> dict[str, float]:
        """The latest raw reading of every IR sensor, m, by name ({} without any), as
        `Robot.ir_distances`."""
        snapshot = self._client._get(self._base)["state"]["ir"]
        return {name.removesuffix("_ir"): s["raw"] for name, s in snapshot.items()}

    def sensor_readings(self) -> dict[str, dict[str, dict]]:
        """Every sensor's latest reading as JSON, {kind field: {name: JSON}}, as
        `Robot.sensor_readings` gives it."""
        return self._client._get(f"{self._base}/sensors")

    def sensor_json(self, name: str, kind: str | None = None) -> dict:
        """The latest reading of the sensor `name` as JSON, as `Robot.sensor_json` gives it
        (`kind`, a kind's field, picks among sensors of several kinds sharing the name; without
        it, the first kind's in the registry's order, IR sensors first)."""
        if kind is None:  # the first kind's in the registry's order, as Robot.sensor_json
            kinds = [k for k, named in self.sensor_readings().items() if name in named]
            if not kinds:
                raise KeyError(f"robot {self.name!r} has no sensor {name!r}")
            kind = kinds[0]
        return self._client._get(f"{self._base}/sensors/{kind}/{name}")

    def camera_image(self, camera: str | None = None):
        """The latest frame of the camera `camera` (default: the front camera): numpy array
        height x width x 4 (RGBA), uint8."""
        import numpy as np
        from PIL import Image

        response = self._client._check(self._client._http.get(
            f"{self._camera_base(camera)}/frame.png"))
        self._last_frame_time = float(response.headers.get("x-frame-time", "nan"))
        return np.asarray(Image.open(io.BytesIO(response.content)).convert("RGBA"))

    def camera_image_time(self, camera: str | None = None) -> float:
        """Simulated time of the camera's latest frame (fetches the frame's header)."""
        response = self._client._check(self._client._http.get(
            f"{self._camera_base(camera)}/frame.jpg"))
        return float(response.headers.get("x-frame-time", "nan"))

    def _camera_base(self, camera: str | None) -> str:
        """The camera's routes: `/camera` for the front camera, `/cameras/<camera>`."""
        return f"{self._base}/camera" if camera is None else f"{self._base}/cameras/{camera}"

    def command_log(self) -> list[dict]:
        """The latest command (the server reports the current one)."""
        command = self.drive_state()["command"]
        return [] if command is None else [command]

    def summary(self) -> dict:
        """The robot's figures now, a subset of `Robot.summary`: `pose`, `velocity`, `wheels`
        (axle speeds, rad/s), `encoders` (ticks), `heading` (rad), `position` (m)."""
        state = self.drive_state()
        return {"pose": state["pose"], "velocity": state["velocity"],
                "wheels": {w: s["axle_speed"] for w, s in state["wheels"].items()},
                "encoders": {w: s["encoder_ticks"] for w, s in state["wheels"].items()
                             if s.get("encoder_ticks") is not None},
                "heading": state["heading"],
                "position": state["position"]}
