"""Contract tests over the tables (`commands.py`, `signals.py`): every command behaves the same
from Python, a scenario's script and HTTP; every signal reads the same in every front end at
the same simulated time."""

import concurrent.futures
import copy
import math

import numpy as np
import pytest
from fastapi.testclient import TestClient
from test_recording import read_mcap

from corobot_drake import commands, signals
from corobot_drake.config.scenario import load_scenario
from corobot_drake.model import dimensions as dim
from corobot_drake.recording.mcap_log import McapLog
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.serving import snapshots
from corobot_drake.serving.webapp import create_app
from corobot_drake.simulation import Simulation, quiet_drake_warnings
from corobot_drake.systems.runlog import COLUMNS, HELD_PERIOD

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


class StepRunner:
    """The `serving.runner.Runner` the routes use, over a simulation the test advances itself:
    a submitted call runs at once, at the simulation's current time (as `SimRunner` runs it
    between steps), so an HTTP command is issued at a time the test knows."""

    def __init__(self, sim: Simulation):
        self.sim = sim
        self.robots = {n: snapshots.RobotInfo.of(r) for n, r in sim.robots.items()}
        self.alive, self.meshcat_url = True, None

    @property
    def snapshot(self) -> dict:
        return snapshots.snapshot(self.sim)

    def submit(self, fn):
        future = concurrent.futures.Future()
        try:
            future.set_result(fn(self.sim))
        except Exception as e:  # the routes answer it (422, ...)
            future.set_exception(e)
        return future

    def watch(self, fn):
        return self.submit(fn)

    def stats(self) -> dict:
        return {"time": self.sim.time}


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
    top_speed = dim.MAX_AXLE_SPEED * dim.WHEEL_RADIUS  # m/s
    # Over a lag of one control period the robot moves at most top speed x lag; the curve
    # then carries a heading error of top yaw rate x lag (both sides at top speed opposite).
    assert math.dist((script["pose"].x, script["pose"].y),
                     (python["pose"].x, python["pose"].y)) <= top_speed * SCRIPT_LAG
    assert abs(script["pose"].yaw - python["pose"].yaw) <= (
        2 * top_speed / dim.TRACK * SCRIPT_LAG)


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


@pytest.fixture(scope="module")
def looked(tmp_path_factory):
    """A curve logged to MCAP; at each of `LOOKS`: the live signals, the summary and the HTTP
    snapshot. Returns (simulation, {time: (live, summary, snapshot)}, MCAP topics)."""
    path = tmp_path_factory.mktemp("tables") / "run.mcap"
    looks = {}
    with McapLog(path) as log:
        scenario = load_scenario(DEFAULT_SCENARIO, overrides=[CURVE])
        scenario.robots[ROBOT].cameras["front"].rgb = False
        sim = Simulation(scenario, foxglove=log.context)
        for t in LOOKS:
            sim.advance_to(t)
            robot = sim.robot(ROBOT)
            live = {s.name: robot.signal(s.name) for s in signals.SIGNALS.values() if s.port}
            looks[t] = (live, robot.summary(), snapshots.robot_snapshot(robot, sim.time))
        sim.advance_to(LOOKS[-1] + 2 * HELD_PERIOD)
    return sim, looks, read_mcap(path)


def _at(messages: list, t: float):
    (message,) = [m for when, _, m in messages if math.isclose(when, t, abs_tol=1e-9)]
    return message


def _row(rows: np.ndarray, t: float) -> dict:
    (row,) = rows[np.isclose(rows[:, 0], t, atol=1e-9)]
    return dict(zip(COLUMNS, row, strict=True))


def test_telemetry_reads_the_same_in_every_front_end(looked):
    """Each telemetry signal, read live at a look, is the summary's value at its key and the
    HTTP state's (per wheel or drive state, at its field). The recorded front ends agree with
    each other: a held (costly) signal's MCAP sample stamped t is the run log's row half a
    held period later (both hold the sample taken at t, from the plant's latest step); a
    signal read every step is the live value in both."""
    sim, looks, topics = looked
    rows = sim.robot(ROBOT).run_log()
    for t, (live, summary, snapshot) in looks.items():
        drive = snapshot["drive"]
        for spec in signals.TELEMETRY:
            value = live[spec.name]
            assert signals.get(summary, spec.summary) == spec.summary_value(value), spec.name
            message = _at(topics[f"/{spec.topic}"], t)
            row = _row(rows, t + (HELD_PERIOD / 2 if spec.costly else 0.0))
            if spec.per_wheel:
                assert {w: drive["wheels"][w][spec.field] for w in dim.WHEEL_NAMES} == value
                recorded = {w: message["wheels"][w][spec.field] for w in dim.WHEEL_NAMES}
                assert dict(zip(dim.WHEEL_NAMES, (row[c] for c in spec.log),
                                strict=True)) == recorded, spec.name
            else:
                assert drive[spec.field] == message[spec.field] == row[spec.log[0]] == value
            if not spec.costly:
                assert message[spec.field] == value, spec.name
        # They moved: a curve's slip is not that of a robot at rest.
        assert live["wheel_slip_ratio"]["front_left"] > 0


def test_state_signals_read_the_same_in_every_front_end(looked):
    """The state signals' hand-written front ends agree with the live reading at a look: the
    summary, the HTTP state, the run log's row (logged at that instant) and MCAP's topics."""
    sim, looks, topics = looked
    rows = sim.robot(ROBOT).run_log()
    checked = set()
    for t, (live, summary, snapshot) in looks.items():
        drive, row = snapshot["drive"], _row(rows, t)
        pose = summary["pose"]
        assert drive["pose"] == pose and drive["velocity"] == summary["velocity"]
        assert (row["x"], row["y"]) == (pose["x"], pose["y"])
        assert row["yaw"] == pytest.approx(pose["yaw"], abs=1e-12)  # (-pi, pi]: the same
        odom = _at(topics["/odom"], t)
        assert (odom.pose.position.x, odom.pose.position.y) == (pose["x"], pose["y"])
        checked |= {"pose", "velocity"}
        heading = live["heading"]
        assert summary["heading"] == drive["heading"] == heading
        # the run log makes its yaw from the logged quaternion when read: the same angle, its
        # own rounding
        assert row["yaw"] == pytest.approx(heading, abs=1e-12)
        position = live["position"]
        assert summary["position"] == list(drive["position"].values()) == position == [
            pose["x"], pose["y"], pose["z"]]
        checked |= {"heading", "position"}
        axles = live["axle_speeds"]
        assert summary["wheels"] == axles == {
            w: drive["wheels"][w]["axle_speed"] for w in dim.WHEEL_NAMES}
        state = _at(topics["/drive_state"], t)
        assert {w: state["wheels"][w]["axle_speed"] for w in dim.WHEEL_NAMES} == axles
        assert state["heading"] == heading and state["position"] == position
        ticks = summary["encoders"]
        assert (row["left_ticks"], row["right_ticks"]) == (ticks["front_left"],
                                                           ticks["front_right"])
        assert ticks == {w: drive["wheels"][w]["encoder_ticks"] for w in ticks}
        assert (row["left_power"], row["right_power"]) == (
            drive["wheels"]["front_left"]["commanded_power"],
            drive["wheels"]["front_right"]["commanded_power"])
        checked |= {"axle_speeds", "encoders", "commanded_power"}
        assert list(summary["odometry"].values()) == live["odometry"]
        assert summary["ir"] == {n[:-3]: s["raw"] for n, s in snapshot["ir"].items()}
        checked |= {"odometry", "ir_distances"}
    assert checked == {s.name for s in signals.STATE}  # a new state signal needs its check
