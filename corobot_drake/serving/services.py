"""The live side of a simulation: a real-time runner thread that owns the Drake Context, and
the service contracts' state read from it.

`SimRunner` advances the simulation in real time in its own thread. Nothing else touches the
Context: other threads (the HTTP server) `submit()` a function, which the runner calls between
simulation steps and whose result comes back in a `concurrent.futures.Future`. After each step
the runner publishes a `snapshot` (plain dicts, replaced whole, never mutated), so readers get a
consistent state without waiting for the simulation, and the simulation never waits for them.

Commands that complete (drive_distance, rotate_degrees) are tracked as *operations*: the runner
checks each running one after every step and resolves its future when it ends.
"""

from __future__ import annotations

import concurrent.futures
import dataclasses as dc
import itertools
import logging
import math
import queue
import threading
import time
from collections.abc import Callable
from typing import Any

from corobot_drake.model import dimensions as dim

log = logging.getLogger(__name__)

# --- contracts ---------------------------------------------------------------------------

CONTRACT_DRIVE = "corobot-drake/drive/v1"
CONTRACT_ANALOG_SENSOR = "corobot-drake/analog_sensor/v1"
CONTRACT_ENCODERS = "corobot-drake/encoders/v1"
CONTRACT_COMPASS = "corobot-drake/compass/v1"
CONTRACT_GPS = "corobot-drake/gps/v1"
CONTRACT_WEBCAM = "corobot-drake/webcam/v1"



def _jsonable(value: Any) -> Any:
    """Dataclasses, numpy scalars/arrays and non-finite floats made JSON-safe."""
    if dc.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _jsonable(getattr(value, f.name)) for f in dc.fields(value)}
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, bool | int | str) or value is None:
        return value
    if hasattr(value, "tolist"):  # numpy
        return _jsonable(value.tolist())
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    try:
        f = float(value)
    except (TypeError, ValueError):
        return str(value)
    return f if math.isfinite(f) else None


def _get(obj: Any, *names: str, default: Any = None) -> Any:
    """The first of `names` that `obj` has (attribute or key)."""
    for name in names:
        if isinstance(obj, dict) and name in obj:
            return obj[name]
        if hasattr(obj, name):
            return getattr(obj, name)
    return default


def robot_capabilities(robot) -> dict[str, bool]:
    """Which optional parts of the Python API this robot has (they land in stages)."""
    return {
        "drive_distance": hasattr(robot, "drive_distance"),
        "rotate_degrees": hasattr(robot, "rotate_degrees"),
        "set_pose": hasattr(robot, "set_pose"),
        "drive_state": hasattr(robot, "drive_state"),
        "ir": hasattr(robot, "ir"),
        "camera": hasattr(robot, "camera_image") and bool(getattr(robot, "has_camera", True)),
    }


def drive_state(robot, sim) -> dict:
    """The drive contract's four-wheel state (MRDS DriveDifferentialFourWheelState in SI
    units): the Python API's `drive_state()` fields, plus pose, velocity and the command."""
    pose = robot.pose()
    velocity = robot.velocity()
    native = robot.drive_state()
    wheels = {name: {"commanded_power": float(w.commanded_power),
                     "axle_speed": float(w.axle_speed),
                     "encoder_ticks": w.encoder_ticks}
              for name, w in native.wheels.items()}
    x, y, z = native.position
    heading, enabled = float(native.heading), bool(native.is_enabled)
    scaling = float(native.power_scaling_factor)
    track = float(native.distance_between_wheels)
    log_ = robot.command_log()
    last = log_[-1] if log_ else None
    return _jsonable({
        "time_stamp": sim.time,
        "is_enabled": enabled,
        "power_scaling_factor": scaling,
        "distance_between_wheels": track,
        "wheel_radius": dim.WHEEL_RADIUS,
        "encoder_ticks_per_revolution": dim.ENCODER_TICKS_PER_REVOLUTION,
        "wheels": wheels,
        "position": {"x": x, "y": y, "z": z},
        "heading": heading,
        "heading_deg": math.degrees(heading),
        "pose": dc.asdict(pose),
        "velocity": dc.asdict(velocity),
        "command": None if last is None else {
            "seq": last.seq, "command": last.command, "status": last.status,
            "reason": last.reason, "start_time": last.start_time, "end_time": last.end_time},
    })


