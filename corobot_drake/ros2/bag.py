"""`--rosbag DIR`: the ROS 2 topics written as a rosbag2 directory (metadata.yaml and MCAP
storage, CDR messages, `ros2msg` schemas with their RIHS01 type hashes), by the `rosbags`
package: no ROS needed at run time; ROS 2 Jazzy's `ros2 bag info` and `ros2 bag play` read it.

The messages are the live node's (`publishers`, through a `bus.Bus`), each logged at its
stamp (simulation time), with the QoS the node offers, so that a replay offers the same.
"""

from __future__ import annotations

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


class BagSink:
    """A `bus.Bus` sink that writes a rosbag2 directory; `close()` finishes it (its metadata
    is written then: a bag not closed has its MCAP file alone)."""

    def __init__(self, path: str | Path):
        from rosbags.rosbag2 import StoragePlugin, Writer

        self.path = Path(path)
        self._writer = Writer(self.path, version=BAG_VERSION, storage_plugin=StoragePlugin.MCAP)
        self._writer.open()
        self._connections: dict = {}
        self.messages = 0

    def declare(self, topic: str, msgtype: str, qos: Qos) -> None:
        self._connections[topic] = self._writer.add_connection(
            topic, msgtype, typestore=typestore(), serialization_format="cdr",
            offered_qos_profiles=[_qos(qos)])

    def write(self, topic: str, data, t_ns: int) -> None:
        self._writer.write(self._connections[topic], t_ns, data)
        self.messages += 1

    def close(self) -> None:
        if self._writer is not None:
            self._writer.close()
            self._writer = None
