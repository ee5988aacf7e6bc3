"""The pipe between the simulation process and the HTTP process (`serve` says why two).

- `SimSide` (simulation process): receives calls and watches from the pipe, hands them to the
  `SimRunner`, and sends back their results and each new snapshot (the latest only, never
  queued up), with the runner's robots when they changed (a robot spawned or deleted). The
  simulation thread never blocks on the pipe: a sender thread does the pickling and writing,
  a receiver thread the reading.
- `RemoteRunner` (HTTP process): the `runner.Runner` protocol over the pipe; its receiver
  thread resolves the futures and replaces the snapshot (and the robots).

Messages: ("hello", {...}) once, then HTTP -> simulation ("call" | "watch", id, fn),
("cancel", id), ("stop",); simulation -> HTTP ("result", id, ok, value or exception),
("snapshot", snapshot, stats), ("robots", robots, snapshot, stats): the robot set changed,
and this snapshot is the first of it.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import itertools
import os
import pickle
import socket
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any, TypeVar

from corobot_drake.serving.runner import SimRunner, SimulationStoppedError
from corobot_drake.serving.snapshots import RobotInfo

T = TypeVar("T")


def _picklable(exc: BaseException) -> BaseException:
    try:
        pickle.dumps(exc)
    except Exception:
        return RuntimeError(f"{type(exc).__name__}: {exc}")
    return exc


class SimSide:
    """The simulation process's end of the pipe (see the module docstring)."""

    def __init__(self, runner: SimRunner, conn):
        self.runner = runner
        self.conn = conn
        self._cond = threading.Condition()
        self._messages: deque = deque()
        self._snapshot: dict | None = None
        self._robots = runner.robots
        """The runner's robots as they were when `_snapshot` was published."""
        self._watches: dict[int, concurrent.futures.Future] = {}
        self._sending = False
        """A batch taken from `_messages` is being written to the pipe."""
        self.closed = threading.Event()
        self._robots_sent = runner.robots
        """The robots the HTTP side knows (the simulation thread replaces the runner's dict
        whole when they change, so identity tells)."""
        runner.on_publish.append(self._on_snapshot)
        self._post(("hello", {"robots": self._robots_sent, "snapshot": runner.snapshot,
                              "stats": runner.stats(), "meshcat_url": runner.meshcat_url}))
        threading.Thread(target=self._send_loop, name="bridge-send", daemon=True).start()
        threading.Thread(target=self._receive_loop, name="bridge-receive", daemon=True).start()

    def _post(self, message) -> None:
        with self._cond:
            self._messages.append(message)
            self._cond.notify()

    def _on_snapshot(self, snapshot: dict) -> None:
        with self._cond:  # (the simulation thread: the robots are those of the snapshot)
            self._snapshot, self._robots = snapshot, self.runner.robots
            self._cond.notify()

    def _next_batch(self) -> tuple[list, dict | None, dict] | None:
        """The messages, the snapshot and its robots to send, once there are any; None once
        closed."""
        with self._cond:
            while not self._messages and self._snapshot is None:
                self._cond.wait(0.5)
                if self.closed.is_set():
                    return None
            messages = list(self._messages)
            self._messages.clear()
            snapshot, robots, self._snapshot = self._snapshot, self._robots, None
            self._sending = True
        return messages, snapshot, robots

    def _send_loop(self) -> None:
        try:
            while not self.closed.is_set():
                batch = self._next_batch()
                if batch is None:
                    return
                messages, snapshot, robots = batch
                for message in messages:
                    self.conn.send(message)
                if snapshot is not None and robots is not self._robots_sent:
                    self.conn.send(("robots", robots, snapshot, self.runner.stats()))
                    self._robots_sent = robots
                elif snapshot is not None:
                    self.conn.send(("snapshot", snapshot, self.runner.stats()))
                with self._cond:
                    self._sending = False
                    self._cond.notify_all()
        except (OSError, EOFError, BrokenPipeError):
            self.closed.set()

    def close(self, timeout: float = 2.0) -> None:
        """Sends what is queued (e.g. the 503s of requests the stopped simulation failed),
        waiting up to `timeout` s, then closes the pipe: the HTTP process then stops."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while ((self._messages or self._sending) and not self.closed.is_set()
                   and time.monotonic() < deadline):
                self._cond.wait(0.05)
        self.closed.set()
        with contextlib.suppress(OSError):
            # A plain close leaves the socket open while the receiver thread is blocked
            # reading it, and the HTTP process would see no end until it was terminated.
            with socket.socket(fileno=os.dup(self.conn.fileno())) as end:
                end.shutdown(socket.SHUT_RDWR)
            self.conn.close()

    def _receive_loop(self) -> None:
        try:
            while True:
                kind, *args = self.conn.recv()
                if kind == "call":
                    self._reply_when_done(args[0], self.runner.submit(args[1]))
                elif kind == "watch":
                    self._watches[args[0]] = future = self.runner.watch(args[1])
                    self._reply_when_done(args[0], future)
                elif kind == "cancel":
                    future = self._watches.pop(args[0], None)
                    if future is not None:
                        future.cancel()
                elif kind == "stop":
                    break
        except (OSError, EOFError):
            pass
        finally:
            self.closed.set()

    def _reply_when_done(self, rid: int, future: concurrent.futures.Future) -> None:
        future.add_done_callback(lambda f: self._reply(rid, f))

    def _reply(self, rid: int, future: concurrent.futures.Future) -> None:
        self._watches.pop(rid, None)
        if future.cancelled():
            return
        exc = future.exception()
        if exc is not None:
            self._post(("result", rid, False, _picklable(exc)))
        else:
            self._post(("result", rid, True, future.result()))


class RemoteRunner:
    """The HTTP process's `runner.Runner`: the simulation process's runner over the pipe (see
    the module docstring)."""

    def __init__(self, conn, on_close: Callable[[], None] | None = None,
                 timeout: float = 600.0):
        """Waits (up to `timeout` s) for the simulation's hello. `on_close` is called (in the
        receiver thread) once the pipe closes."""
        self.conn = conn
        self._on_close = on_close
        if not conn.poll(timeout):
            raise TimeoutError("the simulation did not start")
        kind, hello = conn.recv()
        if kind != "hello":
            raise RuntimeError(f"expected the simulation's hello, got {kind!r}")
        self.robots: dict[str, RobotInfo] = hello["robots"]
        self.snapshot: dict = hello["snapshot"]
        self.meshcat_url: str | None = hello["meshcat_url"]
        self._stats: dict = hello["stats"]
        self._send_lock = threading.Lock()
        self._lock = threading.Lock()
        self._ids = itertools.count(1)
        self._pending: dict[int, concurrent.futures.Future] = {}
        self._open = True
        threading.Thread(target=self._receive_loop, name="bridge-receive", daemon=True).start()

    @property
    def alive(self) -> bool:
        return self._open

    def submit(self, fn: Callable[[Any], T]) -> concurrent.futures.Future[T]:
        return self._request("call", fn)

    def watch(self, fn: Callable[[Any], T | None]) -> concurrent.futures.Future[T]:
        return self._request("watch", fn)

    def stats(self) -> dict:
        return {**self._stats, "running": self._open and bool(self._stats.get("running"))}

    def _send(self, message) -> None:
        with self._send_lock:
            self.conn.send(message)

    def _request(self, kind: str, fn) -> concurrent.futures.Future:
        future: concurrent.futures.Future = concurrent.futures.Future()
        if not self._open:
            future.set_exception(SimulationStoppedError("the simulation is not running"))
            return future
        rid = next(self._ids)
        with self._lock:
            self._pending[rid] = future
        try:
            self._send((kind, rid, fn))
        except (OSError, pickle.PicklingError) as e:
            with self._lock:
                self._pending.pop(rid, None)
            future.set_exception(SimulationStoppedError(f"cannot reach the simulation: {e}"))
            return future
        if kind == "watch":
            future.add_done_callback(lambda f: self._cancelled(rid, f))
        return future

    def _cancelled(self, rid: int, future: concurrent.futures.Future) -> None:
        """Tells the simulation to stop a watch whose future was cancelled here."""
        if not future.cancelled():
            return
        with self._lock:
            self._pending.pop(rid, None)
        if self._open:
            with contextlib.suppress(OSError):
                self._send(("cancel", rid))

    def _receive_loop(self) -> None:
        try:
            while True:
                message = self.conn.recv()
                if message[0] == "snapshot":
                    self.snapshot, self._stats = message[1], message[2]
                elif message[0] == "robots":  # (`Backend` takes either half first)
                    self.snapshot, self._stats = message[2], message[3]
                    self.robots = message[1]
                elif message[0] == "result":
                    self._on_result(*message[1:])
        except (OSError, EOFError):
            pass
        finally:
            self._close()

    def _on_result(self, rid: int, ok: bool, value: Any) -> None:
        with self._lock:
            future = self._pending.pop(rid, None)
        if future is None or not future.set_running_or_notify_cancel():
            return
        if ok:
            future.set_result(value)
        else:
            future.set_exception(value)

    def _close(self) -> None:
        self._open = False
        with self._lock:
            pending, self._pending = self._pending, {}
        for future in pending.values():
            if future.set_running_or_notify_cancel():
                future.set_exception(SimulationStoppedError("the simulation stopped"))
        if self._on_close is not None:
            self._on_close()
