"""The Ray instances the project starts use loopback only: every TCP and UDP socket of their
processes (GCS, raylet, agents, workers) and of a driver joining them is bound to a loopback
address, and a connected one reaches a loopback address. Read from /proc/net, each socket
followed by its inode (lab.processes)."""

import ipaddress
import os
import platform
import sys
from pathlib import Path

from corobot_drake.study import engine
from lab.processes import children_by_parent, descendants, sockets_held


def _address(text: str) -> tuple[ipaddress.IPv4Address | ipaddress.IPv6Address, int]:
    """(address, port) of /proc/net's hex `ADDRESS:PORT` (the address in 32-bit words, each in
    the machine's byte order)."""
    host, port = text.split(":")
    raw = bytes.fromhex(host)
    if sys.byteorder == "little":
        raw = b"".join(raw[i:i + 4][::-1] for i in range(0, len(raw), 4))
    return ipaddress.ip_address(raw), int(port, 16)


def inet_sockets() -> dict[int, tuple]:
    """{inode: ((local address, port), (remote address, port))} of the machine's TCP and UDP
    sockets, IPv4 and IPv6."""
    found = {}
    for table in ("tcp", "tcp6", "udp", "udp6"):
        for row in Path(f"/proc/net/{table}").read_text().splitlines()[1:]:
            fields = row.split()
            found[int(fields[9])] = (_address(fields[1]), _address(fields[2]))
    return found


def off_loopback(held: dict[int, set[int]], sockets: dict[int, tuple]) -> list[str]:
    """The sockets of `held` ({PID: socket inodes}) bound to, or connected to, an address that
    is not loopback (an unconnected socket's remote end is port 0): one line each."""
    return [f"{pid}: {local} -> {remote}:{remote_port}"
            for pid, inodes in held.items() for inode in inodes & sockets.keys()
            for (local, _), (remote, remote_port) in [sockets[inode]]
            if not local.is_loopback or (remote_port and not remote.is_loopback)]


def _name(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/comm").read_text().strip()
    except OSError:  # ended meanwhile
        return ""


def _held(pid: int) -> set[int]:
    try:
        return sockets_held(pid)
    except OSError:  # ended meanwhile
        return set()


def test_the_ray_head_its_workers_and_a_joining_driver_use_loopback_only(ray_head):
    import ray

    before = sockets_held(os.getpid())
    ray.init(address=ray_head.address, log_to_driver=False, configure_logging=False)
    try:
        # A task (a function the workers can import), so that workers have started, each
        # with its gRPC server.
        assert ray.get(ray.remote(platform.python_version).remote()) == platform.python_version()
        parents = children_by_parent(zombies=False)
        head = [info.process.pid for infos in ray_head.head_node.all_processes.values()
                for info in infos]
        held = {d: _held(d) for pid in head for d in [pid, *descendants(pid, parents)]}
        held[os.getpid()] = sockets_held(os.getpid()) - before  # the driver's own
        sockets = inet_sockets()
        names = {_name(pid) for pid, inodes in held.items() if inodes & sockets.keys()}
        assert {"gcs_server", "raylet", "ray::IDLE", _name(os.getpid())} <= names, names
        assert off_loopback(held, sockets) == []
        assert ipaddress.ip_address(ray_head.address.rsplit(":", 1)[0]).is_loopback
    finally:
        ray.shutdown()  # disconnects; the head is the session's


def test_the_study_engines_local_instance_starts_on_loopback_and_leaves_ray_as_it_was(
        monkeypatch):
    """What ray.init sees when the study engine starts its local instance (ray.init replaced:
    nothing started), from Ray's default on Linux: the node's address is loopback and the
    processes it starts get the loopback environment; Ray's mode is put back after (a cluster
    joined later by its address is joined as Ray would)."""
    import ray
    from ray._private import ray_constants

    monkeypatch.setattr(ray_constants, "ENABLE_RAY_CLUSTER", True)
    for name in engine.LOOPBACK_RAY_ENV:
        monkeypatch.delenv(name, raising=False)
    seen = {}

    def init(**kwargs):
        seen.update(address=kwargs["address"], node=ray.util.get_node_ip_address(),
                    env={name: os.environ.get(name) for name in engine.LOOPBACK_RAY_ENV})

    monkeypatch.setattr(ray, "init", init)
    engine._start_local(1)
    assert seen == {"address": "local", "node": "127.0.0.1", "env": engine.LOOPBACK_RAY_ENV}
    assert ray_constants.ENABLE_RAY_CLUSTER is True
    assert not set(engine.LOOPBACK_RAY_ENV) & set(os.environ)
