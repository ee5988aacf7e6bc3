"""The ROS 2 tests' side: a private network, the simulation as a user runs it, and a node of
the test's own that talks to it as a user's node would.

Every DDS participant of a test (the simulation process and the probe node) lives in a network
namespace of the test's own with only loopback up (`private_network`: nothing can leave the
machine), discovers over LOCALHOST, in a domain id of its own (`domain_id`). The probe waits on
discovery and on messages (a condition variable), never on a fixed sleep; its time limits only
bound a test that would otherwise hang.
"""

from __future__ import annotations

import collections
import contextlib
import os
import random
import subprocess
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest

WAIT = 60.0
"""s (wall clock) a wait may take before the test fails: discovery takes up to ~5 s, a
simulated second ~1-2 s of a loaded 2-core machine's time."""
RETRY = 10.0
"""s (wall clock) a service call waits for its answer before asking again (`Probe.call`)."""
SHM = Path("/dev/shm")
ONE_GRAPH_AT_A_TIME = pytest.mark.realtime
"""The DDS tests run in real time, alone on the machine, one module after another on one
pytest worker (tests/conftest.py): their networks are private, but /dev/shm, where Fast DDS
keeps its segments and `own_shared_memory` cleans up, is the machine's."""


@contextlib.contextmanager
def private_network():
    """`graph.private_network`, skipping the test where it cannot be made (not root)."""
    from corobot_drake.ros2.graph import PrivateNetworkError
    from corobot_drake.ros2.graph import private_network as network

    stack = contextlib.ExitStack()
    try:
        stack.enter_context(network())
    except PrivateNetworkError as e:
        pytest.skip(f"{e}: the ROS 2 tests keep DDS off every real network")
    with stack:
        yield


def domain_id() -> int:
    """A ROS_DOMAIN_ID of the test's own (1-100: each maps to its own UDP ports)."""
    return random.Random(os.getpid() ^ time.time_ns()).randint(1, 100)


def _shm_segments() -> set[str]:
    return {p.name for p in SHM.glob("*fastrtps*")} | {p.name for p in SHM.glob("*fastdds*")}


def _mapped_files() -> set[str]:
    """Every /dev/shm file some other live process maps or holds open, with its companions
    (a DDS segment in use is mapped by its owner; its `<segment>_el` liveness lock is only
    held open, and its `sem.<segment>_mutex` neither: a live participant's files, which a
    test ending beside it must leave; this process's Fast DDS keeps its own mapped after its
    participants are gone)."""
    used = set()
    for process in Path("/proc").glob("[0-9]*"):
        if process.name == str(os.getpid()):
            continue
        with contextlib.suppress(OSError):
            used |= {line.split(None, 5)[5].strip()
                     for line in (process / "maps").read_text().splitlines()
                     if len(line.split(None, 5)) == 6 and "/dev/shm/" in line}
        with contextlib.suppress(OSError):
            for fd in (process / "fd").iterdir():
                with contextlib.suppress(OSError):
                    target = os.readlink(fd)
                    if target.startswith("/dev/shm/"):
                        used.add(target)
    companions = set()
    for path in used:
        name = path.removeprefix("/dev/shm/").removesuffix("_el")
        companions |= {f"/dev/shm/{name}", f"/dev/shm/{name}_el", f"/dev/shm/sem.{name}_mutex"}
    return used | companions


@contextlib.contextmanager
def own_shared_memory():
    """Removes, at the end, the Fast DDS shared-memory segments made meanwhile that no other
    live process maps (the test's participants are gone by then): the test's own, never
    another's (one in use is mapped by its owner; one from before the test is left)."""
    before = _shm_segments()
    try:
        yield
    finally:
        in_use = _mapped_files()
        for name in _shm_segments() - before:
            path = SHM / name
            if str(path) not in in_use:
                with contextlib.suppress(OSError):
                    path.unlink()


