"""The robot's topics and frames, named as ROS names them, for every front end that
publishes them (the MCAP/Foxglove recording, the ROS 2 node and its bags).

With one robot the topics and frames are bare (`/odom`, `base_link`), as a ROS robot's; with
several, each robot's are under its name (`/<robot>/odom`, `<robot>/base_link`), as ROS
namespaces and tf prefixes put them; a robot added while running is under its name too, and
the ones the run started with keep theirs (`robot_names`). The signals with a topic of their own
(`signals.Signal.topic`: the contact telemetry, ...) get one `TelemetryTopic` each, a JSON
message the recording writes and the ROS 2 front end turns into a corobot_interfaces message.

No Foxglove or ROS import here: each front end brings its own wire format.
"""

import dataclasses as dc
import functools

from corobot_drake import signals

CHASSIS_FRAME = "base_link"
"""The chassis body's frame name (ROS's base frame)."""


@dc.dataclass(frozen=True)
class RobotNames:
    """One robot's topic and frame names: bare for the only robot, else under its name."""

    robot: str
    namespaced: bool = False
    base: str = "chassis"
    """The robot's base link (`RobotSpec.base`; the Corobot's `chassis`): its frame is
    `base_link`."""

    def topic(self, name: str) -> str:
        return f"/{self.robot}/{name}" if self.namespaced else f"/{name}"

    def frame(self, name: str) -> str:
        return f"{self.robot}/{name}" if self.namespaced else name

    def body_frame(self, body_name: str) -> str:
        """The frame of one of the robot's links (its base link is `base_link`)."""
        return self.frame(CHASSIS_FRAME if body_name == self.base else body_name)

    def base_frame(self) -> str:
        """The frame of the robot's base link: `base_link`."""
        return self.frame(CHASSIS_FRAME)


def robot_names(robot: str, first: tuple[str, ...] | list[str], base: str = "chassis"
                ) -> RobotNames:
    """`robot`'s names in a run that started with the robots `first` (the scenario's): bare
    for the only robot it started with, under its name otherwise (one of several, or a robot
    added while running, e.g. by ROS 2's SpawnEntity). A robot's names never change while the
    run goes on: the robots it started with keep theirs when another is added or deleted."""
    return RobotNames(robot, list(first) != [robot], base)


def nanoseconds(t: float) -> int:
    """Simulation time (s) as integer nanoseconds (an MCAP log time)."""
    return round(t * 1e9)



TIMESTAMP_SCHEMA = {"type": "object", "properties": {"sec": {"type": "integer"},
                                                     "nsec": {"type": "integer"}}}


@dc.dataclass(frozen=True)
class TelemetryTopic:
    """A topic of signals with a message of their own (`signals.Signal.topic`: the contact
    telemetry, ...): the values of some of the robot's output ports (`station`'s
    `<robot>.<port>`), as JSON."""

    name: str
    """The topic, under the robot's namespace."""
    title: str
    description: str
    signals: tuple
    """The `signals.Signal`s it carries, each at its `own_place`."""
    per_wheel: bool
    """Whether its signals have one value per wheel (the robot's wheel order; then
    `wheels: {<wheel>: {<field>: value}}`) or not (then `<field>: value`, or a keyed
    signal's `<key>: value`)."""
    costly: bool
    """Whether a look evaluates the plant's contact results or velocities (costly every
    step: looked at like the run log's held samples, `looks.TELEMETRY_PERIOD`) or the
    chassis pose alone (a few sums: at the state topics' rate)."""

    @property
    def fields(self) -> tuple:
        """(field, robot output port, what: units) of each value of its messages (a keyed
        signal's: one per key)."""
        out = []
        for s in self.signals:
            what = f"{s.unit + ': ' if s.unit else ''}{s.doc}"
            names = (s.field,) if s.per_wheel or not s.keys else s.keys
            out += [(name, s.port, what) for name in names]
        return tuple(out)

    def schema(self) -> dict:
        """The JSON schema of its messages."""
        values = {field: {"type": "number", "description": what}
                  for field, _, what in self.fields}
        if self.per_wheel:
            values = {"wheels": {"type": "object", "description": "by wheel name",
                                 "additionalProperties": {"type": "object",
                                                          "properties": values}}}
        return {"title": self.title, "description": self.description, "type": "object",
                "properties": {"timestamp": TIMESTAMP_SCHEMA, **values}}

    def message(self, t: float, values: list) -> dict:
        """The message at time `t` (s) of its signals' port values (each a vector)."""
        sec, nsec = divmod(nanoseconds(t), 1_000_000_000)
        out: dict = {"timestamp": {"sec": sec, "nsec": nsec}}
        for spec, vector in zip(self.signals, values, strict=True):
            signals.put_value(out, spec.own_place, spec.value_of(vector))
        return out


def _telemetry_topic(name: str, carried: tuple) -> TelemetryTopic:
    """The topic `name` of the signals it carries."""
    title = "corobot." + "".join(word.capitalize() for word in name.split("_"))
    description = signals.TOPIC_DOCS.get(name) or f"{carried[0].doc}."
    return TelemetryTopic(name, title, description, carried, per_wheel=carried[0].per_wheel,
                          costly=carried[0].costly)


TELEMETRY_TOPICS = tuple(_telemetry_topic(name, carried)
                         for name, carried in signals.own_topics().items())
"""The topics of the signals with a message of their own (the contact telemetry, ...): the
Corobot's (`telemetry_topics`: any robot's)."""


@functools.cache
def _topics_of(wheel_names: tuple[str, ...], encoded: tuple[str, str]) -> tuple:
    table = signals.robot_signals(wheel_names, encoded)
    if table is signals.SIGNALS:
        return TELEMETRY_TOPICS
    return tuple(_telemetry_topic(name, carried)
                 for name, carried in signals.own_topics(table).items())


def telemetry_topics(spec=None) -> tuple:
    """`TELEMETRY_TOPICS` of a robot (`robots.RobotSpec`; None: the Corobot's): its
    per-wheel signals by its wheels."""
    if spec is None:
        return TELEMETRY_TOPICS
    left, right = spec.encoded
    return _topics_of(spec.wheel_names, (spec.wheel_names[left], spec.wheel_names[right]))
