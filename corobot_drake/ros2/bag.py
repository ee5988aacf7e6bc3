"""`--rosbag DIR`: the ROS 2 topics written as a rosbag2 directory (metadata.yaml and MCAP
storage, CDR messages, `ros2msg` schemas with their RIHS01 type hashes), by the `rosbags`
package: no ROS needed at run time; ROS 2 Jazzy's `ros2 bag info` and `ros2 bag play` read it.

The messages are the live node's (`publishers`, through a `bus.Bus`), each logged at its
stamp (simulation time), with the QoS the node offers, so that a replay offers the same.
"""

from __future__ import annotations

import collections
import contextlib
import dataclasses as dc
import queue
import sys
import threading
from pathlib import Path

from corobot_drake.ros2.bus import typestore
from corobot_drake.ros2.interfaces import Qos, offer

BAG_VERSION = 9
"""rosbag2's metadata version that ROS 2 Jazzy writes."""
ROS_DISTRO = "jazzy"
"""The distro metadata.yaml names (the rosbags writer puts its own name there)."""


def _qos(kind: Qos):
    """The rosbags QoS record of one of the node's offers (`interfaces.offer`)."""
    from rosbags.interfaces import (
        Qos as BagQos,
    )
    from rosbags.interfaces import (
        QosDurability,
        QosHistory,
        QosLiveliness,
        QosReliability,
        QosTime,
    )

    default = QosTime(0, 0)
    o = offer(kind)  # the node's default offer: a replay offers what the node does
    return BagQos(
        history=QosHistory.KEEP_LAST, depth=o.depth,
        reliability=QosReliability.RELIABLE if o.reliable else QosReliability.BEST_EFFORT,
        durability=(QosDurability.TRANSIENT_LOCAL if o.transient_local
                    else QosDurability.VOLATILE),
        deadline=default, lifespan=default, liveliness=QosLiveliness.AUTOMATIC,
        liveliness_lease_duration=default, avoid_ros_namespace_conventions=False)


def bag_problem(path: Path) -> str | None:
    """Why a bag cannot be written at `path`, else None: its parent must be a writable
    directory, its name (with `.mcap`, its MCAP file's) must fit the file system, and it must
    not exist, not even as a dangling symlink (rosbag2 makes the directory)."""
    import os
    import stat

    parent = path.parent
    try:
        if not parent.exists():
            return f"the directory {parent} does not exist"
        if not parent.is_dir():
            mode = parent.stat().st_mode
            kind = ("a FIFO" if stat.S_ISFIFO(mode) else "a device" if (
                stat.S_ISCHR(mode) or stat.S_ISBLK(mode)) else "a file")
            return f"{parent} is {kind}, not a directory"
        name_max = os.pathconf(parent, "PC_NAME_MAX")
        size = len(os.fsencode(path.name))
        if size + len(MCAP_SUFFIX) > name_max:
            return (f"its name is {size} bytes: with {MCAP_SUFFIX} (its MCAP file's name) it "
                    f"must fit the file system's {name_max}")
        if path.is_symlink() and not path.exists():
            return (f"is a dangling symlink (to {os.readlink(path)}): name a new directory "
                    "(rosbag2 makes it)")
        if path.exists():
            return "exists already: name a new directory (rosbag2 makes it)"
    except OSError as e:  # a path too long, a loop of symlinks, ...
        return f"cannot be looked at ({e.strerror})"
    if not os.access(parent, os.W_OK | os.X_OK):
        return f"the directory {parent} is not writable"
    return None


MCAP_SUFFIX = ".mcap"
"""The bag's MCAP file is `<DIR>/<DIR's name>.mcap` (the rosbags writer's naming)."""


QUEUE_SIZE = 256
"""Messages waiting for the writer thread; a full queue holds the simulation back (at most
~60 MB of camera frames waiting)."""


@dc.dataclass(frozen=True)
class _Kept:
    """What the MCAP file holds on disk up to `offset` (bytes): its first `chunks` chunks,
    `counts` messages per connection id, stamped `start` to `end` (ns)."""

    offset: int
    chunks: int
    counts: dict
    start: int
    end: int


_DECLARE = object()
"""A `BagSink` queue item's mark: a topic declared while the bag is written."""


