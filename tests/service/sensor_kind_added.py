"""A sensor kind added to the registry, run in a process of its own
(tests/service/test_sensor_kind_added.py): one module's worth of kind (a light sensor: its
config with bounded fields, its reading, its system, its `SensorKind` with a check of its own
and a frame of its own added before the plant is finalized) appended to
`sensors.registry.KINDS` before the scenario is imported, as one line in registry.py adds a
kind; then what every front end of one short run makes of it, printed as JSON: the scenario's
schema and loader (good and bad input), the station's plant, the Python `Robot`, the HTTP
routes, the dashboard's snapshot and the summary, a study's `sensors` metric, Meshcat's
drawing, and the wires: the MCAP file (as live
Foxglove gets it) and the ROS 2 bag (as the live node's topics), read back.

Nothing here touches a front end: they find the kind through the registry alone.
"""

import dataclasses as dc
import functools
import json
import sys
import tempfile
import typing
from pathlib import Path

from pydrake.common.schema import Transform
from pydrake.common.value import Value
from pydrake.geometry import Meshcat
from pydrake.math import RigidTransform
from pydrake.multibody.tree import FixedOffsetFrame
from pydrake.systems.framework import LeafSystem

from corobot_drake.config.poses import mount
from corobot_drake.limits import RATE, Range, bounded
from corobot_drake.sensors import registry
from corobot_drake.sensors.kind import BuiltSensor, SensorKind

LOOK = 0.25
"""s: when the front ends are read (the samples at 0, 0.1 and 0.2 s have been taken)."""


def brightening(t: float) -> float:
    """lx at `t` s: what the light sensor reads (no noise: the front ends are under test)."""
    return 100.0 + 10.0 * t


@dc.dataclass
class LightSensorConfig:
    """One light sensor on a robot."""

    X_PB: Transform = dc.field(default_factory=lambda: mount((0.05, 0.0, 0.3), (0, 0, 0)))
    rate_hz: float = bounded(10.0, RATE)
    """Samples per second."""
    low: float = bounded(0.0, Range(0.0, 1e5, unit="lx"))
    """lx: the least it reads."""
    high: float = bounded(1e4, Range(0.0, 1e5, unit="lx"))
    """lx: the most it reads (more than `low`)."""
    enabled: bool = True


@dc.dataclass(frozen=True)
class Illuminance:
    """sensor_msgs/Illuminance's field (lx), taken at `time` (s)."""

    time: float
    illuminance: float


class LightSensor(LeafSystem):
    """Samples `brightening` every 1/`rate` s from 0 (discrete state: [time, lx]); output
    `reading`, an Illuminance, and `state`, [time, lx] (what the run log samples)."""

    def __init__(self, rate: float):
        super().__init__()
        state = self.DeclareDiscreteState([float("nan"), 0.0])
        self.DeclareInitializationDiscreteUpdateEvent(self._sample)
        self.DeclarePeriodicDiscreteUpdateEvent(1.0 / rate, 0.0, self._sample)
        self.DeclareAbstractOutputPort(
            "reading", lambda: Value(Illuminance(float("nan"), 0.0)),
            lambda c, v: v.set_value(Illuminance(*c.get_discrete_state(state).value())),
            {self.discrete_state_ticket(state)})
        self.DeclareStateOutputPort("state", state)

    def _sample(self, context, discrete_state):
        t = context.get_time()
        discrete_state.get_mutable_vector().SetFromVector([t, brightening(t)])


ILLUMINANCE_SCHEMA = {"title": "toy.Illuminance", "type": "object", "properties": {
    "timestamp": {"type": "object"}, "frame_id": {"type": "string"},
    "illuminance": {"type": "number", "description": "lx"}}}
"""Its Foxglove message: JSON (Foxglove has no schema for it)."""


