"""The HTTP server in a process of its own, joined to the simulation by a pipe.

Why a second process: the simulation's Python systems give up and re-take Python's GIL many
times per step, so in one process a busy HTTP thread makes the simulation wait at every one
of those hand-overs (measured: 20 polling clients and a flood of bad requests cut the
real-time factor from 1.0 to 0.7). With the server in its own process the simulation thread
shares its GIL with nothing busy, and the HTTP process runs at a lower priority (nice), so under
load the pages slow down, not the simulation.

- `SimSide` (simulation process): receives calls from the pipe, submits them to the
  `SimRunner`'s queue, and sends back their results, each new snapshot (latest only, never
  queued up) and each operation's end. The simulation thread never blocks on the pipe: a
  sender thread does the pickling and writing.
- `RemoteRunner` (HTTP process): what `webapp.create_app` needs of a runner (`snapshot`,
  `submit`, `start_operation`, `operation`, `operation_done`, `stats`, `capabilities`),
  over the pipe.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import itertools
import logging
import pickle
import threading
from collections import deque
from typing import Any

from corobot_drake.serving.services import Operation, SimRunner

log = logging.getLogger(__name__)


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
        self.closed = threading.Event()
        runner.on_publish.append(self._on_snapshot)
        runner.on_operation_end.append(
            lambda op: self._post(("op", op.public())))
        self._post(("hello", {"capabilities": runner.capabilities,
                              "snapshot": runner.snapshot, "stats": runner.stats(),
                              "meshcat_url": getattr(runner, "meshcat_url", None)}))
        threading.Thread(target=self._send_loop, name="bridge-send", daemon=True).start()
        threading.Thread(target=self._receive_loop, name="bridge-receive", daemon=True).start()

    def _post(self, message) -> None:
        with self._cond:
            self._messages.append(message)
            self._cond.notify()

    def _on_snapshot(self, snapshot: dict) -> None:
        with self._cond:
            self._snapshot = snapshot
            self._cond.notify()

    def _send_loop(self) -> None:
        try:
            while not self.closed.is_set():
                with self._cond:
                    while not self._messages and self._snapshot is None:
                        self._cond.wait(0.5)
                        if self.closed.is_set():
                            return
                    messages = list(self._messages)
                    self._messages.clear()
                    snapshot, self._snapshot = self._snapshot, None
                for message in messages:
                    self.conn.send(message)
                if snapshot is not None:
                    self.conn.send(("snapshot", snapshot, self.runner.stats()))
        except (OSError, EOFError, BrokenPipeError):
            self.closed.set()

    def _receive_loop(self) -> None:
        try:
            while True:
                message = self.conn.recv()
                kind = message[0]
                if kind == "call":
                    _, rid, fn = message
                    self.runner.submit(fn).add_done_callback(
                        lambda f, rid=rid: self._reply(rid, f))
                elif kind == "start_op":
                    _, rid, robot, command, arguments = message
                    self.runner.start_operation(robot, command, arguments).add_done_callback(
                        lambda f, rid=rid: self._reply(rid, f))
                elif kind == "stop":
                    break
        except (OSError, EOFError):
            pass
        finally:
            self.closed.set()

    def _reply(self, rid: int, future: concurrent.futures.Future) -> None:
        exc = future.exception()
        if exc is not None:
            self._post(("result", rid, False, _picklable(exc)))
            return
        value = future.result()
        if isinstance(value, Operation):
            value = ("operation", value.public())
        self._post(("result", rid, True, value))


def _operation(public: dict) -> Operation:
    return Operation(**{k: v for k, v in public.items()})


class RemoteRunner:
    """The HTTP process's view of the runner (see the module docstring)."""

    def __init__(self, conn, on_close=None, timeout: float = 600.0):
        self.conn = conn
        self._on_close = on_close
        if not conn.poll(timeout):
            raise TimeoutError("the simulation did not start")
        kind, hello = conn.recv()
        assert kind == "hello", kind
        self.capabilities: dict[str, dict[str, bool]] = hello["capabilities"]
        self.snapshot: dict = hello["snapshot"]
        self._stats: dict = hello["stats"]
        self.meshcat_url: str | None = hello.get("meshcat_url")
        self._send_lock = threading.Lock()
        self._lock = threading.Lock()
        self._ids = itertools.count(1)
        self._pending: dict[int, tuple[concurrent.futures.Future, bool]] = {}
        self._ops: dict[int, Operation] = {}
        self._op_waiters: dict[int, list[concurrent.futures.Future]] = {}
        self._open = True
        threading.Thread(target=self._receive_loop, name="bridge-receive", daemon=True).start()

    @property
    def robot_names(self) -> list[str]:
        return list(self.capabilities)

    @property
    def alive(self) -> bool:
        return self._open

    def _send(self, message) -> None:
        with self._send_lock:
            self.conn.send(message)

    def _request(self, message_fn, is_op: bool = False) -> concurrent.futures.Future:
        future: concurrent.futures.Future = concurrent.futures.Future()
        if not self._open:
            future.set_exception(RuntimeError("the simulation is not running"))
            return future
        rid = next(self._ids)
        with self._lock:
            self._pending[rid] = (future, is_op)
        try:
            self._send(message_fn(rid))
        except (OSError, pickle.PicklingError) as e:
            with self._lock:
                self._pending.pop(rid, None)
            future.set_exception(RuntimeError(f"cannot reach the simulation: {e}"))
        return future

    def submit(self, fn) -> concurrent.futures.Future:
        return self._request(lambda rid: ("call", rid, fn))

    def start_operation(self, robot: str, command: str,
                        arguments: dict) -> concurrent.futures.Future:
        return self._request(lambda rid: ("start_op", rid, robot, command, arguments), True)

    def operation(self, op_id: int) -> Operation | None:
        return self._ops.get(op_id)

    def operation_done(self, op_id: int) -> concurrent.futures.Future:
        future: concurrent.futures.Future = concurrent.futures.Future()
        with self._lock:
            op = self._ops.get(op_id)
            if op is None:
                future.set_exception(KeyError(f"no operation {op_id}"))
            elif op.status != "running":
                future.set_result(op)
            else:
                self._op_waiters.setdefault(op_id, []).append(future)
        return future

    def stats(self) -> dict:
        return {**self._stats, "running": self._open and bool(self._stats.get("running"))}

    def _receive_loop(self) -> None:
        try:
            while True:
                message = self.conn.recv()
                kind = message[0]
                if kind == "snapshot":
                    self.snapshot, self._stats = message[1], message[2]
                elif kind == "result":
                    self._on_result(*message[1:])
                elif kind == "op":
                    self._on_op(_operation(message[1]))
        except (OSError, EOFError):
            pass
        finally:
            self._open = False
            with self._lock:
                pending, self._pending = self._pending, {}
                waiters, self._op_waiters = self._op_waiters, {}
            for future, _ in pending.values():
                if not future.done():
                    future.set_exception(RuntimeError("the simulation stopped"))
            for op_id, futures in waiters.items():
                op = self._ops[op_id]
                op.status, op.reason = "failed", "the simulation stopped"
                for f in futures:
                    f.set_result(op)
            if self._on_close is not None:
                self._on_close()

    def _on_result(self, rid: int, ok: bool, value: Any) -> None:
        with self._lock:
            future, is_op = self._pending.pop(rid, (None, False))
            if ok and is_op:
                op = _operation(value[1])
                known = self._ops.get(op.id)
                if known is not None and known.status != "running":
                    op = known  # its end overtook its start
                self._ops[op.id] = op
                value = op
        if future is None:
            return
        if ok:
            future.set_result(value)
        else:
            future.set_exception(value)

    def _on_op(self, op: Operation) -> None:
        with self._lock:
            self._ops[op.id] = op
            waiters = self._op_waiters.pop(op.id, [])
        for f in waiters:
            f.set_result(op)


def http_main(conn, host: str, port: int, log_level: str, niceness: int) -> None:
    """The HTTP process: listen, report the port, wait for the simulation, serve."""
    import os
    import socket

    import uvicorn

    from corobot_drake.serving.webapp import create_app

    if niceness:
        with contextlib.suppress(OSError):
            os.nice(niceness)
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
        sock.listen(2048)
    except OSError as e:
        conn.send(("error", f"cannot listen on {host}:{port}: {e.strerror}"))
        return
    conn.send(("listening", sock.getsockname()[1]))
    server_box: list = []

    def closed() -> None:  # the simulation process went away: stop serving
        if server_box:
            server_box[0].should_exit = True

    try:
        runner = RemoteRunner(conn, on_close=closed)
    except (TimeoutError, EOFError, OSError):
        return
    app = create_app(runner, meshcat_url=runner.meshcat_url)
    config = uvicorn.Config(app, log_level=log_level, access_log=False, lifespan="off",
                            timeout_graceful_shutdown=1)
    server = uvicorn.Server(config)
    server_box.append(server)
    with contextlib.suppress(KeyboardInterrupt):
        server.run(sockets=[sock])

