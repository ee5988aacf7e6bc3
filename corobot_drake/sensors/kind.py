"""What a kind of sensor declares, once, for every front end: `SensorKind`.

A kind is one module under `corobot_drake/sensors/` holding its config (a dataclass whose
fields carry their ranges, `limits.bounded`), its reading (a frozen dataclass, units and frame
in its docstring, field names those of the kind's standard message), its systems, and one
`SensorKind` subclass; `sensors/registry.KINDS` lists the kinds, one line each. Everything
else loops over `KINDS` and a robot's sensors by name: the scenario's per-kind maps
(`robots.<robot>.<field>.<sensor>`), the loader's checks, the station's two build phases,
`Robot.reading(name)`, the HTTP routes and dashboard, the summary and run log, Meshcat, the
Foxglove/MCAP channels and the ROS 2 topics and bags. No front end names a kind.

A sensor is mounted on a link of its robot by its config's `X_PB` (Drake's schema
`Transform`, `base_frame` a link name; `config.poses.mount_frame` resolves it), and publishes
in its frame (`SensorKind.frame_name`), which /tf_static places at that mount. The loader
checks every sensor's mount (a link of its robot), then its kind's `check`.

Sensor names are unique within a kind's map; kinds may share one (the Corobot's IR sensor and
camera are both `front`), so a front end addresses a sensor by kind field and name
(`/robots/<robot>/sensors/<field>/<name>`), and `Robot.reading(name, kind=...)` needs the kind
only for a shared name.

A kind's module is imported by the registry, which the scenario's `Robot` is made from: at
import it must not import `config.scenario` (nor anything that does), nor an extra's package
(foxglove, rclpy, ...: import those inside the methods that need them).
"""

from __future__ import annotations

import dataclasses as dc
import math
from typing import Any, ClassVar


@dc.dataclass
class BuiltSensor:
    """One sensor as the station built it: what every front end reads of it.

    `reading` is an output port of `system` whose value is the kind's reading (an abstract
    value of `SensorKind.reading_type`); a front end evaluates it in the system's context.
    `rate` (Hz) is how often a new reading comes: publishers look at that rate.
    `X_PB` is the config's mount (`base_frame` a link of the robot)."""

    kind: SensorKind
    robot: str
    name: str
    config: Any
    system: Any
    reading: Any
    rate: float
    X_PB: Any = None
    extra: dict = dc.field(default_factory=dict)
    """What the kind keeps for itself (e.g. a camera's frame saver, an IR sensor's rays)."""

    def read(self, root_context):
        """The latest reading (a `kind.reading_type`), from the diagram's root context."""
        return self.kind.read(self, root_context)


