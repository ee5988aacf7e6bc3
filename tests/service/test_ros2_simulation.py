"""The ROS 2 Simulation Interfaces: the `simulation_interfaces` package built from its public
definitions (its type hashes rosidl's own), the runner's pause and steps alone, and the node's
services and action from another process in a private network (`ros2_probe`), as a ROS RL
loop drives them: step, observe, step again; reset; the same trajectory every time."""

import ctypes
import hashlib
import json
import math
import sys
import threading
import time
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="the [ros2] extra (tools/setup installs it)")
pytest.importorskip("simulation_interfaces.msg", reason="python -m corobot_drake.ros2.build")

from corobot_drake.ros2.build import INTERFACES_DIR
from corobot_drake.serving.runner import MAX_RATE, SimRunner, StepJob

SOURCES = INTERFACES_DIR / "simulation_interfaces"
UPSTREAM_DIGEST = "3379e49d8eae325ad4c4df5a8b37a307956bb1b1685e166c49bf225160112379"
"""sha256 over the msg/srv/action files (sorted path, then bytes) of ros-simulation/
simulation_interfaces at tag 2.1.0 (commit 172a1b1c1b3c): the sources are its, unchanged."""
DEPENDENCIES = ("builtin_interfaces", "std_msgs", "geometry_msgs", "action_msgs",
                "service_msgs", "unique_identifier_msgs")


# --- the package -----------------------------------------------------------------------------


def _interface_files() -> list[Path]:
    return sorted(p for d in ("msg", "srv", "action") for p in (SOURCES / d).glob("*"))


def test_sources_are_the_upstream_release():
    digest = hashlib.sha256()
    for path in _interface_files():
        digest.update(str(path.relative_to(SOURCES)).encode())
        digest.update(path.read_bytes())
    assert digest.hexdigest() == UPSTREAM_DIGEST
    assert len(_interface_files()) == 15 + 22 + 1


def official_hashes(tmp_path: Path) -> dict[str, str]:
    """Every type's RIHS01 hash as rosidl computes it from the interface files: its adapter
    (.msg/.srv/.action to .idl) and its type-description generator, the installed
    dependencies' descriptions included."""
    from rosidl_adapter import convert_to_idl
    from rosidl_generator_type_description import generate_type_hash

    share = Path(sys.prefix) / "share"
    idl_dir = tmp_path / "idl"
    tuples = [f"{idl_dir}:{convert_to_idl(SOURCES, 'simulation_interfaces', p.relative_to(SOURCES), idl_dir).relative_to(idl_dir)}"  # noqa: E501
              for p in _interface_files()]
    arguments = tmp_path / "arguments.json"
    arguments.write_text(json.dumps({
        "package_name": "simulation_interfaces", "output_dir": str(tmp_path / "json"),
        "idl_tuples": tuples, "include_paths": [f"{d}:{share / d}" for d in DEPENDENCIES]}))
    hashes = {}
    for path in generate_type_hash(str(arguments)):
        for entry in json.loads(Path(path).read_text())["type_hashes"]:
            hashes[entry["type_name"]] = entry["hash_string"]
    return hashes


class _TypeHash(ctypes.Structure):
    _fields_ = [("version", ctypes.c_uint8), ("value", ctypes.c_uint8 * 32)]


def runtime_hash(cls, kind: str) -> str:
    """The RIHS01 hash the built package's C type support reports for a message, service or
    action class (its `get_type_hash_func`: the field after three pointers in a message's
    type support struct, after eight in a service's, after five in an action's)."""
    type(cls).__import_type_support__()
    capsule = ctypes.py_object(cls._TYPE_SUPPORT)
    get_pointer = ctypes.pythonapi.PyCapsule_GetPointer
    get_pointer.restype, get_pointer.argtypes = ctypes.c_void_p, [ctypes.py_object,
                                                                  ctypes.c_char_p]
    name = ctypes.pythonapi.PyCapsule_GetName
    name.restype, name.argtypes = ctypes.c_char_p, [ctypes.py_object]
    support = get_pointer(capsule, name(capsule))
    slot = {"msg": 3, "srv": 8, "action": 5}[kind]
    function = ctypes.cast(support + slot * ctypes.sizeof(ctypes.c_void_p),
                           ctypes.POINTER(ctypes.c_void_p))[0]
    get = ctypes.CFUNCTYPE(ctypes.POINTER(_TypeHash), ctypes.c_void_p)(function)
    h = get(support).contents
    assert h.version == 1
    return "RIHS01_" + bytes(h.value).hex()