def two_wheel_view(state: dict) -> dict:
    """The generic differential-drive view: left = front left, right = front right."""
    w = state["wheels"]
    return {
        "time_stamp": state["time_stamp"],
        "is_enabled": state["is_enabled"],
        "distance_between_wheels": state["distance_between_wheels"],
        "left": w["front_left"],
        "right": w["front_right"],
        "position": state["position"],
        "heading": state["heading"],
        "command": state["command"],
    }


def ir_states(robot, sim) -> dict[str, dict]:
    """Analog-sensor state of each IR sensor, by service name (`front_ir`, `rear_ir`, ...):
    raw (m), range (m), normalized, time_stamp (s, the scan's time)."""
    sensors = getattr(robot._parts, "ir_sensors", None)
    if not sensors or not hasattr(robot, "ir"):
        return {}
    return {f"{name}_ir": _analog(robot.ir(name)) for name in sensors}


def _analog(reading) -> dict:
    raw = float(_get(reading, "raw", "distance"))
    range_ = float(_get(reading, "range", "maximum_range"))
    normalized = _get(reading, "normalized")
    normalized = float(normalized) if normalized is not None else raw / range_
    stamp = _get(reading, "time_stamp", "time", default=math.nan)
    return _jsonable({"raw": raw, "range": range_, "normalized": normalized,
                      "time_stamp": float(stamp)})


def robot_snapshot(robot, sim) -> dict:
    drive = drive_state(robot, sim)
    return {
        "drive": drive,
        "ir": ir_states(robot, sim),
        "encoders": {
            "time_stamp": drive["time_stamp"],
            "ticks_per_revolution": dim.ENCODER_TICKS_PER_REVOLUTION,
            "front_left": drive["wheels"]["front_left"]["encoder_ticks"],
            "front_right": drive["wheels"]["front_right"]["encoder_ticks"],
        },
        "compass": {"time_stamp": drive["time_stamp"], "heading": drive["heading"],
                    "heading_deg": drive["heading_deg"]},
        "gps": {"time_stamp": drive["time_stamp"], **drive["position"]},
    }


# --- calls the HTTP side sends (module-level, so they pickle) ---------------------------------


def call_robot(robot: str, method: str, args: tuple, sim) -> tuple[int | None, float]:
    """`sim.robot(robot).method(*args)`; returns (its sequence number if any, sim time)."""
    result = getattr(sim.robot(robot), method)(*args)
    return (result if isinstance(result, int) else None), sim.time


def grab_frame(robot: str, sim) -> tuple[float, float, Any]:
    """(sim time, frame time, RGB uint8 image h x w x 3) of the robot's latest camera frame;
    (sim time, NaN, None) before the first."""
    import numpy as np

    r = sim.robot(robot)
    image = r.camera_image()
    if image is None:  # before the first frame has come out of the camera
        return sim.time, math.nan, None
    image = np.asarray(image)
    if image.ndim == 3 and image.shape[2] == 4:
        image = image[:, :, :3]
    stamp = getattr(r, "camera_image_time", None)
    return sim.time, (float(stamp()) if stamp is not None else sim.time), \
        np.ascontiguousarray(image, dtype=np.uint8)


def start_command(command: str, arguments: dict, robot):
    """Starts a command that completes without waiting; returns the API's handle."""
    if command == "set_pose":
        return robot.set_pose(**arguments)
    return getattr(robot, f"{command}_async")(**arguments)


# --- operations (commands that complete) -------------------------------------------------


@dc.dataclass
class Operation:
    """A command that completes, as the HTTP contract reports it."""

    id: int
    robot: str
    command: str
    arguments: dict
    seq: int | None = None
    status: str = "running"
    """running, succeeded or failed."""
    reason: str = ""
    start_time: float = math.nan
    end_time: float | None = None
    handle: Any = dc.field(default=None, repr=False)
    futures: list = dc.field(default_factory=list, repr=False)

    def public(self) -> dict:
        return _jsonable({
            "id": self.id, "robot": self.robot, "command": self.command,
            "arguments": self.arguments, "seq": self.seq, "status": self.status,
            "reason": self.reason, "start_time": self.start_time, "end_time": self.end_time,
        })


def _handle_status(handle) -> tuple[str, str, float | None] | None:
    """(status, reason, end_time) of an async command handle from the Python API once the
    command has ended; None while it runs or when the handle cannot tell."""
    result = getattr(handle, "result", None)
    if not callable(result):
        return None
    r = result()
    if r.end_time is None:
        return None
    return str(r.status), str(r.reason or ""), float(r.end_time)


# --- the runner ---------------------------------------------------------------------------


