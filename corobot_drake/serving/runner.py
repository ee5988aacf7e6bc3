"""The simulation, run live: the `Runner` protocol the HTTP routes depend on, and `SimRunner`,
which owns the Drake Context in a thread of its own.

Threads: `SimRunner`'s thread builds the simulation, advances it in real time (x `rate`, or as
fast as it can), or holds it `paused` and takes the physics steps asked of it (`step`), and is
the only one that touches the Context. Other threads `submit()` a function, which the runner calls
between steps, or `watch()` one, which it calls after every step until it answers; results
come back in `concurrent.futures.Future`s. Every `snapshot_period` s of simulated time, and
after each submitted call, the runner publishes a `snapshot` (`snapshots.snapshot`, replaced
whole, never mutated), so readers get a consistent state without waiting for the simulation,
and the simulation never waits for them. `transport.RemoteRunner` is the same protocol in the
HTTP process.
"""

from __future__ import annotations

import concurrent.futures
import logging
import math
import queue
import threading
import time
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any, Protocol, TypeVar, runtime_checkable

from corobot_drake.serving.snapshots import RobotInfo, jsonable, snapshot

if TYPE_CHECKING:  # the HTTP process imports this module without Drake
    from corobot_drake.simulation import Simulation

log = logging.getLogger(__name__)

T = TypeVar("T")

BUILD_STOP_TIMEOUT = 60.0
"""s a simulation being built when Ctrl-C comes has to finish building before the runner
stops: a few seconds for the default scene."""


SIGNAL_WAIT = 0.1
"""s: the longest the main thread sleeps at once waiting on the simulation (`wait_for`), so
the longest a stop signal another thread took waits to be acted on."""


def wait_for[T](future: concurrent.futures.Future[T], timeout: float | None = None) -> T:
    """`future.result(timeout)`, waited for in slices of `SIGNAL_WAIT` s, for the main thread
    of a program that stops on a signal (`cli.ctrl_c_stops`). Python runs a signal's handler
    in the main thread only, when it next runs Python code; the kernel gives a signal sent to
    the process to any thread not blocking it (a thread that is starting one takes it, as
    rclpy's executor does for a goal's callback), and a main thread asleep on an untimed
    lock is not woken by that: Ctrl-C went unheard until the run ended."""
    deadline = None if timeout is None else time.monotonic() + timeout
    while not future.done():
        left = SIGNAL_WAIT if deadline is None else min(SIGNAL_WAIT, deadline - time.monotonic())
        if left <= 0:
            raise TimeoutError(f"no answer in {timeout:g} s")
        concurrent.futures.wait([future], left)
    return future.result()


def robot_infos(sim) -> dict[str, RobotInfo]:
    """Each of `sim`'s robots' `RobotInfo`, by name, in its scenario's order."""
    return {name: RobotInfo.of(r) for name, r in sim.robots.items()}


class SimulationStoppedError(RuntimeError):
    """A request the simulation will never answer: it has stopped (or was never reached).
    The routes answer it 503."""


@runtime_checkable
class Runner(Protocol):
    """A running simulation as the HTTP routes see it (`SimRunner` in process,
    `transport.RemoteRunner` across a pipe). Every member is safe to use from any thread."""

    @property
    def robots(self) -> Mapping[str, RobotInfo]:
        """Each robot's fixed services, by name, in the scenario's order: those of the
        simulation run now (a rebuilt one's robots may differ: a robot spawned or deleted);
        replaced whole, never mutated. A robot's state may lag it by one snapshot."""

    @property
    def snapshot(self) -> dict:
        """The latest published state (`snapshots.snapshot`); never mutated."""

    @property
    def alive(self) -> bool:
        """Whether the simulation still runs (and takes requests)."""

    @property
    def meshcat_url(self) -> str | None:
        """Meshcat's URL when the simulation has a Meshcat."""

    def submit(self, fn: Callable[[Simulation], T]) -> concurrent.futures.Future[T]:
        """Calls `fn(sim)` in the simulation thread between steps; the future gets its result
        or its exception."""

    def watch(self, fn: Callable[[Simulation], T | None]) -> concurrent.futures.Future[T]:
        """Calls `fn(sim)` now and after every step until it returns something other than
        None; the future gets that. Cancel the future to stop watching."""

    def stats(self) -> dict:
        """Simulated time, real-time factors, steps, slips, requests served, error (JSON)."""


def _resolve(future: concurrent.futures.Future, value: Any = None,
             error: BaseException | None = None) -> None:
    """Sets a future's result (or exception) unless it is done or cancelled meanwhile."""
    try:
        if error is not None:
            future.set_exception(error)
        else:
            future.set_result(value)
    except concurrent.futures.InvalidStateError:
        pass