class Probe:
    """The test's node: records what it subscribes to, publishes, calls services and actions."""

    def __init__(self, domain: int, name: str = "corobot_test_probe"):
        import rclpy
        from rclpy.executors import MultiThreadedExecutor

        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = rclpy.create_node(name, context=self.context)
        self.messages: dict[str, list] = collections.defaultdict(list)
        self._changed = threading.Condition()
        self._clients: dict = {}
        self._publishers: dict = {}
        self._executor = MultiThreadedExecutor(context=self.context)
        self._executor.add_node(self.node)
        self._thread = threading.Thread(target=self._executor.spin, daemon=True)
        self._thread.start()

    def subscribe(self, topic: str, msgtype, qos=None) -> None:
        from rclpy.qos import qos_profile_sensor_data

        def record(msg):
            with self._changed:
                self.messages[topic].append(msg)
                self._changed.notify_all()

        self.node.create_subscription(msgtype, topic, record,
                                      qos if qos is not None else qos_profile_sensor_data)

    def wait_for(self, topic: str, predicate: Callable = lambda m: True, start: int = 0,
                 timeout: float = WAIT):
        """The first message on `topic` from index `start` on that satisfies `predicate`."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while True:
                for msg in self.messages[topic][start:]:
                    if predicate(msg):
                        return msg
                start = max(start, len(self.messages[topic]))
                left = deadline - time.monotonic()
                if left <= 0:
                    raise AssertionError(f"no message on {topic} as wanted in {timeout} s "
                                         f"({len(self.messages[topic])} received)")
                self._changed.wait(left)

    def count(self, topic: str) -> int:
        with self._changed:
            return len(self.messages[topic])

    def wait_future(self, future, timeout: float = WAIT):
        """The result of an rclpy future (the executor's thread completes it)."""
        event = threading.Event()
        future.add_done_callback(lambda f: event.set())
        if not event.wait(timeout):
            raise AssertionError(f"no answer in {timeout} s")
        return future.result()

    def client(self, service: str, srvtype):
        """The probe's client of `service`, made (and its server discovered) on first use and
        kept: each new client is a new round of discovery, whose race can lose an answer."""
        if (service, srvtype) not in self._clients:
            client = self.node.create_client(srvtype, service)
            if not client.wait_for_service(timeout_sec=WAIT):
                raise AssertionError(f"service {service} not discovered in {WAIT} s")
            self._clients[service, srvtype] = client
        return self._clients[service, srvtype]

    def publisher(self, topic: str, msgtype, qos=10):
        """The probe's publisher on `topic`, made on first use and kept until `close`: an
        entity destroyed while the executor's thread waits on it kills that thread
        (rclpy's InvalidHandle, "destruction was requested"), and the probe hears nothing
        more."""
        if (topic, msgtype) not in self._publishers:
            self._publishers[topic, msgtype] = self.node.create_publisher(msgtype, topic, qos)
        return self._publishers[topic, msgtype]

    def action_client(self, kind, name: str):
        """The probe's client of action `name`, made (and its server discovered) on first use
        and kept. Make it before the test needs it: a goal sent before the server has
        discovered the client's readers is accepted, but its answer is lost."""
        from rclpy.action import ActionClient

        if (name, kind) not in self._clients:
            client = ActionClient(self.node, kind, name)
            if not client.wait_for_server(timeout_sec=WAIT):
                raise AssertionError(f"action {name} not discovered in {WAIT} s")
            self._clients[name, kind] = client
        return self._clients[name, kind]

    def call(self, service: str, srvtype, request, timeout: float = WAIT,
             retry: float | None = RETRY):
        """The answer of `service` to `request`, asked again every `retry` s without one:
        wait_for_service sees the server's reader, not whether the server has discovered the
        client's (Fast DDS then drops the response after 100 ms). For a quick, idempotent
        service only (a stop, parameters); `retry=None` for one that takes its time (a pose
        answers once the robot has settled: asked again, it would start over)."""
        client = self.client(service, srvtype)
        deadline = time.monotonic() + timeout
        while True:
            future = client.call_async(request)
            left = deadline - time.monotonic()
            try:
                return self.wait_future(future, left if retry is None else min(retry, left))
            except AssertionError:
                client.remove_pending_request(future)
                if time.monotonic() >= deadline:
                    raise AssertionError(f"no answer from {service} in {timeout} s") from None

    def close(self) -> None:
        import rclpy

        self._executor.shutdown(timeout_sec=5.0)
        self._thread.join(5.0)
        from rclpy.action import ActionClient

        for client in self._clients.values():  # before the node, whose destruction leaves
            if isinstance(client, ActionClient):  # an action client's futures failing
                client.destroy()
            else:
                self.node.destroy_client(client)
        self.node.destroy_node()
        if self.context.ok():
            rclpy.shutdown(context=self.context)


@contextlib.contextmanager
def simulation_process(args: list[str], log=None):
    """`python -m corobot_drake [args]` (this Python: the project's), stopped at the end by
    Ctrl-C (SIGINT) to its PID. Its stderr is a pipe the test reads; with `log` (a path),
    its output goes there instead (a pipe nobody reads would fill)."""
    import signal
    import sys

    if log is None:
        process = subprocess.Popen([sys.executable, "-m", "corobot_drake", *args],
                                   stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    else:
        with open(log, "w") as out:
            process = subprocess.Popen([sys.executable, "-m", "corobot_drake", *args],
                                       stdout=out, stderr=subprocess.STDOUT)
    try:
        yield process
    finally:
        if process.poll() is None:
            process.send_signal(signal.SIGINT)
            try:
                process.wait(30)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(5)


@contextlib.contextmanager
def private_domain():
    """A private network (`private_network`), shared memory of its own (`own_shared_memory`)
    and a ROS domain of its own, discovery on this host only (the environment variables set
    while inside): yields the domain id."""
    domain = domain_id()
    with contextlib.ExitStack() as stack:
        stack.enter_context(private_network())
        stack.enter_context(own_shared_memory())
        patch = stack.enter_context(pytest.MonkeyPatch.context())
        patch.setenv("ROS_DOMAIN_ID", str(domain))
        patch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
        yield domain


@contextlib.contextmanager
def ros2_simulation(args: list[str], serve: bool = True):
    """`python -m corobot_drake [args] --ros2` and a `Probe`, both in a private network in a
    domain of their own: yields (server, probe). With `serve`, `--serve --port 0` too (the
    HTTP services are the tests' window on the simulation: `robot.pose()` ...; `server` is
    its `ServerProcess`), else `server` is the process."""
    from corobot_drake.serving.serve import ServerProcess

    with contextlib.ExitStack() as stack:
        domain = stack.enter_context(private_domain())
        server = stack.enter_context(ServerProcess([*args, "--ros2"]) if serve
                                     else simulation_process([*args, "--ros2"]))
        probe = Probe(domain)
        stack.callback(probe.close)
        yield server, probe