class SensorKind:
    """One kind of sensor: subclass it in the kind's module, set the class attributes and
    override what the kind does; register an instance in `sensors/registry.KINDS`.

    Wire formats: `to_json` (HTTP and the summary), `foxglove_message` (MCAP and live
    Foxglove; `foxglove_schema` names the foxglove-sdk message class), `ros2_message`
    (`ros2_type`, `ros2_qos`). A kind that has no message on a wire leaves its schema None.
    One publisher per sensor and wire (`recording.looks.SensorPublisher`) looks for a new
    reading (`looks`, `out_time`) and hands it to the wire; a kind with several topics on a
    wire (a camera's image and calibration) declares them (`foxglove_channels`,
    `ros2_channels`) and its message methods return {subtopic: message}.
    """

    field: ClassVar[str]
    """The robot's map of this kind in the scenario: `robots.<robot>.<field>.<sensor>`
    (plural, e.g. `ir_sensors`, `cameras`, `lidars`, `imus`, `bumpers`)."""
    config_type: ClassVar[type]
    """The config dataclass of one sensor (its fields bounded: `limits.bounded`)."""
    reading_type: ClassVar[type]
    """The reading dataclass (frozen; units and frame in its docstring)."""
    topic: ClassVar[str]
    """The topic and frame stem: by default a sensor `s` publishes on `<stem>/<s>` in frame
    `<stem>_<s>` (`front` of kind `ir` -> topic `ir/front`, frame `ir_front`), each under the
    robot's namespace when a scene has several (`topics.RobotNames`)."""
    ros2_type: ClassVar[str | None] = None
    """`package/msg/Name` of its ROS 2 message (None: not on ROS 2)."""
    ros2_qos: ClassVar[str] = "sensor"
    """What its ROS 2 topic is, for its QoS (`ros2.interfaces.Qos`, whose `offer` is the one
    place the profiles are said): `sensor`, a stream (reliable unless the node's `sensor_qos`
    parameter says best_effort), or `reliable`, events none of which may be dropped."""
    off: ClassVar[dict | None] = {"enabled": False}
    """The config fields that turn a sensor of the kind off (no systems built), for a run that
    reads no sensor (the tools' physics-only runs, a study whose metrics read none); None: it
    stays on (its own geometry is part of the robot's physics)."""
    renders: ClassVar[bool] = False
    """Whether it renders images (a camera): a study keeps it on only when its `cameras:`
    says so, whatever its metrics read (no metric reads an image)."""
    foxglove_schema: ClassVar[str | dict | None] = None
    """The foxglove-sdk message class name (`foxglove.messages.<name>`), or a JSON schema (a
    dict with a `title`) for a message Foxglove has no schema for; None: not recorded."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.field!r})"

    # --- the scenario ------------------------------------------------------------------------
    def defaults(self) -> dict:
        """{name: config} every robot has unless its scenario says otherwise (the Corobot's
        own sensors of the kind; `{}` for none)."""
        return {}

    def new_sensor(self, name: str):
        """The config a sensor the defaults lack starts as (its fields then merged over it):
        a working default mount on the robot."""
        return self.config_type()

    def enabled(self, config) -> bool:
        """Whether `config` builds a sensor (a default sensor is removed by turning it off)."""
        return bool(getattr(config, "enabled", True))

    def check(self, config) -> list[tuple[str, str]]:
        """Problems beyond each field's own range (e.g. an inverted range): (field, what is
        wrong) pairs, which the loader reports as one line at the field's file and line."""
        return []

    # --- the station ---------------------------------------------------------------------------
    def add_geometry(self, plant, model_instance, robot: str, name: str, config) -> None:
        """Before the plant is finalized: any geometry or frame the sensor needs of its own
        (a bumper's collision shape); default none."""

    def add(self, site, name: str, config) -> BuiltSensor | None:
        """After the plant is finalized: the sensor's systems in `site.builder`
        (`sensors.site.SensorSite`); None when `config` turns it off."""
        raise NotImplementedError

    def read(self, sensor: BuiltSensor, root_context):
        """The sensor's latest reading from the diagram's root context: by default the value
        of its `reading` port (a kind whose systems put the reading out in parts overrides
        this and assembles it)."""
        return sensor.reading.Eval(sensor.system.GetMyContextFromRoot(root_context))

    def set_seed(self, sensor: BuiltSensor, root_context, random_seed: int, config) -> None:
        """At each run's start: key the sensor's noise in `root_context` from the scenario's
        `random_seed` and its `config` (a study varies the seed between runs of one built
        diagram); default nothing (a kind without noise, or keyed when built)."""

    def log_columns(self, sensor: str) -> tuple[str, ...]:
        """The run-log columns of sensor `sensor` (`systems.runlog`), after the robot's own,
        each a number in the units its kind's docstring says; default none."""
        return ()

    def log_port(self, sensor: BuiltSensor):
        """(vector output port, its rows) the sensor's `log_columns` are sampled from, one
        row a column (None when it has none): a port that costs no Python call per sample (a
        state output port), whose rows a C++ gain picks every `runlog.LOG_PERIOD` s."""
        return None

    def add_meshcat(self, builder, meshcat, sensor: BuiltSensor) -> None:
        """What Meshcat draws of the sensor (its rays, a pressed bumper); default nothing."""

    # --- the wire formats ------------------------------------------------------------------
    def topic_name(self, sensor: str) -> str:
        """The sensor's topic, relative to its robot's namespace (no leading slash)."""
        return f"{self.topic}/{sensor}"

    def frame_name(self, sensor: str) -> str:
        """The sensor's frame (the frame its readings are in), relative to its robot's."""
        return f"{self.topic}_{sensor}"

    def read_json(self, sensor: BuiltSensor, root_context, summary: bool = False) -> dict:
        """The sensor's latest reading as JSON (`to_json`; with `summary`, `summary_json`),
        from the diagram's root context: what the HTTP snapshot (at 30 Hz) and the summary
        ask. A kind whose reading costs to make (a camera's frame is rendered when it is
        read) overrides it to give the JSON without the costly part."""
        reading = self.read(sensor, root_context)
        return self.summary_json(reading) if summary else self.to_json(reading)

    def summary_json(self, reading) -> dict:
        """The reading as the run's summary holds it (`Robot.summary()["sensors"]`): by
        default `to_json`; a kind with bulky readings keeps a summary-sized part."""
        return self.to_json(reading)

    def to_json(self, reading) -> dict:
        """The reading as JSON (HTTP, dashboard, summary): its fields, non-finite numbers as
        None (JSON has no NaN or Infinity)."""
        return {f.name: _jsonable(getattr(reading, f.name)) for f in dc.fields(reading)}

    def foxglove_message(self, reading, frame: str):
        """The foxglove-sdk message (a dict for a JSON schema) of a reading, stamped with its
        own time, or {subtopic: message} (`foxglove_channels`); None: nothing to publish for
        this reading."""
        raise NotImplementedError

    def ros2_message(self, messages, reading, frame: str):
        """The ROS 2 message of a reading (`messages`: `ros2.messages.Messages`, whose
        `header(t, frame)` stamps it), stamped with the reading's own time, or {subtopic:
        message} (`ros2_channels`)."""
        raise NotImplementedError

    def reading_time(self, reading) -> float:
        """s: the simulated time a reading was taken (a publisher sends a reading once, when
        this moves)."""
        return float(reading.time)

    def foxglove_channels(self) -> dict[str, str | dict]:
        """{subtopic: schema} of a sensor's Foxglove channels, each on its `topic_name` ("")
        or `<topic_name>/<subtopic>`: by default its one topic of `foxglove_schema`. A kind
        with several returns them here and {subtopic: message} from `foxglove_message`."""
        return {} if self.foxglove_schema is None else {"": self.foxglove_schema}

    def ros2_channels(self) -> dict[str, tuple[str, str]]:
        """{subtopic: (ROS 2 type, QoS name)} of a sensor's ROS 2 topics, as
        `foxglove_channels`: by default its one topic of `ros2_type` and `ros2_qos`."""
        return {} if self.ros2_type is None else {"": (self.ros2_type, self.ros2_qos)}

    def ros2_frames(self, sensor: str) -> list[tuple[str, Any]]:
        """The frames /tf_static places for the sensor, a chain from its mount: (frame, X)
        pairs, the first's pose in the mount's link `X_PB @ X`, each other's in the frame
        before it. By default its `frame_name` at the mount (X None: the mount itself)."""
        return [(self.frame_name(sensor), None)]

    # --- what a publisher reads ----------------------------------------------------------------
    def wire_ports(self, sensor: BuiltSensor) -> dict:
        """{input name: output port} a publisher of the sensor's messages reads: by default
        {"reading": its `reading` port}."""
        return {"reading": sensor.reading}

    def looks(self, sensor: BuiltSensor) -> tuple[float, float]:
        """(period, offset), s: when a publisher looks for a new reading; by default every
        1 / `rate` s from 0. A kind whose readings are discrete updates on a schedule of their
        own gives that schedule (a look and a reading at one time are then at the same float
        time, the look first, and the look after sees it)."""
        return 1.0 / sensor.rate, 0.0

    def out_time(self, sensor: BuiltSensor, inputs) -> float:
        """s: when the sensor's latest reading came out (NaN: none yet), `inputs(name)` being
        the value of the publisher's input `name` (`wire_ports`); a look publishes a reading
        that came out since the look before. By default `reading_time` of input `reading`."""
        return self.reading_time(inputs("reading"))

    def wire_reading(self, sensor: BuiltSensor, inputs):
        """What `foxglove_message` and `ros2_message` make the messages of (asked only for a
        new reading): by default input `reading`, the reading. A kind whose messages carry
        more than its reading (an IR scan's rays, a camera's calibration) returns a value of
        its own, whose time is its `reading_time`."""
        return inputs("reading")

    def add_reader(self, sensor: BuiltSensor, wanted) -> None:
        """A publisher of the sensor's readings joins its readers; `wanted()` says whether it
        would take a reading now. By default nothing: a kind whose readings cost work ahead of
        being read (a camera's frames, rendered on a worker from their capture) does that work
        only while some reader wants them."""


def _jsonable(value):
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if hasattr(value, "tolist"):  # numpy
        return _jsonable(value.tolist())
    return value
