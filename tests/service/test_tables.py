"""Contract tests over the tables (`commands.py`, `signals.py`): every command behaves the same
from Python, a scenario's script and HTTP; every signal reads the same in every front end at
the same simulated time."""

import copy
import functools
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient
from step_runner import StepRunner
from test_recording import read_mcap

from corobot_drake import commands, signals
from corobot_drake.config.scenario import load_scenario
from corobot_drake.recording.mcap_log import McapLog
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.robots import robot_spec
from corobot_drake.serving import snapshots
from corobot_drake.serving.webapp import create_app
from corobot_drake.simulation import Simulation, quiet_drake_warnings
from corobot_drake.systems.runlog import HELD_PERIOD, MADE_WHEN_READ

quiet_drake_warnings()

ROBOT = "corobot"
SAMPLES = {
    "set_power": {"left": 0.6, "right": 0.3},
    "set_speed": {"left": 0.2, "right": -0.1},
    "set_velocity": {"linear": 0.2, "angular": 0.5},
    "all_stop": {},
    "enable": {"enabled": False},
    "drive_distance": {"distance": 0.05, "power": 0.5},
    "rotate_degrees": {"degrees": 10.0, "power": 0.5},
    "set_pose": {"x": 0.2, "y": -0.1, "yaw_deg": 30.0},
}
"""A valid call of each command the front ends take (each issued while the robot drives)."""
PRELUDE = commands.SetPower(0.4, 0.4)
ISSUE_AT = 0.2
"""s: the sample command is issued then, the prelude (driving) at 0."""
END = 2.5
"""s: the state compared (every completing sample has ended by then)."""


@pytest.fixture(scope="module")
def sim():
    scenario = load_scenario(DEFAULT_SCENARIO)
    for robot in scenario.robots.values():
        robot.cameras["front"].rgb = False
    return Simulation(scenario)


def test_every_command_has_a_sample_and_a_complete_declaration():
    assert set(SAMPLES) == set(commands.BY_METHOD)
    for spec in commands.ISSUABLE:
        assert {a.name for a in spec.args if a.required} <= set(SAMPLES[spec.method])
        for arg in spec.args:  # every number has its range, every argument its description
            assert (arg.range is not None) == (arg.type is float), (spec.name, arg.name)
            assert arg.doc, (spec.name, arg.name)
        assert spec.ros2 is None or (spec.ros2.kind in ("topic", "service", "action")
                                     and spec.ros2.name.startswith("/"))
        # A completing command's ROS 2 interface answers when it has ended: not a topic.
        assert not (spec.completing and spec.ros2 and spec.ros2.kind == "topic"), spec.name


def _end_state(sim: Simulation) -> dict:
    robot = sim.robot(ROBOT)
    log = [(r.command, r.status, r.reason, r.start_time, r.end_time)
           for r in robot.command_log() if r.command != "Wait"]
    return {"time": sim.time, "log": log, "pose": robot.pose(), "axles": robot.axle_speeds(),
            "enabled": robot.is_enabled()}


def _from_python(sim: Simulation, method: str, arguments: dict) -> dict:
    sim.reset()
    robot = sim.robot(ROBOT)
    robot.issue(PRELUDE)
    sim.advance_to(ISSUE_AT)
    robot.command(method, **arguments)
    sim.advance_to(END)
    return _end_state(sim)


def _from_script(sim: Simulation, spec: commands.CommandSpec, arguments: dict) -> dict:
    scenario = copy.deepcopy(sim.scenario)
    scenario.robots[ROBOT].commands = [PRELUDE, commands.Wait(ISSUE_AT),
                                       spec.dataclass(**arguments)]
    original = sim.scenario
    sim.reset(scenario)
    sim.advance_to(END)
    state = _end_state(sim)
    sim.reset(original)
    return state


def _from_http(sim: Simulation, spec: commands.CommandSpec, arguments: dict) -> dict:
    sim.reset()
    with TestClient(create_app(StepRunner(sim)), base_url="http://127.0.0.1") as http:
        base = f"/robots/{ROBOT}/drive"
        prelude = {"left": PRELUDE.left, "right": PRELUDE.right}
        assert http.post(f"{base}/set_power", json=prelude).status_code == 200
        sim.advance_to(ISSUE_AT)
        body = {**arguments, **({"wait": False} if spec.completing else {})}
        answer = http.post(f"{base}/{spec.method}", json=body)
        assert answer.status_code in (200, 202), answer.text
        assert answer.json()["command"] == spec.method
    sim.advance_to(END)
    return _end_state(sim)


