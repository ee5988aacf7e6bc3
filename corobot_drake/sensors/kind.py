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
in its frame (`SensorKind.frame_name`), which /tf_static places at that mount.
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
    """The QoS profile name of its ROS 2 topic (`ros2.interfaces`)."""
    foxglove_schema: ClassVar[str | None] = None
    """The foxglove-sdk message class name (`foxglove.messages.<name>`; None: not recorded)."""

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

    def add_meshcat(self, builder, meshcat, sensor: BuiltSensor) -> None:
        """What Meshcat draws of the sensor (its rays, a pressed bumper); default nothing."""

    # --- the wire formats ------------------------------------------------------------------
    def topic_name(self, sensor: str) -> str:
        """The sensor's topic, relative to its robot's namespace (no leading slash)."""
        return f"{self.topic}/{sensor}"

    def frame_name(self, sensor: str) -> str:
        """The sensor's frame (the frame its readings are in), relative to its robot's."""
        return f"{self.topic}_{sensor}"

    def to_json(self, reading) -> dict:
        """The reading as JSON (HTTP, dashboard, summary): its fields, non-finite numbers as
        None (JSON has no NaN or Infinity)."""
        return {f.name: _jsonable(getattr(reading, f.name)) for f in dc.fields(reading)}

    def foxglove_message(self, reading, frame: str):
        """The foxglove-sdk message of a reading, stamped with its own time; None: nothing to
        publish for this reading."""
        raise NotImplementedError

    def ros2_message(self, messages, reading, frame: str):
        """The ROS 2 message of a reading (`messages`: `ros2.messages.Messages`, whose
        `header(t, frame)` stamps it), stamped with the reading's own time."""
        raise NotImplementedError

    def reading_time(self, reading) -> float:
        """s: the simulated time a reading was taken (a publisher sends a reading once, when
        this moves)."""
        return float(reading.time)


def _jsonable(value):
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if hasattr(value, "tolist"):  # numpy
        return _jsonable(value.tolist())
    return value
