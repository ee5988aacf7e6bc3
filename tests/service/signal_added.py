"""A signal added to the table, run in a process of its own (tests/service/test_tables.py):
one entry in `signals.SIGNALS` (a battery voltage) and the output port of its system, then
every front end of one short run, printed as JSON: {front end: the value it carries at
`LOOK`}, and what it was live.

The entry is made before any front end is imported, as one written in signals.py is.
"""

import functools
import json
import sys
import tempfile
from pathlib import Path

from corobot_drake import signals

BATTERY = signals.Signal(
    "battery_voltage", "V", "the battery's terminal voltage", port="battery_voltage",
    system="battery", fields={"battery_voltage": 0.01}, summary="battery_V",
    http=("drive.battery_voltage",), log=(("battery", ""),), topic="battery")
signals.SIGNALS[BATTERY.name] = BATTERY

from fastapi.testclient import TestClient  # noqa: E402
from pydrake.systems.framework import LeafSystem  # noqa: E402
from step_runner import StepRunner  # noqa: E402

from corobot_drake.config.scenario import load_scenario  # noqa: E402
from corobot_drake.recording.mcap_log import McapLog  # noqa: E402
from corobot_drake.resources import DEFAULT_SCENARIO  # noqa: E402
from corobot_drake.serving import snapshots  # noqa: E402
from corobot_drake.serving.routes.subscriptions import CHANGE_THRESHOLDS  # noqa: E402
from corobot_drake.serving.webapp import create_app  # noqa: E402
from corobot_drake.simulation import Simulation, quiet_drake_warnings  # noqa: E402
from corobot_drake.systems.runlog import COLUMNS  # noqa: E402

LOOK = 0.3
"""s: when the front ends are read (a multiple of the state topics' period)."""


class Battery(LeafSystem):
    """A battery running down: `battery_voltage` (1, V) = 12.6 - 0.5 t."""

    def __init__(self):
        super().__init__()
        self.DeclareVectorOutputPort("battery_voltage", 1,
                                     lambda c, o: o.SetAtIndex(0, 12.6 - 0.5 * c.get_time()))


def add_battery(builder, plant, scene_graph, robots, scenario):
    for name in robots:
        builder.AddNamedSystem(f"{name}.battery", Battery())


class Memory:
    """A ROS 2 bus sink keeping each message's CDR bytes: {topic: {t_ns: bytes}}."""

    def __init__(self):
        self.types, self.messages = {}, {}

    def declare(self, topic, msgtype, qos):
        self.types[topic], self.messages[topic] = msgtype, {}

    def write(self, topic, data, t_ns):
        self.messages[topic][t_ns] = bytes(data)


def main() -> None:
    from mcap.reader import make_reader

    from corobot_drake.ros2.bus import Bus
    from corobot_drake.ros2.publishers import add_ros2_topics

    quiet_drake_warnings()
    memory = Memory()
    bus = Bus([memory])
    folder = Path(tempfile.mkdtemp())
    scenario = load_scenario(DEFAULT_SCENARIO)
    scenario.robots["corobot"].cameras["front"].rgb = False
    with McapLog(folder / "run.mcap") as log:
        sim = Simulation(scenario, foxglove=log.context,
                         extras=[add_battery, functools.partial(add_ros2_topics, bus)])
        sim.advance_to(LOOK)
        robot = sim.robot("corobot")
        out = {"live": robot.signal("battery_voltage"),
               "summary": robot.summary()["battery_V"],
               "snapshot": snapshots.robot_snapshot(robot, sim.time)["drive"][
                   "battery_voltage"],
               "change_threshold": CHANGE_THRESHOLDS["battery_voltage"]}
        http = TestClient(create_app(StepRunner(sim)), base_url="http://127.0.0.1")
        out["http"] = http.get("/robots/corobot/drive").json()["battery_voltage"]
        sim.advance_to(LOOK + 0.1)
    rows = robot.run_log()
    out["run_log"] = next(float(r[COLUMNS.index("battery")]) for r in rows
                      if abs(r[0] - LOOK) < 1e-9)
    robot.write_log(folder / "log.csv")
    out["csv_header"] = (folder / "log.csv").read_text().splitlines()[0].split(",")
    with open(folder / "run.mcap", "rb") as f:
        out["mcap"] = next(json.loads(m.data)["battery_voltage"] for _, c, m
                       in make_reader(f).iter_messages(topics=["/battery"])
                       if m.log_time == round(LOOK * 1e9))
    message = bus.store.deserialize_cdr(memory.messages["/battery"][round(LOOK * 1e9)],
                                        memory.types["/battery"])
    out["ros2"] = message.battery_voltage
    out["ros2_type"] = memory.types["/battery"]
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