SCRIPT_LAG = 0.01
"""s: a scripted command reaches the drive up to one control period (`Drive.control_period`)
after the command log says it started: the command source issues it in the same update
event as the drive controller reads its request, so the controller sees it at its next
update; a command from Python or HTTP, issued between steps, is seen at the update of its
instant when that update has not yet run. (Measured: the samples' end poses differ by up to
~3 mm and 0.005 rad, one control period of driving; the command log's end times by one
control period.)"""


@pytest.fixture(scope="module", params=commands.ISSUABLE, ids=lambda s: s.name)
def runs(sim, request):
    """A sample command issued at `ISSUE_AT` while driving, from each front end: the state at
    `END` (spec, {front end: state})."""
    spec, arguments = request.param, SAMPLES[request.param.method]
    return spec, {"python": _from_python(sim, spec.method, arguments),
                  "script": _from_script(sim, spec, arguments),
                  "http": _from_http(sim, spec, arguments)}


def test_a_command_behaves_the_same_from_python_and_http(runs):
    spec, states = runs
    python = states["python"]
    last = python["log"][-1]
    assert last[0] == spec.name
    if spec.completing:  # it ran to its end (a failure would compare equal too)
        assert last[1] == "succeeded", last
    # The same command handed to the drive at the same simulated time through the same
    # `Robot.command`: the same run, bit for bit (the log, the pose, the axle speeds).
    assert states["http"] == python


def test_a_scripted_command_logs_the_same_and_ends_near(runs):
    """A script's command: the same command log (commands, statuses, reasons, start and end
    times) and an end state within one control period's driving (`SCRIPT_LAG`)."""
    _, states = runs
    python, script = states["python"], states["script"]
    assert [r[:4] for r in script["log"]] == [r[:4] for r in python["log"]]
    assert [r[4] for r in script["log"]] == pytest.approx(
        [r[4] for r in python["log"]], abs=SCRIPT_LAG + 1e-9)
    assert script["enabled"] == python["enabled"]
    spec = robot_spec("corobot")
    top_speed = spec.drive.max_axle_speed * spec.wheel_radius  # m/s
    # Over a lag of one control period the robot moves at most top speed x lag; the curve
    # then carries a heading error of top yaw rate x lag (both sides at top speed opposite).
    assert math.dist((script["pose"].x, script["pose"].y),
                     (python["pose"].x, python["pose"].y)) <= top_speed * SCRIPT_LAG
    assert abs(script["pose"].yaw - python["pose"].yaw) <= (
        2 * top_speed / spec.track * SCRIPT_LAG)


def test_a_bad_argument_is_refused_alike_by_python_and_http(sim):
    """The ranges are the table's: Python's ValueError and HTTP's 422 name the same range."""
    with TestClient(create_app(StepRunner(sim)), base_url="http://127.0.0.1") as http:
        for spec in commands.ISSUABLE:
            for arg in spec.args:
                if arg.range is None:
                    continue
                arguments = {**SAMPLES[spec.method], arg.name: arg.range.high + 1.0}
                with pytest.raises(ValueError, match=rf"{spec.name}\.{arg.name} must be"):
                    sim.robot(ROBOT).command(spec.method, **arguments)
                answer = http.post(f"/robots/{ROBOT}/drive/{spec.method}", json=arguments)
                assert answer.status_code == 422, (spec.name, arg.name)
                assert answer.json()["detail"].startswith(f"{arg.name}: Input should be less")


# --- signals ---------------------------------------------------------------------------------

CURVE = ("robots: {corobot: {commands: [!SetPower {left: 1, right: 0.5}, !Wait {seconds: 0.5},"
         " !AllStop {}]}}")
LOOKS = (0.3, 0.6)
"""s: when the front ends are compared (mid-curve, and braking), on the held samples' times."""
CONVERTED = 1e-12
"""rad, m: a value a front end carries converted (degrees, a quaternion, an angle the run log
makes from the logged quaternion) reads back within this of the live one (float rounding)."""
FLOAT32 = 2.0 ** -24
"""The relative rounding of a value a message holds as a 32-bit float (`|f32`)."""


