"""`--rosbag DIR`: the ROS 2 topics written as a rosbag2 directory (metadata.yaml and MCAP
storage, CDR messages, `ros2msg` schemas with their RIHS01 type hashes), by the `rosbags`
package: no ROS needed at run time; ROS 2 Jazzy's `ros2 bag info` and `ros2 bag play` read it.

The messages are the live node's (`publishers`, through a `bus.Bus`), each logged at its
stamp (simulation time), with the QoS the node offers, so that a replay offers the same.
"""

from __future__ import annotations

import queue
import threading
from pathlib import Path

from corobot_drake.ros2.bus import typestore
from corobot_drake.ros2.interfaces import Qos

BAG_VERSION = 9
"""rosbag2's metadata version that ROS 2 Jazzy writes."""


def _qos(kind: Qos):
    """The rosbags QoS record of one of the node's offers (`node.QOS`)."""
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
    depth = {Qos.SENSOR: 5, Qos.RELIABLE: 10, Qos.LATCHED: 1}[kind]
    return BagQos(
        history=QosHistory.KEEP_LAST, depth=depth,
        reliability=QosReliability.BEST_EFFORT if kind is Qos.SENSOR else QosReliability.RELIABLE,
        durability=(QosDurability.TRANSIENT_LOCAL if kind is Qos.LATCHED
                    else QosDurability.VOLATILE),
        deadline=default, lifespan=default, liveliness=QosLiveliness.AUTOMATIC,
        liveliness_lease_duration=default, avoid_ros_namespace_conventions=False)


def bag_problem(path: Path) -> str | None:
    """Why a bag cannot be written at `path` (it must not exist; its parent must be a
    writable directory), else None."""
    import os

    if path.exists():
        return "exists already: name a new directory (rosbag2 makes it)"
    parent = path.parent
    if not parent.is_dir():
        return f"the directory {parent} does not exist"
    if not os.access(parent, os.W_OK | os.X_OK):
        return f"the directory {parent} is not writable"
    return None


QUEUE_SIZE = 256
"""Messages waiting for the writer thread; a full queue holds the simulation back (at most
~60 MB of camera frames waiting)."""


class BagSink:
    """A `bus.Bus` sink that writes a rosbag2 directory; `close()` finishes it (the messages
    still queued written, then its metadata: a bag not closed has its MCAP file alone).

    The file is written by a thread of its own: the rosbags writer copies each message a few
    times in Python (~1.3 ms a camera frame), which then overlaps the simulation's steps (its
    C++ runs without the GIL) instead of adding to them."""

    def __init__(self, path: str | Path):
        from rosbags.rosbag2 import StoragePlugin, Writer

        self.path = Path(path)
        self._writer = Writer(self.path, version=BAG_VERSION, storage_plugin=StoragePlugin.MCAP)
        self._writer.open()
        self._connections: dict = {}
        self.messages = 0
        self._queue: queue.Queue = queue.Queue(QUEUE_SIZE)
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._drain, name="corobot-rosbag", daemon=True)
        self._thread.start()

    def declare(self, topic: str, msgtype: str, qos: Qos) -> None:
        self._connections[topic] = self._writer.add_connection(
            topic, msgtype, typestore=typestore(), serialization_format="cdr",
            offered_qos_profiles=[_qos(qos)])

    def write(self, topic: str, data, t_ns: int) -> None:
        if self._error is not None:
            raise self._error
        self._queue.put((self._connections[topic], t_ns, data))
        self.messages += 1

    def _drain(self) -> None:
        while (item := self._queue.get()) is not None:
            if self._error is None:
                try:
                    self._writer.write(*item)
                except BaseException as e:  # the disk filled: raised in the simulation thread
                    self._error = e

    def close(self) -> None:
        if self._writer is None:
            return
        self._queue.put(None)
        self._thread.join()
        self._writer.close()
        self._writer = None
        if self._error is not None:
            raise self._error