class SimRunner:
    """Runs `sim` in real time (x `rate`) in a thread of its own; see the module docstring."""

    def __init__(self, sim, *, rate: float = 1.0, tick: float = 1.0 / 120.0,
                 max_step: float = 0.05, max_lag: float = 0.5,
                 snapshot_period: float = 1.0 / 30.0):
        """`sim`: a Simulation, or a function that builds one; `start()` then builds it in the
        simulation thread, so that everything bound to a thread (the renderer's OpenGL
        context) belongs to the thread that steps the simulation."""
        self._factory = sim if callable(sim) else None
        self.sim = None if callable(sim) else sim
        self.rate = rate
        self.tick = tick
        self.max_step = max_step
        self.max_lag = max_lag
        """s of simulated time: when it falls further behind the clock than this (a slow
        machine), the runner stops trying to catch up and counts a `slip`."""
        self.snapshot_period = snapshot_period
        self._inbox: queue.SimpleQueue = queue.SimpleQueue()
        self._stop = threading.Event()
        self._ready = threading.Event()
        self._thread: threading.Thread | None = None
        self._ops: dict[int, Operation] = {}
        self._ops_lock = threading.Lock()
        self.on_operation_end: list[Callable[[Operation], None]] = []
        self.on_publish: list[Callable[[dict], None]] = []
        """Called in the sim thread with each new snapshot (the process bridge sends it)."""
        self._running_ops: list[Operation] = []
        self._op_ids = itertools.count(1)
        self.snapshot: dict = {}
        self.error: BaseException | None = None
        self.started_wall = math.nan
        self.started_sim = 0.0
        self.steps = 0
        self.slips = 0
        self.requests_served = 0
        self._window: list[tuple[float, float]] = []
        self.hooks: list[Callable[[Any], None]] = []
        """Called with the simulation between steps, in its thread (e.g. Meshcat teleop)."""
        self.capabilities: dict[str, dict[str, bool]] = {}
        self.meshcat_url: str | None = None

    # --- life cycle ---
    def start(self, timeout: float = 300.0) -> SimRunner:
        """Starts the simulation thread; returns once the simulation is built and its first
        snapshot published (re-raising what building it raised)."""
        self._thread = threading.Thread(target=self._main, name="corobot-sim", daemon=True)
        self._thread.start()
        if not self._ready.wait(timeout):
            raise TimeoutError("the simulation was not built in time")
        if self.sim is None:
            raise self.error
        return self

    def stop(self, timeout: float = 5.0) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)

    @property
    def robot_names(self) -> list[str]:
        return list(self.capabilities)

    @property
    def alive(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    # --- requests from other threads ---
    def submit(self, fn: Callable[[Any], Any]) -> concurrent.futures.Future:
        """Calls `fn(sim)` in the simulation thread between steps; its result comes back in
        the returned future (or its exception)."""
        future: concurrent.futures.Future = concurrent.futures.Future()
        if self._stop.is_set() or (self._thread is not None and not self.alive):
            future.set_exception(RuntimeError("the simulation is not running"))
            return future
        self._inbox.put((fn, future))
        return future

    def call(self, fn: Callable[[Any], Any], timeout: float = 10.0) -> Any:
        return self.submit(fn).result(timeout)

    def start_operation(self, robot: str, command: str,
                        arguments: dict) -> concurrent.futures.Future:
        """Starts a command that completes (`start_command` in the sim thread). The returned
        future resolves to the `Operation` once it is registered; `operation_done(op.id)`
        gives a future that resolves to it once it has ended."""

        def start(sim):
            op = Operation(next(self._op_ids), robot, command, arguments, start_time=sim.time)
            handle = start_command(command, arguments, sim.robot(robot))
            if isinstance(handle, int):
                op.seq = handle
            else:
                op.handle = handle
                seq = _get(handle, "seq")
                op.seq = seq if isinstance(seq, int) else None
            self._ops[op.id] = op
            self._running_ops.append(op)
            self._check_op(op, sim)
            return op

        return self.submit(start)

    def operation(self, op_id: int) -> Operation | None:
        return self._ops.get(op_id)

    def operation_done(self, op_id: int) -> concurrent.futures.Future:
        """A future that resolves to operation `op_id` once it has ended."""
        future: concurrent.futures.Future = concurrent.futures.Future()
        with self._ops_lock:
            op = self._ops.get(op_id)
            if op is None:
                future.set_exception(KeyError(f"no operation {op_id}"))
            elif op.status != "running":
                future.set_result(op)
            else:
                op.futures.append(future)
        return future

    # --- measurements ---
    def stats(self) -> dict:
        wall = time.perf_counter()
        elapsed = wall - self.started_wall if self.alive else math.nan
        sim_elapsed = self.snapshot.get("time", self.started_sim) - self.started_sim
        window = self._window
        recent = math.nan
        if len(window) >= 2 and window[-1][0] > window[0][0]:
            recent = (window[-1][1] - window[0][1]) / (window[-1][0] - window[0][0])
        return _jsonable({
            "time": self.snapshot.get("time"),
            "running": self.alive,
            "rate": self.rate,
            "wall_seconds": elapsed,
            "realtime_factor": sim_elapsed / elapsed if elapsed and elapsed > 0 else None,
            "recent_realtime_factor": recent,
            "steps": self.steps,
            "slips": self.slips,
            "requests_served": self.requests_served,
            "error": None if self.error is None else repr(self.error),
        })

    # --- the simulation thread ---
    def _main(self) -> None:
        try:
            if self.sim is None:
                try:
                    self.sim = self._factory()
                except BaseException as e:
                    self.error = e
                    return
            self.capabilities = {name: robot_capabilities(r)
                                 for name, r in self.sim.robots.items()}
            self._publish()
            self._ready.set()
            self._loop()
        except BaseException as e:  # the runner must report, not vanish silently
            log.exception("simulation thread stopped")
            self.error = e
        finally:
            self._ready.set()
            self._stop.set()
            self._fail_pending(RuntimeError("the simulation stopped"))

    def _loop(self) -> None:
        sim = self.sim
        clock = time.perf_counter
        self.started_wall = wall0 = clock()
        self.started_sim = t0 = sim.time
        next_snapshot = sim.time
        while not self._stop.is_set():
            self._drain()
            for hook in self.hooks:
                hook(sim)
            now = clock()
            target = t0 + self.rate * (now - wall0)
            if target - sim.time > self.max_lag:
                self.slips += 1
                wall0, t0 = now, sim.time
                target = sim.time
            if target > sim.time + 1e-9:
                sim.advance_to(min(target, sim.time + self.max_step))
                self.steps += 1
                self._check_ops(sim)
            if sim.time >= next_snapshot - 1e-9:
                self._publish()
                next_snapshot = sim.time + self.snapshot_period
            self._window.append((clock(), sim.time))
            if len(self._window) > 240:
                del self._window[:40]
            wait = self.tick - (clock() - now)
            if wait > 0:
                try:
                    item = self._inbox.get(timeout=wait)
                except queue.Empty:
                    continue
                self._run(item)

    def _drain(self) -> None:
        while True:
            try:
                item = self._inbox.get_nowait()
            except queue.Empty:
                return
            self._run(item)

    def _run(self, item) -> None:
        fn, future = item
        if not future.set_running_or_notify_cancel():
            return
        try:
            result = fn(self.sim)
        except Exception as e:  # reported to the caller; the simulation goes on
            future.set_exception(e)
        else:
            future.set_result(result)
            self._publish()
        self.requests_served += 1

    def _publish(self) -> None:
        sim = self.sim
        self.snapshot = {
            "time": sim.time,
            "robots": {name: robot_snapshot(robot, sim) for name, robot in sim.robots.items()},
        }
        for callback in self.on_publish:
            callback(self.snapshot)

    def _check_ops(self, sim) -> None:
        if not self._running_ops:
            return
        for op in list(self._running_ops):
            self._check_op(op, sim)

    def _check_op(self, op: Operation, sim) -> None:
        status = None
        if op.handle is not None:
            status = _handle_status(op.handle)
        if status is None and op.seq is not None:
            for record in reversed(sim.robot(op.robot).command_log()):
                if record.seq == op.seq:
                    if record.end_time is not None:
                        status = (record.status, record.reason, record.end_time)
                    break
        if status is None or status[0] in ("running", "pending", "active"):
            return
        with self._ops_lock:
            op.status, op.reason = status[0], status[1]
            op.end_time = status[2] if status[2] is not None else sim.time
            futures, op.futures = op.futures, []
        self._running_ops.remove(op)
        for future in futures:
            if not future.done():
                future.set_result(op)
        for callback in self.on_operation_end:
            callback(op)

    def _fail_pending(self, error: Exception) -> None:
        while True:
            try:
                _, future = self._inbox.get_nowait()
            except queue.Empty:
                break
            if not future.done():
                future.set_exception(error)
        for op in self._running_ops:
            with self._ops_lock:
                op.status, op.reason = "failed", str(error)
                futures, op.futures = op.futures, []
            for future in futures:
                if not future.done():
                    future.set_result(op)