class Ros2Memory:
    """A ROS 2 bus sink (`ros2.bus`) that keeps every message, decoded by rclpy's type
    support as a subscriber's would be: {topic: {t_ns: message}}."""

    def __init__(self):
        from rclpy.serialization import deserialize_message

        from corobot_drake.ros2.graph import ros_type

        self._decode, self._type = deserialize_message, ros_type
        self.types, self.messages = {}, {}

    def declare(self, topic, msgtype, qos):
        self.types[topic] = msgtype
        self.messages[topic] = {}

    def write(self, topic, data, t_ns):
        self.messages[topic][t_ns] = self._decode(bytes(data), self._type(self.types[topic]))


def _ros2_extras():
    """The ROS 2 topics on a `Ros2Memory` (None without the [ros2] extra and its built
    interfaces)."""
    try:
        import corobot_interfaces.msg  # noqa: F401
        import rclpy  # noqa: F401

        from corobot_drake.ros2.bus import Bus
        from corobot_drake.ros2.publishers import add_ros2_topics
    except ImportError:
        return None, []
    memory = Ros2Memory()
    return memory, [functools.partial(add_ros2_topics, Bus([memory]))]


@pytest.fixture(scope="module")
def looked(tmp_path_factory):
    """One short run (a curve) read by every front end: at each of `LOOKS`, every signal live,
    the summary and the HTTP snapshot; the run log, the MCAP topics and the ROS 2 messages
    after. Returns (simulation, {time: (live, summary, snapshot)}, MCAP topics, ROS 2
    messages or None)."""
    path = tmp_path_factory.mktemp("tables") / "run.mcap"
    looks = {}
    memory, extras = _ros2_extras()
    with McapLog(path) as log:
        scenario = load_scenario(DEFAULT_SCENARIO, overrides=[CURVE])
        scenario.robots[ROBOT].cameras["front"].rgb = False
        sim = Simulation(scenario, foxglove=log.context, extras=extras)
        for t in LOOKS:
            sim.advance_to(t)
            robot = sim.robot(ROBOT)
            live = {s.name: robot.signal(s.name) for s in signals.SIGNALS.values()}
            looks[t] = (live, robot.summary(), snapshots.robot_snapshot(robot, sim.time))
        sim.advance_to(LOOKS[-1] + 2 * HELD_PERIOD)
    return sim, looks, read_mcap(path), memory and memory.messages


def _at(messages: list, t: float):
    (message,) = [m for when, _, m in messages if math.isclose(when, t, abs_tol=1e-9)]
    return message


def _row(rows: np.ndarray, columns: tuple, t: float) -> dict:
    (row,) = rows[np.isclose(rows[:, 0], t, atol=1e-9)]
    return dict(zip(columns, row, strict=True))


def _same(read, expected, place: str, what: str) -> None:
    """`read` is `expected` exactly, or within `CONVERTED` where the front end converts it."""
    if place.endswith(("|f32", "|range")):
        expected = pytest.approx(expected, rel=FLOAT32, abs=0)
    elif "|" in place:
        expected = pytest.approx(expected, abs=CONVERTED)
    assert read == expected, (what, place)


def _keys(value):
    return tuple(value) if isinstance(value, dict) else None


def _stamp(spec: signals.Signal, topic: str, key: str, t: float, snapshot: dict) -> float:
    """The time stamp of the message of `topic` that carries `spec`'s value read at `t`: a
    topic per key (an IR sensor's) carries each reading at its own time (the scan's), a
    costly signal's the sample held at t, any other the look's at t."""
    if "*" in topic:
        return snapshot["ir"][f"{key}_ir"]["time_stamp"]
    return t


def _recorded(spec, value, keys, t, snapshot, topics, ros2) -> list:
    """[(front end, place, value read)] of `spec` in the run log, MCAP and ROS 2 at `t`."""
    out = []
    row = _row(*topics["__rows__"], t + (HELD_PERIOD / 2 if spec.costly else 0.0))
    if spec.log:
        read = {key: row[column] for column, key in spec.log}
        place = "|log" if spec.name in MADE_WHEN_READ else "log"
        out.append(("run log", place, read if keys else read[""],
                    {k: value[k] for k in read} if keys else value))
    per_topic = [("mcap", spec.mcap_places, topics), ("ros2", spec.ros2_places, ros2)]
    for front_end, places, source in per_topic:
        if source is None:
            continue
        for topic, place in places.items():
            for key in (keys if "*" in topic else (None,)):
                name = "/" + signals.topic_name(topic, key or "")
                stamp = _stamp(spec, topic, key, t, snapshot)
                message = (_at(source[name], stamp) if front_end == "mcap"
                           else source[name][round(stamp * 1e9)])
                expected = value[key] if key else value
                read = signals.read_value(message, place, None if key else _keys(expected))
                if isinstance(expected, dict):  # a place may carry some of the keys
                    expected = {k: expected[k] for k in read}
                out.append((f"{front_end} {name}", place, read, expected))
    return out