class BagSink:
    """A `bus.Bus` sink that writes a rosbag2 directory; `close()` finishes it (the messages
    still queued written, then its metadata: a bag not closed has its MCAP file alone).

    The file is written by a thread of its own: the rosbags writer copies each message a few
    times in Python (~1.3 ms a camera frame), which then overlaps the simulation's steps (its
    C++ runs without the GIL) instead of adding to them.

    A write that fails (the disk filled) finishes the bag with what is on disk: the MCAP file
    cut back to its last whole chunk (~1 MiB each), then its index and metadata.yaml for those
    messages, dropping chunks until they fit; one line says so (`report`), the later
    messages are dropped, and `failed` is True."""

    def __init__(self, path: str | Path, report=None):
        from rosbags.rosbag2 import StoragePlugin, Writer

        self.path = Path(path)
        self.report = report or (lambda line: print(line, file=sys.stderr, flush=True))
        self.failed = False
        self._connections: dict = {}
        self.messages = 0
        self._queue: queue.Queue = queue.Queue(QUEUE_SIZE)
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._drain, name="corobot-rosbag", daemon=True)
        self._thread.start()
        self._writer = Writer(self.path, version=BAG_VERSION, storage_plugin=StoragePlugin.MCAP)
        # The MCAP writer's state at each chunk it finishes (written out: flushed), which a
        # failed write falls back to (`_salvage`).
        self._storage = None
        self._kept: list[_Kept] = []
        try:
            self._writer.open()
            self._storage = self._writer.storage
            close_chunk = self._storage.close_chunk

            def chunk_closed():
                close_chunk()
                self._keep()

            self._storage.close_chunk = chunk_closed
            self._keep()
        except OSError as e:  # a disk full from the start
            self._fail(e)

    def _keep(self) -> None:
        storage = self._storage
        storage.bio.flush()
        self._kept.append(_Kept(storage.bio.tell(), len(storage.chunks),
                                dict(storage.channel_stats), storage.message_start_time,
                                storage.message_end_time))

    def declare(self, topic: str, msgtype: str, qos: Qos) -> None:
        """A topic's connection: added at once before the first message, else by the
        writing thread in its turn (a robot spawned while recording: the MCAP writer writes
        a connection into the chunk the messages go to)."""
        if self.failed:
            return
        if self.messages:
            self._queue.put((_DECLARE, topic, (msgtype, qos)))
        else:
            self._add_connection(topic, msgtype, qos)

    def _add_connection(self, topic: str, msgtype: str, qos: Qos) -> None:
        self._connections[topic] = self._writer.add_connection(
            topic, msgtype, typestore=typestore(), serialization_format="cdr",
            offered_qos_profiles=[_qos(qos)])

    def write(self, topic: str, data, t_ns: int) -> None:
        if self._error is not None:
            raise self._error
        if self.failed:
            return
        self._queue.put((topic, t_ns, data))
        self.messages += 1

    def _drain(self) -> None:
        while (item := self._queue.get()) is not None:
            if self._error is None and not self.failed:
                try:
                    if item[0] is _DECLARE:
                        self._add_connection(item[1], *item[2])
                    else:
                        topic, t_ns, data = item
                        self._writer.write(self._connections[topic], t_ns, data)
                except OSError as e:  # the disk filled: the bag is finished as it stands
                    self._fail(e)
                except BaseException as e:  # raised in the simulation thread
                    self._error = e

    def close(self) -> None:
        if self._writer is None:
            return
        self._queue.put(None)
        self._thread.join()
        if not self.failed:
            try:
                self._writer.close()
                _name_distro(self.path)
            except OSError as e:
                self._fail(e)
        self._writer = None
        if self._error is not None:
            raise self._error

    def _fail(self, error: OSError) -> None:
        self.failed = True
        kept = self._salvage()
        problem = f"error: --rosbag: {self.path}: cannot write ({error.strerror or error})"
        if kept is None:
            self.report(f"{problem}; its index does not fit either: the bag is incomplete")
        elif not sum(kept.counts.values()):
            self.report(f"{problem}; the bag is finished, with no messages")
        else:
            self.report(f"{problem}; the bag is finished with the {sum(kept.counts.values())} "
                        f"messages written before, up to t = {kept.end * 1e-9:.2f} s")

    def _salvage(self) -> _Kept | None:
        """The bag finished with what the MCAP file holds on disk (`_kept`, the latest that
        fits with its index and metadata), or None if not even the header's does."""
        from io import BytesIO

        from rosbags.rosbag2.storage_mcap import PendingChunk

        writer, storage = self._writer, self._storage
        if storage is None:  # not even its directory and file were made
            return None
        with contextlib.suppress(OSError):
            storage.bio.close()  # what its buffer held cannot be written
        ids = list(storage.channel_stats)
        for kept in reversed(self._kept):
            counts = {i: kept.counts.get(i, 0) for i in ids}
            try:
                storage.bio = storage.path.open("r+b")
                storage.bio.truncate(kept.offset)
                storage.bio.seek(kept.offset)
                del storage.chunks[kept.chunks:]
                storage.chunk = PendingChunk(2**63 - 1, 0, BytesIO(), collections.defaultdict(list))
                storage.channel_stats, writer.counts = dict(counts), dict(counts)
                storage.message_start_time = writer.min_timestamp = kept.start
                storage.message_end_time = writer.max_timestamp = kept.end
                writer.storage = storage
                writer.close()
                with contextlib.suppress(OSError):  # (shorter: it fits where the old did)
                    _name_distro(self.path)
                return kept
            except OSError:
                with contextlib.suppress(OSError):
                    storage.bio.close()
        return None


def _name_distro(path: Path) -> None:
    """Names the distro the bag is for in its metadata.yaml (`ros_distro`, as `ros2 bag`
    writes it), where the rosbags writer names itself."""
    metadata = path / "metadata.yaml"
    text = metadata.read_text()
    metadata.write_text(text.replace("ros_distro: rosbags", f"ros_distro: {ROS_DISTRO}", 1))
