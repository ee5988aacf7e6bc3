"""The machine's process tree and listening sockets, read from /proc: for the benchmarks that
measure a server's processes and the tests that check what a process left running or open.

A socket is followed by its inode, not its port: another process may bind a freed port number
at once (the suite runs on every core)."""

import contextlib
import os
from pathlib import Path


def children_by_parent(zombies: bool = True) -> dict[int, list[int]]:
    """{parent PID: its children's PIDs} now, from every /proc/*/stat (a process that ends
    meanwhile is left out; zombies too, unless `zombies`)."""
    parents: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            state, parent = stat.read_text().rsplit(")", 1)[1].split()[:2]
        except (OSError, ValueError):
            continue
        if zombies or state != "Z":
            parents.setdefault(int(parent), []).append(int(stat.parent.name))
    return parents


def descendants(pid: int, parents: dict[int, list[int]] | None = None,
                skip: frozenset[int] | set[int] = frozenset()) -> list[int]:
    """The PIDs below `pid` in the process tree (`parents`: `children_by_parent()`'s map, read
    now if None), the trees of `skip` left out."""
    parents = children_by_parent() if parents is None else parents
    found, todo = [], [pid]
    while todo:
        for child in parents.get(todo.pop(), []):
            if child not in skip:
                found.append(child)
                todo.append(child)
    return found


def alive(pid: int) -> bool:
    """`pid` runs: one of its threads exists and is no zombie. Every thread is read, not only
    the process's own stat: a leader thread that has ended reads "Z" while the other threads
    still run and hold the process's files."""
    for stat in Path(f"/proc/{pid}/task").glob("*/stat"):
        try:
            if stat.read_text().rsplit(")", 1)[1].split()[0] not in ("Z", "X"):
                return True
        except (OSError, IndexError):
            continue
    return False


def listening_sockets(port: int | None = None) -> set[int]:
    """The inodes of the machine's listening TCP sockets (/proc/net/tcp and tcp6, state 0A),
    only those on `port` if given."""
    found = set()
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        for row in Path(table).read_text().splitlines()[1:]:
            local, state, inode = (row.split()[i] for i in (1, 3, 9))
            if state == "0A" and (port is None or int(local.rsplit(":", 1)[1], 16) == port):
                found.add(int(inode))
    return found


def sockets_held(pid: int) -> set[int]:
    """The inodes of the sockets among `pid`'s open files."""
    held = set()
    for fd in Path(f"/proc/{pid}/fd").iterdir():
        with contextlib.suppress(OSError):
            target = os.readlink(fd)
            if target.startswith("socket:["):
                held.add(int(target[len("socket:["):-1]))
    return held
