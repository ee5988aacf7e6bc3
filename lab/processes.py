"""The machine's process tree, read from /proc: for the benchmarks that measure a server's
processes and the tests that check what a process left running."""

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
    """`pid` runs (it exists and is no zombie)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return False