MAX_RATE = math.inf
"""`rate`: as fast as the machine can (no wait between the loop's turns)."""


class StepJob:
    """Physics steps asked of a paused runner (`SimRunner.step`): `future` gets the number of
    steps taken once they are all taken, or fewer when `cancel()`ed; `progress(done, left)`,
    if given, is called in the simulation thread after each advance."""

    def __init__(self, steps: int, progress: Callable[[int, int], None] | None = None):
        self.steps = steps
        self.done = 0
        self.progress = progress
        self.future: concurrent.futures.Future[int] = concurrent.futures.Future()
        self.start: float | None = None
        """s: the simulated time the first step starts from."""
        self._cancelled = threading.Event()

    def cancel(self) -> None:
        """Stops after the advance under way (any thread)."""
        self._cancelled.set()

    @property
    def cancelled(self) -> bool:
        return self._cancelled.is_set()


class SimRunner:
    """Runs a simulation in real time (x `rate`; `MAX_RATE`: as fast as it can) in a thread of
    its own, or holds it `paused`; implements `Runner`. See the module docstring."""

    def __init__(self, sim, *, rate: float = 1.0, tick: float = 1.0 / 120.0,
                 max_step: float = 0.05, max_lag: float = 0.5,
                 snapshot_period: float = 1.0 / 30.0, paused: bool = False):
        """`sim`: a Simulation, or a function that builds one; `start()` then builds it in the
        simulation thread, so that everything bound to a thread (the renderer's OpenGL
        context) belongs to the thread that steps the simulation. `paused`: start paused."""
        self._factory = sim if callable(sim) else None
        self.sim = None if callable(sim) else sim
        self.rate = rate
        self._paused = paused
        self._jobs: list[StepJob] = []
        """Step requests, oldest first; the first is under way (simulation thread only)."""
        self._anchor = (math.nan, math.nan)
        """(wall-clock s, simulated s) the pacing counts from; NaN: from the next turn."""
        self.tick = tick
        self.max_step = max_step
        self.max_lag = max_lag
        """s of simulated time: when it falls further behind the clock than this (a slow
        machine), the runner stops trying to catch up and counts a `slip`."""
        self.snapshot_period = snapshot_period
        self.robots: dict[str, RobotInfo] = {}
        self.snapshot: dict = {}
        self.meshcat_url: str | None = None
        self.hooks: list[Callable[[Any], None]] = []
        """Called with the simulation between steps, in its thread (e.g. Meshcat teleop)."""
        self.rebuild: Callable[[Any], Any] | None = None
        """Builds a Simulation of a given scenario as this one was built (its Meshcat, its
        front ends' systems), for `replace`; None when the maker of the runner gives none."""
        self.on_publish: list[Callable[[dict], None]] = []
        """Called in the simulation thread with each new snapshot (the transport sends it)."""
        self.error: BaseException | None = None
        self.started_wall = math.nan
        self.started_sim = 0.0
        self.steps = 0
        self.slips = 0
        self.requests_served = 0
        self._inbox: queue.SimpleQueue = queue.SimpleQueue()
        self._watches: list[tuple[Callable, concurrent.futures.Future]] = []
        self._stop = threading.Event()
        self._ending = threading.RLock()  # (a future's callback may submit again)
        """Held to queue a request, and by the simulation thread's last drain: a request is
        either queued before that drain (and failed by it) or refused after it."""
        self._ready = threading.Event()
        self._thread: threading.Thread | None = None
        self._window: list[tuple[float, float]] = []

    # --- life cycle ---
    def start(self, timeout: float = 300.0) -> SimRunner:
        """Starts the simulation thread; returns once the simulation is built and its first
        snapshot published (re-raising what building it raised). A KeyboardInterrupt while
        it is built stops the runner once the build has ended (at most `BUILD_STOP_TIMEOUT`
        s: it cannot be cut short; the process must not end under it), then goes on."""
        self._thread = threading.Thread(target=self._main, name="corobot-sim", daemon=True)
        self._thread.start()
        deadline = time.monotonic() + timeout
        try:  # in slices (`wait_for`): a signal another thread took is acted on at once
            while not self._ready.wait(SIGNAL_WAIT) and time.monotonic() < deadline:
                pass
        except KeyboardInterrupt:
            self.stop(BUILD_STOP_TIMEOUT)
            raise
        if not self._ready.is_set():
            raise TimeoutError("the simulation was not built in time")
        if self.sim is None:
            raise self.error
        return self

    def stop(self, timeout: float = 5.0) -> None:
        """Stops the simulation thread and waits for it at most `timeout` s; a request
        queued or made after this fails with `SimulationStoppedError`."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)

    @property
    def alive(self) -> bool:
        """Whether the simulation thread runs (and takes requests)."""
        return self._thread is not None and self._thread.is_alive()

    # --- requests from other threads ---
    def submit(self, fn: Callable[[Any], T]) -> concurrent.futures.Future[T]:
        """Calls `fn(sim)` in the simulation thread between steps; the future gets its result
        or its exception (`SimulationStoppedError` once the runner has stopped)."""
        return self._put(fn, watch=False)

    def watch(self, fn: Callable[[Any], T | None]) -> concurrent.futures.Future[T]:
        """Calls `fn(sim)` now and after every step until it returns something other than
        None; the future gets that. Cancel the future to stop watching."""
        return self._put(fn, watch=True)

    @property
    def paused(self) -> bool:
        """Whether the simulation holds still (but for the steps asked of it)."""
        return self._paused

    def pause(self, paused: bool = True) -> None:
        """Pauses (or plays) from the loop's next turn; playing paces from where it is."""
        self._anchor = (math.nan, math.nan)
        self._paused = paused

    def step(self, job: StepJob) -> StepJob:
        """Queues `job` (taken once the runner is paused and the jobs before it are done)."""
        queued = self.submit(lambda sim: self._jobs.append(job))
        queued.add_done_callback(
            lambda f: f.exception() is not None and _resolve(job.future, error=f.exception()))
        return job

    def replace(self, sim) -> None:
        """In the simulation thread: runs `sim` from now on (built by `rebuild`); `robots`
        becomes its robots' when they differ (a robot spawned or deleted), then its first
        snapshot is published. The one it replaces is dropped here, in this thread."""
        self.sim = sim
        robots = robot_infos(sim)
        if list(robots.items()) != list(self.robots.items()):
            self.robots = robots  # (a new dict: the transport sees the change by identity)
        self._publish()

    def call(self, fn: Callable[[Any], T], timeout: float = 10.0) -> T:
        """`submit(fn)` and wait for its result."""
        return self.submit(fn).result(timeout)

    def _put(self, fn: Callable, watch: bool) -> concurrent.futures.Future:
        future: concurrent.futures.Future = concurrent.futures.Future()
        with self._ending:
            if self._stop.is_set() or (self._thread is not None and not self.alive):
                future.set_exception(SimulationStoppedError("the simulation is not running"))
            else:
                self._inbox.put((fn, future, watch))
        return future

    # --- measurements ---
    def stats(self) -> dict:
        """JSON: simulated `time` (s), `running`, `rate`, `wall_seconds` since the start,
        `realtime_factor` and `recent_realtime_factor` (simulated over wall s: since the
        start; over the last few hundred loop turns), `steps`, `slips`, `requests_served`,
        `error` (its repr, or None)."""
        elapsed = time.perf_counter() - self.started_wall if self.alive else math.nan
        sim_elapsed = self.snapshot.get("time", self.started_sim) - self.started_sim
        return jsonable({
            "time": self.snapshot.get("time"),
            "running": self.alive,
            "rate": self.rate,
            "wall_seconds": elapsed,
            "realtime_factor": sim_elapsed / elapsed if elapsed and elapsed > 0 else None,
            "recent_realtime_factor": self._recent_rate(),
            "steps": self.steps,
            "slips": self.slips,
            "requests_served": self.requests_served,
            "error": None if self.error is None else repr(self.error),
        })

    def _recent_rate(self) -> float:
        """Simulated over wall seconds across the last few hundred loop turns."""
        window = self._window
        if len(window) >= 2 and window[-1][0] > window[0][0]:
            return (window[-1][1] - window[0][1]) / (window[-1][0] - window[0][0])
        return math.nan

    # --- the simulation thread ---
    def _main(self) -> None:
        try:
            if self.sim is None:
                try:
                    self.sim = self._factory()
                except BaseException as e:
                    self.error = e
                    return
            self.robots = robot_infos(self.sim)
            self._publish()
            self._ready.set()
            self._loop()
        except BaseException as e:  # the runner must report, not vanish silently
            from corobot_drake.simulation import PhysicsError

            if isinstance(e, PhysicsError):  # a limit of the scenario's: one line says it
                log.error("simulation thread stopped: %s", e)
            else:
                log.exception("simulation thread stopped")
            self.error = e
        finally:
            self._ready.set()
            with self._ending:
                self._stop.set()
                self._fail_pending(SimulationStoppedError("the simulation stopped"))

    def _loop(self) -> None:
        clock = time.perf_counter
        self.started_wall = clock()
        self.started_sim = self.sim.time
        seen = (None, math.nan)  # (the simulation, its time) as the last turn left them
        next_snapshot = self.sim.time
        while not self._stop.is_set():
            self._drain()
            sim = self.sim  # (a request may have replaced it, or reset it)
            if seen != (sim, sim.time):  # a reset or a teleport in time: pace from here
                self._anchor = (math.nan, math.nan)
                next_snapshot = min(next_snapshot, sim.time)
                for job in self._jobs[:1]:  # a job under way counts its steps on from here
                    if job.start is not None:
                        job.start = sim.time - job.done * sim.physics_step
            for hook in self.hooks:
                hook(sim)
            now = clock()
            job = self._job(sim)
            stop = self._job_stop(sim, job) if job else self._paced_stop(sim, now)
            if stop > sim.time + 1e-9:
                sim.advance_to(stop)
                self.steps += 1
                self._check_watches()
            if job:
                self._job_advanced(sim, job)
            if sim.time >= next_snapshot - 1e-9:
                self._publish()
                next_snapshot = sim.time + self.snapshot_period
            seen = (sim, sim.time)
            self._window.append((clock(), sim.time))
            if len(self._window) > 240:
                del self._window[:40]
            if not (job or (self.rate == MAX_RATE and not self._paused)):
                self._idle(self.tick - (clock() - now))

    def _paced_stop(self, sim, now: float) -> float:
        """Where this turn stops when no steps are asked: here when paused; else where the
        clock (x `rate`) is, at most `max_step` on."""
        if self._paused:
            return sim.time
        if self.rate == MAX_RATE:
            return sim.stop_time(sim.time + self.max_step)
        wall0, t0 = self._anchor
        if math.isnan(wall0):
            wall0, t0 = self._anchor = (now, sim.time)
        target = t0 + self.rate * (now - wall0)
        if target - sim.time > self.max_lag:
            self.slips += 1
            self._anchor = (now, sim.time)
            target = sim.time
        return sim.stop_time(min(target, sim.time + self.max_step))

    def _job(self, sim) -> StepJob | None:
        """The step job to work on this turn (paused only), those cancelled answered (also
        while playing: a cancel is answered at once)."""
        while self._jobs:
            job = self._jobs[0]
            if not (job.cancelled or job.future.cancelled() or job.done >= job.steps):
                if not self._paused:
                    return None
                if job.start is None:
                    job.start = sim.time
                return job
            self._jobs.pop(0)
            _resolve(job.future, job.done)
        return None

    def _job_stop(self, sim, job: StepJob) -> float:
        """The next stop of `job`: one physics step for a job that reports its progress,
        else as many as fit in `max_step` (at least one), each ending on the physics' grid
        from where the job started."""
        h = sim.physics_step
        most = 1 if job.progress is not None else max(1, int(self.max_step / h + 1e-9))
        n = min(job.steps - job.done, most)
        return sim.on_step(job.start + (job.done + n) * h)

    def _job_advanced(self, sim, job: StepJob) -> None:
        h = sim.physics_step
        job.done = min(job.steps, round((sim.time - job.start) / h))
        if job.progress is not None:
            job.progress(job.done, job.steps - job.done)
        if job.done >= job.steps:
            self._jobs.pop(0)
            _resolve(job.future, job.done)

    def _idle(self, seconds: float) -> None:
        """Waits up to `seconds` for a request, and serves it."""
        if seconds > 0:
            try:
                item = self._inbox.get(timeout=seconds)
            except queue.Empty:
                return
            self._run(item)

    def _drain(self) -> None:
        while True:
            try:
                item = self._inbox.get_nowait()
            except queue.Empty:
                return
            self._run(item)

    def _run(self, item) -> None:
        fn, future, watch = item
        if watch:
            self._watches.append((fn, future))
            self._check_watches()
            return
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

    def _check_watches(self) -> None:
        if not self._watches:
            return
        remaining = []
        for fn, future in self._watches:
            if future.cancelled():
                continue
            try:
                result = fn(self.sim)
            except Exception as e:
                _resolve(future, error=e)
                continue
            if result is None:
                remaining.append((fn, future))
            else:
                _resolve(future, result)
        self._watches = remaining

    def _publish(self) -> None:
        self.snapshot = snapshot(self.sim)
        for callback in self.on_publish:
            callback(self.snapshot)

    def _fail_pending(self, error: Exception) -> None:
        while True:
            try:
                _, future, _ = self._inbox.get_nowait()
            except queue.Empty:
                break
            _resolve(future, error=error)
        jobs, self._jobs = self._jobs, []
        for job in jobs:
            _resolve(job.future, error=error)
        watches, self._watches = self._watches, []
        for _, future in watches:
            _resolve(future, error=error)