class LightSensorKind(SensorKind):
    """Light sensors: `robots.<robot>.light_sensors.<name>` (none by default); a frame
    `light_<name>` of their own on their link; topic `light/<name>` (JSON on Foxglove,
    sensor_msgs/Illuminance on ROS 2)."""

    field = "light_sensors"
    config_type = LightSensorConfig
    reading_type = Illuminance
    topic = "light"
    foxglove_schema = ILLUMINANCE_SCHEMA
    ros2_type = "sensor_msgs/msg/Illuminance"

    def foxglove_message(self, reading: Illuminance, frame: str) -> dict:
        ns = round(reading.time * 1e9)
        return {"timestamp": {"sec": ns // 10**9, "nsec": ns % 10**9}, "frame_id": frame,
                "illuminance": reading.illuminance}

    def ros2_message(self, messages, reading: Illuminance, frame: str):
        return messages.msg("sensor_msgs/msg/Illuminance")(
            header=messages.header(reading.time, frame), illuminance=reading.illuminance,
            variance=0.0)

    def log_columns(self, sensor: str) -> tuple[str, ...]:
        """`light_<sensor>`: lx."""
        return (f"light_{sensor}",)

    def log_port(self, sensor: BuiltSensor):
        return sensor.system.GetOutputPort("state"), (1,)

    def check(self, config: LightSensorConfig) -> list[tuple[str, str]]:
        if not config.high > config.low:
            return [("high", f"must be more than low ({config.low:g} lx); got {config.high:g}")]
        return []

    def add_geometry(self, plant, model_instance, robot: str, name: str, config) -> None:
        parent = plant.GetFrameByName(config.X_PB.base_frame, model_instance)
        plant.AddFrame(FixedOffsetFrame(f"light_{name}", parent,
                                        RigidTransform(config.X_PB.translation)))

    def add_meshcat(self, builder, meshcat, sensor: BuiltSensor) -> None:
        """A small yellow sphere at the sensor, drawn once (a toy's drawing)."""
        from pydrake.geometry import Rgba, Sphere

        meshcat.SetObject(f"/light/{sensor.robot}/{sensor.name}", Sphere(0.02),
                          Rgba(1.0, 0.9, 0.2, 1.0))

    def add(self, site, name: str, config: LightSensorConfig) -> BuiltSensor | None:
        if not config.enabled:
            return None
        system = site.builder.AddNamedSystem(f"{site.robot}.light.{name}",
                                             LightSensor(config.rate_hz))
        return BuiltSensor(self, site.robot, name, config, system, system.GetOutputPort("reading"),
                           config.rate_hz, config.X_PB)


registry.KINDS = (*registry.KINDS, LightSensorKind())

from fastapi.testclient import TestClient  # noqa: E402
from step_runner import StepRunner  # noqa: E402

from corobot_drake.config import scenario as sc  # noqa: E402
from corobot_drake.recording.mcap_log import McapLog  # noqa: E402
from corobot_drake.resources import DEFAULT_SCENARIO  # noqa: E402
from corobot_drake.ros2.bag import BagSink  # noqa: E402
from corobot_drake.ros2.bus import Bus  # noqa: E402
from corobot_drake.ros2.publishers import add_ros2_topics  # noqa: E402
from corobot_drake.serving import snapshots  # noqa: E402
from corobot_drake.serving.webapp import create_app  # noqa: E402
from corobot_drake.simulation import Simulation, quiet_drake_warnings  # noqa: E402
from corobot_drake.study.metrics import measure  # noqa: E402

BAD = {
    "inverted": "{top: {low: 50, high: 5}}",
    "unknown_link": "{top: {X_PB: {base_frame: antenna}}}",
    "rate": "{top: {rate_hz: 0}}",
}
"""Bad light sensors: a check of the kind's own, a link the robot lacks, a field's bound."""


def loader_errors(folder: Path) -> dict:
    """The one line each bad sensor gets, from an override and (the first) from a file."""
    out = {}
    for name, sensors in BAD.items():
        try:
            sc.load_scenario(DEFAULT_SCENARIO,
                             overrides=[f"robots: {{corobot: {{light_sensors: {sensors}}}}}"])
        except sc.ScenarioError as e:
            out[name] = str(e)
    path = folder / "bad.yaml"
    path.write_text("robots:\n  corobot:\n    light_sensors:\n      top:\n        low: 50\n"
                    "        high: 5\n")
    try:
        sc.load_scenario(path)
    except sc.ScenarioError as e:
        out["file"] = str(e).replace(str(path), "bad.yaml")
    return out


def read_mcap(path: Path) -> dict:
    """What the MCAP file carries of the light sensors: {topic: [[log time ns, schema,
    frame, lx], ...]}, and `/tf`'s mounts of their frames (the last): {frame: [parent, xyz]}."""
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
    from mcap.reader import make_reader

    out: dict = {"/tf": {}}
    with open(path, "rb") as f:
        for schema, channel, m in make_reader(f).iter_messages(log_time_order=True):
            if channel.topic.startswith("/light/"):
                message = json.loads(m.data)
                out.setdefault(channel.topic, []).append(
                    [m.log_time, schema.name, message["frame_id"], message["illuminance"]])
            elif channel.topic == "/tf":
                pool = descriptor_pool.DescriptorPool()
                for fd in descriptor_pb2.FileDescriptorSet.FromString(schema.data).file:
                    pool.Add(fd)
                tf = message_factory.GetMessageClass(
                    pool.FindMessageTypeByName(schema.name)).FromString(m.data)
                out["/tf"] = {x.child_frame_id: [x.parent_frame_id, [
                    x.translation.x, x.translation.y, x.translation.z]]
                    for x in tf.transforms if x.child_frame_id.startswith("light_")}
    return out


def read_bag(path: Path) -> dict:
    """What the ROS 2 bag carries of the light sensors: {topic: [[t ns, type, frame, lx],
    ...]}, and `/tf_static`'s mounts of their frames: {frame: [parent, xyz]}."""
    from rosbags.rosbag2 import Reader

    from corobot_drake.ros2.bus import typestore

    store, out = typestore(), {"/tf_static": {}}
    with Reader(path) as reader:
        for connection, t_ns, data in reader.messages():
            msg = store.deserialize_cdr(data, connection.msgtype)
            if connection.topic.startswith("/light/"):
                out.setdefault(connection.topic, []).append(
                    [t_ns, connection.msgtype, msg.header.frame_id, msg.illuminance])
            elif connection.topic == "/tf_static":
                out["/tf_static"] = {x.child_frame_id: [x.header.frame_id, [
                    x.transform.translation.x, x.transform.translation.y,
                    x.transform.translation.z]]
                    for x in msg.transforms if x.child_frame_id.startswith("light_")}
    return out


def main() -> None:
    quiet_drake_warnings()
    hints = typing.get_type_hints(sc.Robot)
    out = {"schema": str(hints["light_sensors"]),
           "default": list(sc.Robot().light_sensors),
           "errors": loader_errors(Path(tempfile.mkdtemp()))}
    scenario = sc.load_scenario(DEFAULT_SCENARIO, overrides=[
        "robots: {corobot: {light_sensors: {top: {}, side: {rate_hz: 20}}}}"])
    scenario.robots["corobot"].cameras["front"].rgb = False
    out["loaded"] = {n: c.rate_hz for n, c in scenario.robots["corobot"].light_sensors.items()}
    folder = Path(tempfile.mkdtemp())
    bag = BagSink(folder / "bag")
    with McapLog(folder / "run.mcap") as log:
        sim = Simulation(scenario, foxglove=log.context,
                         extras=[functools.partial(add_ros2_topics, Bus([bag]))])
        sim.advance_to(LOOK)
    bag.close()
    out.update(mcap=read_mcap(folder / "run.mcap"), bag=read_bag(folder / "bag"))
    robot = sim.robot("corobot")
    plant = sim.station.plant
    out["frame"] = plant.HasFrameNamed("light_top", plant.GetModelInstanceByName("corobot"))
    out["sensors"] = {field: list(named) for field, named in robot.sensors().items()}
    out["reading"] = dc.asdict(robot.reading("top"))
    out["reading_type"] = type(robot.reading("side", kind="light")).__name__
    out["expected"] = {"time": 0.2, "illuminance": brightening(0.2)}
    out["summary"] = sim.summary()["robots"]["corobot"]["sensors"]["light_sensors"]
    robot.write_log(folder / "run.csv")
    header, *rows = (folder / "run.csv").read_text().splitlines()
    out["run_log"] = {"columns": header.split(","), "last": rows[-1].split(",")}
    out["snapshot"] = snapshots.robot_snapshot(robot, sim.time)["sensors"]["light_sensors"]
    http = TestClient(create_app(StepRunner(sim)), base_url="http://127.0.0.1")
    out["http"] = http.get("/robots/corobot/sensors/light_sensors/top").json()
    out["http_all"] = http.get("/robots/corobot/sensors").json()["light_sensors"]
    start = (robot.pose(), 0.0)
    out["study"] = {column: value for column, value in
                    measure(sim, {"corobot": start}, ["sensors"]).items() if "light" in column}
    meshcat = Meshcat()
    Simulation(scenario, meshcat)
    out["meshcat"] = {name: meshcat.HasPath(f"/light/corobot/{name}") for name in ("top", "side")}
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