def test_built_type_hashes_are_the_official_ones(tmp_path):
    import importlib

    official = official_hashes(tmp_path)
    checked = 0
    for path in _interface_files():
        kind = path.parent.name
        cls = getattr(importlib.import_module(f"simulation_interfaces.{kind}"), path.stem)
        name = f"simulation_interfaces/{kind}/{path.stem}"
        assert runtime_hash(cls, kind) == official[name], name
        checked += 1
        if kind == "srv":  # a request and a response are messages of their own
            for part in ("Request", "Response"):
                assert runtime_hash(getattr(cls, part), "msg") == official[f"{name}_{part}"]
    assert checked == 38


# --- the runner alone ------------------------------------------------------------------------


class _Clock:
    """A Simulation as the runner sees it: time, a 10 ms physics step, advance_to."""

    physics_step = 0.01

    def __init__(self):
        self.time, self.stops, self.robots = 0.0, [], {}

    def stop_time(self, t):
        return t

    def on_step(self, t):
        k = round(t / self.physics_step)
        return k * self.physics_step if abs(t / self.physics_step - k) < 1e-6 else t

    def advance_to(self, t):
        self.stops.append(t)
        self.time = t


@pytest.fixture
def runner(monkeypatch):
    monkeypatch.setattr("corobot_drake.serving.runner.snapshot", lambda sim: {"time": sim.time})
    made = []

    def make(**kwargs):
        r = SimRunner(_Clock(), **kwargs).start()
        made.append(r)
        return r
    yield make
    for r in made:
        r.stop()


def test_paused_runner_takes_exactly_the_steps_asked(runner):
    r = runner(paused=True)
    time.sleep(0.05)
    assert r.sim.time == 0.0  # paused from the start: no time passes
    job = r.step(StepJob(12))
    assert job.future.result(5) == 12
    assert r.sim.time == 12 * 0.01  # on the physics' grid: k h exactly
    seen = []
    job = r.step(StepJob(3, progress=lambda done, left: seen.append((done, left))))
    assert job.future.result(5) == 3 and seen == [(1, 2), (2, 1), (3, 0)]  # one step each
    time.sleep(0.05)
    assert r.sim.time == 15 * 0.01  # and stays paused


@pytest.mark.realtime  # paced by the wall clock
def test_a_cancelled_job_ends_early_and_a_reset_repaces(runner):
    r = runner(paused=True)
    job = r.step(StepJob(10**6, progress=lambda done, left: done >= 5 and job.cancel()))
    assert 5 <= job.future.result(5) < 10**6
    r.call(lambda sim: setattr(sim, "time", 0.0))  # a reset: back in time
    r.pause(False)  # real time, paced from the reset
    time.sleep(0.2)
    assert 0.1 < r.sim.time < 0.4
    waiting = r.step(StepJob(5))  # steps are taken paused only: cancelled, answered at once
    time.sleep(0.05)
    assert not waiting.future.done()
    waiting.cancel()
    assert waiting.future.result(1) == 0


@pytest.mark.realtime  # paced by the wall clock
def test_max_rate_runs_as_fast_as_it_can(runner):
    r = runner(rate=MAX_RATE)
    time.sleep(0.2)
    assert r.sim.time > 2.0  # 10x real time at least (nothing to compute)


@pytest.mark.realtime  # paced by the wall clock
def test_rate_paces_the_simulated_time(runner):
    r = runner(rate=4.0)
    time.sleep(0.5)
    assert 1.5 < r.sim.time < 2.5  # 4 x 0.5 s (the thread's start and the sleep's slack)


