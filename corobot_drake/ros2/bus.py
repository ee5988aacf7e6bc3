"""Where the ROS 2 publishers' messages go: each is serialized once (CDR, by the `rosbags` type
store, no ROS needed) and handed to every sink: the live node's publishers (`node.LiveSink`),
a rosbag2 writer (`bag.BagSink`). A sink has `declare(topic, type, qos)` and `write(topic,
data, t_ns)`, and may have `watched(topic)` (False: nobody would see a message on it now, a
live topic without a subscriber; without it, always True: a bag records everything); the bus
declares every topic to every sink before the first write. A sink may also have
`forget(topic)`: a topic the simulation no longer publishes (a robot deleted while running,
`Bus.building`); a bag keeps every topic it was given.
"""

from __future__ import annotations

import contextlib
from functools import cache

from corobot_drake.ros2.interfaces import Qos, message_definitions


@cache
def typestore():
    """ROS 2 Jazzy's message types (`rosbags`' built-in store) with corobot_interfaces'."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    types = {}
    for name, text in message_definitions().items():
        if name not in store.types:
            types.update(get_types_from_msg(text, name))
    store.register(types)
    return store


class Channel:
    """One topic of a `Bus`: `publish(t_ns, message)` (a `typestore()` message instance)."""

    def __init__(self, bus: Bus, topic: str, msgtype: str):
        self._bus, self.topic, self.msgtype = bus, topic, msgtype
        self._serialize = bus.store.serialize_cdr

    def watched(self) -> bool:
        """Whether a message published now would reach anyone (a sink records it, or a live
        topic has a subscriber)."""
        return any(getattr(sink, "watched", None) is None or sink.watched(self.topic)
                   for sink in self._bus.sinks)

    def publish(self, t_ns: int, message) -> None:
        sinks = self._bus.sinks
        if not sinks:
            return
        data = self._serialize(message, self.msgtype)
        for sink in sinks:
            sink.write(self.topic, data, t_ns)


class Bus:
    """The topics the simulation publishes (full names, e.g. `/odom`, `/bot2/odom`) and the
    sinks their messages go to (given before the simulation is built: a latched topic's
    message is written once, at initialization)."""

    def __init__(self, sinks=()):
        self.store = typestore()
        self.types = self.store.types
        self.sinks = list(sinks)
        self.topics: dict[str, tuple[str, Qos]] = {}
        self.first_robots: tuple[str, ...] | None = None
        """The robots of the first simulation built on this bus (the scenario the run started
        with): they name every robot's topics (`topics.robot_names`), in a rebuilt one too."""
        self._built: set[str] | None = None

    def channel(self, topic: str, msgtype: str, qos: Qos) -> Channel:
        """Declares `topic` (once; again: the same channel's type must agree)."""
        known = self.topics.get(topic)
        if known is not None and known[0] != msgtype:
            raise ValueError(f"topic {topic} declared as {known[0]} and {msgtype}")
        if known is None:
            self.topics[topic] = (msgtype, qos)
            for sink in self.sinks:
                sink.declare(topic, msgtype, qos)
        if self._built is not None:
            self._built.add(topic)
        return Channel(self, topic, msgtype)

    @contextlib.contextmanager
    def building(self, robots):
        """Around the making of a simulation's publishers (`robots`: its robots' names): the
        topics a simulation built before it had and it has not are forgotten by the sinks
        that forget (`forget`: the node's publishers of a deleted robot's topics go)."""
        if self.first_robots is None:
            self.first_robots = tuple(robots)
        self._built = set()
        try:
            yield
            for topic in self.topics.keys() - self._built:
                for sink in self.sinks:
                    forget = getattr(sink, "forget", None)
                    if forget is not None:
                        forget(topic)
        finally:
            self._built = None