def test_every_signal_reads_the_same_in_every_front_end(looked):
    """Each signal read live (`Robot.signal`) at a look is, at each of its places in the
    table, the summary's and the HTTP state's value; the recorded front ends (the run log's
    row logged then, the MCAP and ROS 2 messages of that instant) carry it too. A costly
    signal is recorded from the sample held at the look (`HELD_PERIOD`: the row half a held
    period later, the messages stamped with the look), which a command at the look moves
    from the live value: its recorded places agree with each other."""
    sim, looks, topics, ros2 = looked
    robot = sim.robot(ROBOT)
    topics = {**topics, "__rows__": (robot.run_log(), robot.log_columns)}
    carried = {"summary": set(), "http": set(), "log": set(), "mcap": set(), "ros2": set()}
    for t, (live, summary, snapshot) in looks.items():
        for spec in signals.SIGNALS.values():
            value, keys = live[spec.name], _keys(live[spec.name])
            if spec.summary:
                _same(signals.read_value(summary, spec.summary, keys), value, spec.summary,
                      spec.name)
                carried["summary"].add(spec.name)
            for place in spec.http:
                _same(signals.read_value(snapshot, place, keys), value, place, spec.name)
                carried["http"].add(spec.name)
            recorded = _recorded(spec, value, keys, t, snapshot, topics, ros2)
            held = recorded[0][2] if spec.costly else None
            for where, place, read, expected in recorded:
                _same(read, held if spec.costly else expected, place, (spec.name, where))
                carried[where.split()[0].replace("run", "log")].add(spec.name)
        # They moved: a curve's slip is not that of a robot at rest.
        assert live["wheel_slip_ratio"]["front_left"] > 0
    assert carried["summary"] == {s.name for s in signals.SIGNALS.values() if s.summary}
    assert carried["http"] == {s.name for s in signals.SIGNALS.values() if s.http}
    assert carried["log"] == {s.name for s in signals.SIGNALS.values() if s.log}
    assert carried["mcap"] == {s.name for s in signals.SIGNALS.values() if s.mcap_places}
    if ros2 is not None:
        assert carried["ros2"] == {s.name for s in signals.SIGNALS.values() if s.ros2_places}


def test_every_signal_is_carried_by_every_front_end_or_says_why_not():
    """The table's coverage: every signal is in the summary and the HTTP state; all but the
    chassis velocity (in its heading's frame: /odom's twist is in base_link) in ROS 2, all but
    it and the dead reckoning (ROS 2's /wheel_odom) in MCAP; each has its doc and a port or
    a reader; a costly signal is logged (its recorded places are checked against the run
    log's)."""
    for spec in signals.SIGNALS.values():
        assert spec.summary and spec.http, spec.name
        assert spec.doc and (spec.port or spec.reader), spec.name
        assert not spec.costly or spec.log, spec.name
    assert {s.name for s in signals.SIGNALS.values() if not s.ros2_places} == {"velocity"}
    assert {s.name for s in signals.SIGNALS.values() if not s.mcap_places} == {
        "velocity", "odometry"}


def test_a_signal_added_to_the_table_appears_in_every_front_end():
    """One entry in the table and its system's output port (`signal_added.py`, in a process
    of its own: the table is read when the front ends are imported) and the new signal is in
    the summary, the HTTP state (its served JSON too, through the derived response model) and
    its subscriptions' thresholds, the run log (its CSV too), its own MCAP topic and its own
    ROS 2 message (made from the table: no rebuilt interfaces needed for the bus and bags),
    each with the live value."""
    pytest.importorskip("rosbags", reason="the [ros2] extra (tools/setup installs it)")
    script = Path(__file__).with_name("signal_added.py")
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout)
    live = out.pop("live")
    assert live == pytest.approx(12.6 - 0.5 * 0.3, abs=1e-12)  # the system's value at LOOK
    assert out.pop("change_threshold") == 0.01
    header = out.pop("csv_header")  # the signals' columns, then the sensors' (the IR's)
    assert header[header.index("battery"):] == ["battery", "ir_front", "ir_rear"]
    assert out.pop("ros2_type") == "corobot_interfaces/msg/Battery"
    assert out == dict.fromkeys(("summary", "snapshot", "http", "run_log", "mcap", "ros2"),
                                live)