@pytest.mark.parametrize(("argv", "line"), [
    (["--ros2", "--rate", "0"], "error: --rate: must be in (0, 1000]"),
    (["--ros2", "--rate", "fast"], "error: --rate: expected a number or max, got 'fast'"),
])
def test_rate_flags_are_checked_in_one_line(argv, line, capsys):
    """(Without --ros2: tests/unit/test_cli_rate.py.)"""
    from corobot_drake import cli

    assert cli.main(["--headless", *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith(line) and err.count("\n") == 1, err


# --- the node --------------------------------------------------------------------------------

from ros2_probe import ONE_GRAPH_AT_A_TIME, WAIT, ros2_simulation  # noqa: E402

QUIET = "robots: {corobot: {commands: [], cameras: {front: {rgb: false}}}}"
"""The default scene without its camera's frames (rendering is not what is tested)."""
ACTIONS = [(0.3, 0.0), (0.3, 0.8), (0.0, -0.8), (-0.2, 0.0)]
"""The RL loop's actions (linear m/s, angular rad/s), each held for `STEPS_PER_ACTION`."""
STEPS_PER_ACTION = 10
COMMAND_ARRIVAL = 0.3
"""s (wall clock) for a /cmd_vel to reach the paused simulation (~1-7 ms on loopback): a
command taken after the next step would make the trajectories differ, and the test fail."""


@pytest.fixture(scope="module")
def sim_ros():
    from geometry_msgs.msg import Twist
    from simulation_interfaces.srv import GetSimulationState, StepSimulation

    from corobot_drake.serving.client import CorobotClient

    with ros2_simulation(["--headless", "--paused", "--override", QUIET]) as (server, probe):
        probe.call("/get_simulation_state", GetSimulationState, GetSimulationState.Request())
        # A refused step (0) discovers the step service both ways without stepping.
        probe.call("/step_simulation", StepSimulation, StepSimulation.Request(steps=0))
        cmd_vel = probe.publisher("/cmd_vel", Twist)
        deadline = time.monotonic() + 60
        while cmd_vel.get_subscription_count() == 0 and time.monotonic() < deadline:
            time.sleep(0.05)
        probe.fresh = _episode(probe, reset=False)  # the first run, as the node started it
        probe.http = CorobotClient(server.url)  # --serve beside it: the same clock
        yield probe
        probe.http.close()


def _call(probe, service, srv, /, retry=None, **fields):
    return probe.call(f"/{service}", srv, srv.Request(**fields), retry=retry)


def _pose(probe, entity="corobot"):
    from simulation_interfaces.srv import GetEntityState

    response = _call(probe, "get_entity_state", GetEntityState, retry=10.0, entity=entity)
    assert response.result.result == response.result.RESULT_OK, response.result.error_message
    s = response.state
    p, q = s.pose.position, s.pose.orientation
    return (s.header.stamp.sec + 1e-9 * s.header.stamp.nanosec,
            (p.x, p.y, p.z, q.w, q.x, q.y, q.z, s.twist.linear.x, s.twist.angular.z))


def _episode(probe, reset: bool = True) -> list:
    """Reset, then each action: /cmd_vel, wait for it to arrive, step, observe."""
    from geometry_msgs.msg import Twist
    from simulation_interfaces.srv import ResetSimulation, StepSimulation

    if reset:
        done = _call(probe, "reset_simulation", ResetSimulation, retry=10.0)
        assert done.result.result == done.result.RESULT_OK, done.result.error_message
    observations = [_pose(probe)]
    for linear, angular in ACTIONS:
        twist = Twist()
        twist.linear.x, twist.angular.z = linear, angular
        probe.publisher("/cmd_vel", Twist).publish(twist)
        time.sleep(COMMAND_ARRIVAL)
        step = _call(probe, "step_simulation", StepSimulation, steps=STEPS_PER_ACTION)
        assert step.result.result == step.result.RESULT_OK, step.result.error_message
        observations.append(_pose(probe))
    return observations


@ONE_GRAPH_AT_A_TIME
def test_rl_loop_gets_the_same_trajectory_after_every_reset(sim_ros):
    from simulation_interfaces.msg import SimulationState
    from simulation_interfaces.srv import GetSimulationState

    probe = sim_ros
    state = _call(probe, "get_simulation_state", GetSimulationState, retry=10.0)
    assert state.state.state == SimulationState.STATE_PAUSED  # --paused
    first = _episode(probe)
    times = [t for t, _ in first]
    h = 0.01  # the default physics step
    assert times == [pytest.approx(k * STEPS_PER_ACTION * h, abs=1e-9)
                     for k in range(len(ACTIONS) + 1)]
    x0, x1 = first[0][1][0], first[1][1][0]
    assert x1 - x0 > 0.005  # the first action (0.3 m/s) moved it forwards
    assert first == probe.fresh  # the run after a reset is the first run, bit for bit
    assert probe.http.time == times[-1]  # the HTTP server's time is the steps' (paused)
    assert _episode(probe) == first


@ONE_GRAPH_AT_A_TIME
def test_play_pause_stop_and_the_action(sim_ros):
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.action import ActionClient  # noqa: F401 (the probe's)
    from simulation_interfaces.action import SimulateSteps
    from simulation_interfaces.msg import SimulationState
    from simulation_interfaces.srv import SetSimulationState

    probe = sim_ros
    probe.subscribe("/diagnostics", DiagnosticArray)

    def set_state(state):
        return _call(probe, "set_simulation_state", SetSimulationState, retry=10.0,
                     state=SimulationState(state=state)).result

    assert set_state(SimulationState.STATE_PLAYING).result == 1
    t0, _ = _pose(probe)
    time.sleep(0.5)
    t1, _ = _pose(probe)
    assert 0.2 < t1 - t0 < 1.5  # real time, about
    assert set_state(SimulationState.STATE_PAUSED).result == 1
    t2, _ = _pose(probe)
    time.sleep(0.3)
    assert _pose(probe)[0] == t2
    # /diagnostics goes on (a wall-clock timer) and says so, not the factor before the pause
    report = probe.wait_for("/diagnostics", lambda m: m.status[0].message.startswith(
        "paused"), start=probe.count("/diagnostics"))
    assert report.status[0].level == bytes([0])  # OK
    again = set_state(SimulationState.STATE_PAUSED)
    assert again.result == SetSimulationState.Response.ALREADY_IN_TARGET_STATE
    assert set_state(SimulationState.STATE_STOPPED).result == 1
    assert _pose(probe)[0] == 0.0  # stopped: back at the start, paused
    # the action: N steps with feedback after each, then paused
    client = probe.action_client(SimulateSteps, "/simulate_steps")
    feedback = []
    last = threading.Event()

    def fed_back(m):
        feedback.append((m.feedback.completed_steps, m.feedback.remaining_steps))
        if m.feedback.remaining_steps == 0:
            last.set()

    handle = probe.wait_future(client.send_goal_async(SimulateSteps.Goal(steps=7),
                                                      feedback_callback=fed_back))
    assert handle.accepted
    # The last feedback goes out before the result, on a topic of its own. rclpy's client
    # drops a goal's feedback callback once its result arrives, so the result is asked for
    # only after the last feedback is in (waited for, never slept on).
    assert last.wait(WAIT), f"no feedback with no step left: {feedback}"
    assert feedback[-1] == (7, 0) and len(feedback) >= 2
    done = probe.wait_future(handle.get_result_async())
    assert done.result.result.result == 1
    assert _pose(probe)[0] == pytest.approx(0.07, abs=1e-9)
    # cancelled: stops, paused, fewer steps
    handle = probe.wait_future(client.send_goal_async(SimulateSteps.Goal(steps=100_000)))
    # the node's clock is the simulation's: the goal is stamped at its simulated time (the
    # last /clock, 10 ms apart, the node had taken when it accepted it), not the wall clock's
    stamp = handle.stamp.sec + 1e-9 * handle.stamp.nanosec
    assert 0.07 - 0.01 - 1e-9 <= stamp <= 0.07 + 1e-9, stamp
    time.sleep(0.3)
    probe.wait_future(handle.cancel_goal_async())
    probe.wait_future(handle.get_result_async())
    t = _pose(probe)[0]
    assert 0.07 < t < 1000.0
    time.sleep(0.2)
    assert _pose(probe)[0] == t
    # a goal of 0 or 10^12 steps is rejected when sent
    for steps in (0, 10**12):
        assert not probe.wait_future(client.send_goal_async(SimulateSteps.Goal(
            steps=steps))).accepted


@ONE_GRAPH_AT_A_TIME
def test_bad_requests_get_their_codes_and_one_line(sim_ros, tmp_path):
    """The hostile corpus's requests (`hostile_inputs.ros_requests`), then poses a robot
    cannot start at; the node keeps serving."""
    import simulation_interfaces.srv as srvs
    from geometry_msgs.msg import PoseStamped
    from simulation_interfaces.msg import Resource, Result
    from simulation_interfaces.srv import GetSimulatorFeatures, SpawnEntity

    from lab.hostile_inputs import ros_requests

    probe = sim_ros

    def check(response, code, words):
        r = response.result
        assert r.result == code and words in r.error_message and "\n" not in r.error_message, r

    for case in ros_requests():
        for name, text in case.files:
            (tmp_path / name).write_text(text)
        srv = getattr(srvs, case.srv)
        code = getattr(srv.Response, case.code, None)
        request = _message(srv.Request, case.fields, str(tmp_path))
        answer = probe.call(f"/{case.service}", srv, request, retry=10.0)
        check(answer, getattr(Result, case.code) if code is None else code,
              case.words.replace("{dir}", str(tmp_path)))
    tilted = PoseStamped()
    tilted.pose.position.y, tilted.pose.orientation.w = 1.0, 0.0
    tilted.pose.orientation.x = 1.0  # upside down
    origin = PoseStamped()
    origin.pose.orientation.w = 1.0  # where the Corobot is
    for pose, words in ((tilted, "initial_pose.pose.orientation: a robot stands on the ground"),
                        (origin, "initial_pose: robot 'b' starts ")):
        check(_call(probe, "spawn_entity", SpawnEntity, retry=10.0, name="b", initial_pose=pose,
                    entity_resource=Resource(uri="burger")), SpawnEntity.Response.INVALID_POSE,
              words)
    # still serving
    features = _call(probe, "get_simulator_features", GetSimulatorFeatures, retry=10.0)
    assert features.features.spawn_formats == ["yaml", "sdf", "urdf", "mjcf"]
    assert "robots (a robot file's uri" in features.features.custom_info


def _message(cls, fields: dict, directory: str):
    """A `cls` message of `fields` (nested dicts for its messages; `{dir}` in a string:
    `directory`)."""
    msg = cls()
    for name, value in fields.items():
        if isinstance(value, dict):
            value = _message(type(getattr(msg, name)), value, directory)
        elif isinstance(value, str):
            value = value.replace("{dir}", directory)
        setattr(msg, name, value)
    return msg


@ONE_GRAPH_AT_A_TIME
def test_spawn_then_delete_then_reset(sim_ros):
    from geometry_msgs.msg import PoseStamped
    from simulation_interfaces.msg import EntityCategory
    from simulation_interfaces.srv import (
        DeleteEntity,
        GetEntities,
        GetEntityInfo,
        GetSpawnables,
        ResetSimulation,
        SpawnEntity,
        StepSimulation,
    )

    probe = sim_ros
    spawnables = _call(probe, "get_spawnables", GetSpawnables, retry=10.0).spawnables
    box = next(s for s in spawnables if "!Box" in s.entity_resource.resource_string)
    at = PoseStamped()
    at.pose.position.x, at.pose.position.z, at.pose.orientation.w = 1.0, 0.15, 1.0
    spawned = _call(probe, "spawn_entity", SpawnEntity, name="crate", initial_pose=at,
                    entity_resource=box.entity_resource)
    assert spawned.result.result == 1, spawned.result.error_message
    assert spawned.entity_name == "crate"
    entities = _call(probe, "get_entities", GetEntities, retry=10.0).entities
    assert "crate" in entities and "corobot" in entities and "giant_box" in entities
    info = _call(probe, "get_entity_info", GetEntityInfo, retry=10.0, entity="crate")
    assert info.info.category.category == EntityCategory.CATEGORY_OBJECT  # a free box
    _call(probe, "step_simulation", StepSimulation, steps=20)
    _, crate = _pose(probe, "crate")
    assert crate[0] == pytest.approx(1.0, abs=1e-3) and crate[2] < 0.15  # fell onto the ground
    deleted = _call(probe, "delete_entity", DeleteEntity, entity="crate")
    assert deleted.result.result == 1, deleted.result.error_message
    assert "crate" not in _call(probe, "get_entities", GetEntities, retry=10.0).entities
    reset = _call(probe, "reset_simulation", ResetSimulation, retry=10.0)
    assert reset.result.result == 1 and _pose(probe)[0] == 0.0
    # the simulation rebuilt from the scenario the node started with: its first run again
    assert _episode(probe, reset=False) == probe.fresh


def _graph_has(probe, topic: str, publishers: bool = True) -> bool:
    """Whether the node publishes `topic` (or, not `publishers`, subscribes to it), as the
    probe's graph sees it now."""
    infos = (probe.node.get_publishers_info_by_topic(topic) if publishers
             else probe.node.get_subscriptions_info_by_topic(topic))
    return any(i.node_name == "corobot_drake" for i in infos)


def _robot_services(probe, robot: str) -> set[str]:
    """The node's services under /<robot>/ (an action's are `<action>/_action/...`)."""
    served = probe.node.get_service_names_and_types_by_node("corobot_drake", "/")
    return {name for name, _ in served if name.startswith(f"/{robot}/")}


def _eventually(check, what: str) -> None:
    """Waits for `check()` (the probe's graph learns of a change within a few ms to s)."""
    deadline = time.monotonic() + WAIT
    while not check():
        assert time.monotonic() < deadline, what
        time.sleep(0.05)


def _await_graph(probe, topic: str, present: bool, publishers: bool = True) -> None:
    _eventually(lambda: _graph_has(probe, topic, publishers) == present,
                f"{topic}: still {'absent' if present else 'there'}")


def _drive_until_odometry_moves(probe, robot: str) -> tuple:
    """/<robot>/cmd_vel forwards, 10 steps at a time, until /<robot>/odom has moved 5 cm (a
    paused node publishes as it steps; its first steps may pass before it has discovered the
    probe's subscription): (the first odometry, the last)."""
    from geometry_msgs.msg import Twist
    from simulation_interfaces.srv import StepSimulation

    forward = Twist()
    forward.linear.x = 0.2  # m/s: the Burger's top speed is 0.22
    cmd_vel = probe.publisher(f"/{robot}/cmd_vel", Twist)
    for _ in range(100):  # at most 10 s of simulated time
        cmd_vel.publish(forward)
        time.sleep(0.05)  # (it arrives in ~1-7 ms on loopback)
        _call(probe, "step_simulation", StepSimulation, steps=10)
        seen = probe.messages[f"/{robot}/odom"]
        if seen and seen[-1].pose.pose.position.x - seen[0].pose.pose.position.x > 0.05:
            return seen[0], seen[-1]
    raise AssertionError(f"/{robot}/odom did not move: {len(seen)} messages")


@ONE_GRAPH_AT_A_TIME
def test_a_spawned_robot_has_its_topics_under_its_name_until_deleted(sim_ros):
    from action_msgs.msg import GoalStatus
    from corobot_interfaces.action import DriveDistance
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import Odometry
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from simulation_interfaces.msg import EntityCategory, Resource
    from simulation_interfaces.srv import (
        DeleteEntity,
        GetEntities,
        GetEntityInfo,
        GetSpawnables,
        ResetSimulation,
        SpawnEntity,
    )

    probe = sim_ros
    spawnables = _call(probe, "get_spawnables", GetSpawnables, retry=10.0).spawnables
    robots = [s for s in spawnables if s.description.startswith("robot ")]
    assert [s.entity_resource.uri for s in robots] == ["corobot", "burger", "pioneer"]
    assert "TurtleBot3 Burger class" in robots[1].description
    at = PoseStamped()  # beside the Corobot, facing +x as it does
    at.pose.position.y, at.pose.orientation.w = 1.0, 1.0
    before = _pose(probe)
    spawned = _call(probe, "spawn_entity", SpawnEntity, name="burger", initial_pose=at,
                    entity_resource=Resource(uri="burger"))
    assert spawned.result.result == 1, spawned.result.error_message
    assert spawned.entity_name == "burger"
    after = _pose(probe)  # the simulation goes on from where it was
    assert after[0] == before[0] and after[1] == pytest.approx(before[1], abs=1e-9)
    assert probe.http.time == after[0]  # --serve's HTTP state follows the rebuilt simulation
    _served_over_http(probe)
    assert "burger" in _call(probe, "get_entities", GetEntities, retry=10.0).entities
    info = _call(probe, "get_entity_info", GetEntityInfo, retry=10.0, entity="burger")
    assert info.info.category.category == EntityCategory.CATEGORY_ROBOT
    # the Corobot keeps its bare names; the Burger's are under its name
    _await_graph(probe, "/burger/cmd_vel", True, publishers=False)
    _await_graph(probe, "/burger/odom", True)
    assert _graph_has(probe, "/odom") and _graph_has(probe, "/cmd_vel", publishers=False)
    assert not _graph_has(probe, "/corobot/odom")
    served = {"/burger/set_pose", "/burger/all_stop", "/burger/enable_drive",
              "/burger/drive_distance/_action/send_goal",
              "/burger/rotate_degrees/_action/send_goal"}
    _eventually(lambda: served <= _robot_services(probe, "burger"), "the Burger's services")
    drive = probe.action_client(DriveDistance, "/burger/drive_distance")  # (before it is used)
    probe.subscribe("/burger/odom", Odometry,
                    QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))
    first, last = _drive_until_odometry_moves(probe, "burger")
    assert (first.header.frame_id, first.child_frame_id) == ("burger/odom", "burger/base_link")
    assert first.pose.pose.position.y == pytest.approx(1.0, abs=0.01)  # from its true start
    _, (x, y, *_) = _pose(probe, "burger")
    assert x == pytest.approx(last.pose.pose.position.x, abs=0.02) and x > 0.05
    assert y == pytest.approx(1.0, abs=0.02)
    # a goal under way when its robot is deleted (paused: it waits for steps) is aborted
    goal = probe.wait_future(drive.send_goal_async(DriveDistance.Goal(distance=1.0, power=0.5)))
    assert goal.accepted
    result = goal.get_result_async()  # asked while its server is there
    deleted = _call(probe, "delete_entity", DeleteEntity, entity="burger")
    assert deleted.result.result == 1, deleted.result.error_message
    ended = probe.wait_future(result)
    assert ended.status == GoalStatus.STATUS_ABORTED and not ended.result.success
    assert "burger" in ended.result.reason, ended.result.reason
    assert "burger" not in _call(probe, "get_entities", GetEntities, retry=10.0).entities
    _await_graph(probe, "/burger/odom", False)
    _await_graph(probe, "/burger/cmd_vel", False, publishers=False)
    assert _graph_has(probe, "/odom") and _graph_has(probe, "/cmd_vel", publishers=False)
    _eventually(lambda: not _robot_services(probe, "burger"), "the Burger's services left")
    _gone_over_http(probe, "burger")
    # spawned again, then a reset: back to the scenario's start, the Burger gone
    again = _call(probe, "spawn_entity", SpawnEntity, name="", allow_renaming=True,
                  initial_pose=at, entity_resource=Resource(uri="burger"))
    assert (again.result.result, again.entity_name) == (1, "burger_1"), again.result
    _await_graph(probe, "/burger_1/odom", True)
    reset = _call(probe, "reset_simulation", ResetSimulation, retry=10.0)
    assert reset.result.result == 1 and _pose(probe)[0] == 0.0
    assert _call(probe, "get_entities", GetEntities, retry=10.0).entities[0] == "corobot"
    assert "burger_1" not in _call(probe, "get_entities", GetEntities, retry=10.0).entities
    _await_graph(probe, "/burger_1/odom", False)
    _await_graph(probe, "/burger_1/cmd_vel", False, publishers=False)
    _gone_over_http(probe, "burger_1")


def _served_over_http(probe) -> None:
    """The spawned Burger on --serve's HTTP server: listed, its state and sensors served,
    driven by a SetVelocity over HTTP (0.2 m/s for 50 steps of 10 ms), then stopped."""
    from simulation_interfaces.srv import StepSimulation

    http = probe.http
    _eventually(lambda: list(http.robots) == ["corobot", "burger"], "GET /robots")
    burger = http.robot("burger")
    x0, y0, _ = burger.position()
    assert y0 == pytest.approx(1.0, abs=0.01)
    assert list(burger.sensor_readings()["lidars"]) == ["scan"]
    burger.set_velocity(0.2, 0.0)
    t = http.time + 0.5
    step = _call(probe, "step_simulation", StepSimulation, steps=50)
    assert step.result.result == step.result.RESULT_OK, step.result.error_message
    _eventually(lambda: http.time >= t - 1e-9, "no snapshot of the steps")
    drive = burger.drive_state()
    # measured alone (the runner's replace test): 0.079 m, 0.198 m/s
    assert 0.06 < drive["position"]["x"] - x0 < 0.1
    assert drive["velocity"]["forward"] == pytest.approx(0.2, rel=0.02)
    burger.all_stop()


def _gone_over_http(probe, robot: str) -> None:
    """A deleted robot left --serve's HTTP server: not listed, its routes answer 404 with the
    one line naming it and the robots there."""
    import httpx

    _eventually(lambda: robot not in probe.http.robots, f"GET /robots still lists {robot}")
    line = f"no robot named {robot!r}; robots: corobot"
    base = f"/robots/{robot}"
    with httpx.Client(base_url=probe.http.url, timeout=30) as http:
        for path in (base, f"{base}/drive", f"{base}/gps", f"{base}/sensors"):
            r = http.get(path)
            assert (r.status_code, r.json()) == (404, {"detail": line}), path
        r = http.post(f"{base}/drive/set_velocity", json={"linear": 0.2, "angular": 0.0})
        assert (r.status_code, r.json()) == (404, {"detail": line})


CRATE_SDF = """<?xml version="1.0"?>
<sdf version="1.9"><model name="crate"><link name="body">
  <inertial><mass>2.0</mass><inertia><ixx>0.01</ixx><iyy>0.01</iyy><izz>0.01</izz></inertia>
  </inertial>
  <collision name="c"><geometry><box><size>0.2 0.2 0.2</size></box></geometry></collision>
  <visual name="v"><geometry><box><size>0.2 0.2 0.2</size></box></geometry></visual>
</link></model></sdf>
"""


WALL_URDF = """<?xml version="1.0"?>
<robot name="wall"><link name="slab">
  <collision><geometry><box size="2.0 0.1 0.5"/></geometry></collision>
  <visual><geometry><box size="2.0 0.1 0.5"/></geometry></visual>
</link></robot>
"""


@ONE_GRAPH_AT_A_TIME
def test_model_files_spawn_free_or_fixed(sim_ros, tmp_path):
    from geometry_msgs.msg import PoseStamped
    from simulation_interfaces.msg import EntityCategory, Resource
    from simulation_interfaces.srv import (
        DeleteEntity,
        GetEntities,
        GetEntityInfo,
        GetSpawnables,
        SpawnEntity,
        StepSimulation,
    )

    probe = sim_ros
    crate = tmp_path / "crate.sdf"
    crate.write_text(CRATE_SDF)
    at = PoseStamped()
    at.pose.position.x, at.pose.position.y, at.pose.position.z = 1.5, 1.0, 0.3
    at.pose.orientation.w = 1.0
    spawned = _call(probe, "spawn_entity", SpawnEntity, name="crate", initial_pose=at,
                    entity_resource=Resource(uri=str(crate)))
    assert spawned.result.result == 1, spawned.result.error_message
    assert spawned.entity_name == "crate::body"
    _call(probe, "step_simulation", StepSimulation, steps=30)
    _, state = _pose(probe, "crate::body")
    assert state[:2] == pytest.approx((1.5, 1.0), abs=1e-3) and 0.09 < state[2] < 0.11  # landed
    deleted = _call(probe, "delete_entity", DeleteEntity, entity="crate::body")
    assert deleted.result.result == 1, deleted.result.error_message
    # a model without mass (a URDF link without inertial): fixed where it is put
    wall = tmp_path / "wall.urdf"
    wall.write_text(WALL_URDF)
    at.pose.position.x, at.pose.position.z = 20.0, 0.25
    spawned = _call(probe, "spawn_entity", SpawnEntity, name="wall", initial_pose=at,
                    entity_resource=Resource(uri=f"file://{wall}"))
    assert spawned.result.result == 1, spawned.result.error_message
    info = _call(probe, "get_entity_info", GetEntityInfo, retry=10.0, entity=spawned.entity_name)
    assert info.info.category.category == EntityCategory.CATEGORY_STATIC_OBJECT
    entities = _call(probe, "get_entities", GetEntities, retry=10.0).entities
    assert "wall::slab" in entities and "crate::body" not in entities
    _call(probe, "step_simulation", StepSimulation, steps=10)
    assert _pose(probe, "wall::slab")[1][:3] == pytest.approx((20.0, 1.0, 0.25), abs=1e-12)
    # GetSpawnables lists no shipped model file, and says why
    listed = _call(probe, "get_spawnables", GetSpawnables, retry=10.0)
    assert not [s for s in listed.spawnables if s.entity_resource.uri.endswith(".sdf")]
    assert listed.result.error_message.startswith("no shipped model file is listed: the maze")


@ONE_GRAPH_AT_A_TIME
def test_set_entity_state_teleports_a_robot_and_moves_a_body(sim_ros):
    from geometry_msgs.msg import Pose
    from simulation_interfaces.msg import EntityState
    from simulation_interfaces.srv import ResetSimulation, SetEntityState, StepSimulation

    probe = sim_ros
    _call(probe, "reset_simulation", ResetSimulation, retry=10.0)
    pose = Pose()
    yaw = math.radians(30)
    pose.position.x, pose.position.y = 0.5, 0.3
    pose.orientation.w, pose.orientation.z = math.cos(yaw / 2), math.sin(yaw / 2)
    moved = _call(probe, "set_entity_state", SetEntityState, entity="corobot",
                  state=EntityState(pose=pose), set_pose=True)
    assert moved.result.result == 1, moved.result.error_message  # paused: at once
    _call(probe, "step_simulation", StepSimulation, steps=40)  # settles (0.25 s)
    _, (x, y, _, w, _, _, z, *_) = _pose(probe)
    assert (x, y) == pytest.approx((0.5, 0.3), abs=0.01)
    assert 2 * math.atan2(z, w) == pytest.approx(yaw, abs=0.01)
    box = Pose()  # the giant box, lifted and spun: at once, exactly
    box.position.x, box.position.z, box.orientation.w = -3.0, 2.0, 1.0
    state = EntityState(pose=box)
    state.twist.angular.z = 1.0
    moved = _call(probe, "set_entity_state", SetEntityState, entity="giant_box", state=state,
                  set_pose=True, set_twist=True)
    assert moved.result.result == 1, moved.result.error_message
    _, (bx, by, bz, *_, spin) = _pose(probe, "giant_box")
    assert (bx, by, bz, spin) == (-3.0, 0.0, 2.0, 1.0)
    tilted = Pose()
    tilted.orientation.w, tilted.orientation.x = 0.0, 1.0  # upside down: it stands on the ground
    refused = _call(probe, "set_entity_state", SetEntityState, entity="corobot",
                    state=EntityState(pose=tilted), set_pose=True)
    assert refused.result.result == SetEntityState.Response.INVALID_POSE
    assert "only a yaw" in refused.result.error_message
    _call(probe, "reset_simulation", ResetSimulation, retry=10.0)
