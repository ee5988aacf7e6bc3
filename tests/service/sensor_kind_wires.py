"""A sensor kind added to the registry, run in a process of its own
(tests/service/test_recording.py): one module's worth of kind (a thermometer: its config, its
reading, its system and its `SensorKind`) appended to `sensors.registry.KINDS` before the
scenario is imported, as one line in registry.py would add it; then one short run writing
`<FOLDER>/run.mcap` and the ROS 2 bag `<FOLDER>/bag` (`python sensor_kind_wires.py FOLDER`),
which the test reads back.

Nothing here touches a front end: the recording and the bag find the kind through the
registry alone.
"""

import dataclasses as dc
import sys
from pathlib import Path

from pydrake.common.schema import Transform
from pydrake.common.value import Value
from pydrake.systems.framework import LeafSystem

from corobot_drake.sensors import registry
from corobot_drake.sensors.kind import BuiltSensor, SensorKind

RATE = 10.0
"""Hz: the thermometer's samples."""
DURATION = 0.45
"""s: the run (looks at 0, 0.1, ... 0.4 s: the samples of 0 to 0.3 s are published)."""


def warming(t: float) -> float:
    """degC at `t` s: what the thermometer reads (no noise: the wires are under test)."""
    return 20.0 + 0.5 * t


def _mount() -> Transform:
    X = Transform()
    X.base_frame, X.translation = "chassis", [0.1, 0.0, 0.2]
    return X


@dc.dataclass
class ThermometerConfig:
    X_PB: Transform = dc.field(default_factory=_mount)
    rate_hz: float = RATE


@dc.dataclass(frozen=True)
class Temperature:
    """sensor_msgs/Temperature's field (degC), taken at `time` (s)."""

    time: float
    temperature: float


class Thermometer(LeafSystem):
    """Samples `warming` every 1/`rate` s from 0 (discrete state: [time, degC]); output
    `reading`, a Temperature."""

    def __init__(self, rate: float):
        super().__init__()
        state = self.DeclareDiscreteState([float("nan"), 0.0])
        self.DeclareInitializationDiscreteUpdateEvent(self._sample)
        self.DeclarePeriodicDiscreteUpdateEvent(1.0 / rate, 0.0, self._sample)
        self.DeclareAbstractOutputPort(
            "reading", lambda: Value(Temperature(float("nan"), 0.0)),
            lambda c, v: v.set_value(Temperature(*c.get_discrete_state(state).value())),
            {self.discrete_state_ticket(state)})

    def _sample(self, context, discrete_state):
        t = context.get_time()
        discrete_state.get_mutable_vector().SetFromVector([t, warming(t)])


TEMPERATURE_SCHEMA = {"title": "toy.Temperature", "type": "object", "properties": {
    "timestamp": {"type": "object"}, "frame_id": {"type": "string"},
    "temperature": {"type": "number", "description": "degC"}}}
"""Its Foxglove message: JSON (Foxglove has no temperature schema)."""


class ThermometerKind(SensorKind):
    """Thermometers: `robots.<robot>.thermometers.<name>`, default `cabin`; topic
    `thermometer/<name>`, frame `thermometer_<name>`."""

    field = "thermometers"
    config_type = ThermometerConfig
    reading_type = Temperature
    topic = "thermometer"
    ros2_type = "sensor_msgs/msg/Temperature"
    foxglove_schema = TEMPERATURE_SCHEMA

    def defaults(self) -> dict:
        return {"cabin": ThermometerConfig()}

    def add(self, site, name: str, config: ThermometerConfig) -> BuiltSensor:
        system = site.builder.AddNamedSystem(f"{site.robot}.thermometer.{name}",
                                             Thermometer(config.rate_hz))
        return BuiltSensor(self, site.robot, name, config, system, system.get_output_port(),
                           config.rate_hz, config.X_PB)

    def foxglove_message(self, reading: Temperature, frame: str) -> dict:
        ns = round(reading.time * 1e9)
        return {"timestamp": {"sec": ns // 10**9, "nsec": ns % 10**9}, "frame_id": frame,
                "temperature": reading.temperature}

    def ros2_message(self, messages, reading: Temperature, frame: str):
        return messages.msg("sensor_msgs/msg/Temperature")(
            header=messages.header(reading.time, frame), temperature=reading.temperature,
            variance=0.0)


registry.KINDS = (*registry.KINDS, ThermometerKind())

from corobot_drake.config.scenario import load_scenario  # noqa: E402
from corobot_drake.recording.mcap_log import McapLog  # noqa: E402
from corobot_drake.resources import DEFAULT_SCENARIO  # noqa: E402
from corobot_drake.simulation import Simulation, quiet_drake_warnings  # noqa: E402


def run(folder: Path) -> None:
    """The default scenario, the camera off (cheap), with an MCAP file and a ROS 2 bag."""
    import functools

    from corobot_drake.ros2.bag import BagSink
    from corobot_drake.ros2.bus import Bus
    from corobot_drake.ros2.publishers import add_ros2_topics

    scenario = load_scenario(DEFAULT_SCENARIO)
    scenario.robots["corobot"].cameras["front"].rgb = False
    bag = BagSink(folder / "bag")
    with McapLog(folder / "run.mcap") as log:
        sim = Simulation(scenario, foxglove=log.context,
                         extras=[functools.partial(add_ros2_topics, Bus([bag]))])
        sim.advance_to(DURATION)
    bag.close()


def main() -> None:
    quiet_drake_warnings()
    run(Path(sys.argv[1]))


if __name__ == "__main__":
    main()
