"""The Python API refuses bad arguments with a ValueError naming the allowed range (never
SystemExit, never a hang), and leaves the simulation as it was; a SetPose into a body fails
`blocked` and leaves the robot where it was."""

import math
import reprlib
import threading

import numpy as np
import pytest

from conftest import CENIC, SAP, make_sim
from corobot_drake.config import scenario as sc


@pytest.fixture(scope="module")
def sim():
    return make_sim()


BAD_CALLS = [
    # (method, args, words the message must contain)
    ("advance", (math.nan,), "seconds must be a finite number >= 0, got nan"),
    ("advance", (-1.0,), "seconds must be a finite number >= 0, got -1.0"),
    ("advance", (math.inf,), "seconds must be a finite number >= 0, got inf"),
    ("advance", ("1",), "seconds must be a finite number"),
    ("advance_to", (math.nan,), "t must be a finite number >="),
    ("advance_to", (-5.0,), "t must be a finite number >="),
    ("run", (math.inf,), "duration must be a finite number >= 0"),
    ("run", (1.0, None, 0.0), "chunk must be a finite number >= 0.0001"),
    ("run", (1.0, None, 1e-300), "chunk must be a finite number >= 0.0001, got 1e-300"),
    ("advance", (10**400,), "seconds must be a finite number >= 0, got 1000"),
    ("set_power", (10**400, 0), "SetPower.left must be a finite number in [-1, 1], got 1000"),
    ("set_power", (0, -10**400), "SetPower.right must be a finite number in [-1, 1], got -1000"),
    ("set_power", (np.array([0.5, 0.5]), 0), "SetPower.left must be a finite number in [-1, "
     "1], got array([0.5, 0.5])"),
    ("set_power", (np.array([0.5]), 0), "got array([0.5])"),  # numpy would make it 0.5
    ("set_speed", ([1.0], 0), "SetSpeed.left must be a finite number in [-5, 5], got [1.0]"),
    ("set_power", (1.5, 0), "SetPower.left must be a finite number in [-1, 1], got 1.5"),
    ("set_power", (0, -2), "SetPower.right must be a finite number in [-1, 1]"),
    ("set_power", (math.nan, 0), "SetPower.left must be a finite number in [-1, 1], got nan"),
    ("set_power", (math.inf, 0), "in [-1, 1], got inf"),
    ("set_power", (True, 0), "in [-1, 1], got True"),
    ("set_speed", (6.0, 0), "SetSpeed.left must be a finite number in [-5, 5], got 6.0"),
    ("set_speed", (0, -math.inf), "SetSpeed.right must be a finite number in [-5, 5]"),
    ("set_velocity", (6.0, 0.0), "SetVelocity.linear must be a finite number in [-5, 5]"),
    ("set_velocity", (0.0, math.nan), "SetVelocity.angular must be a finite number in [-50"),
    ("enable", ("false",), "Enable.enabled must be True or False"),
    ("drive_distance_async", (1.0, 0.0), "DriveDistance.power must be a finite number in (0, 1]"),
    ("drive_distance_async", (1e9,), "DriveDistance.distance must be a finite number in [-100"),
    ("drive_distance_async", (math.nan,), "DriveDistance.distance"),
    ("drive_distance", (0.1, 0.5, -1.0), "timeout must be a number > 0"),
    ("drive_distance", (0.1, 0.5, math.nan), "timeout must be a number > 0"),
    ("rotate_degrees_async", (90, 1.5), "RotateDegrees.power must be a finite number in (0, 1]"),
    ("rotate_degrees_async", (math.inf,), "RotateDegrees.degrees must be a finite number in"),
    ("set_pose", (math.nan, 0.0), "SetPose.x must be a finite number in [-10000, 10000]"),
    ("set_pose", (0.0, 1e6), "SetPose.y must be a finite number in [-10000, 10000]"),
    ("set_pose", (0.0, 0.0, math.inf), "SetPose.yaw_deg must be a finite number"),
    ("issue", ("forward",), "a command must be one of SetPower"),
    ("issue", (sc.Wait(1.0),), "a command must be one of"),
    ("issue", (sc.SetPower(3.0, 0.0),), "SetPower.left must be a finite number in [-1, 1]"),
]


@pytest.mark.parametrize(("method", "args", "words"), BAD_CALLS,
                         ids=[f"{m}{reprlib.repr(a)}" for m, a, _ in BAD_CALLS])
def test_bad_arguments_raise_value_error_and_change_nothing(sim, method, args, words):
    robot = sim.robot()
    target = sim if hasattr(sim, method) else robot
    t0, log0 = sim.time, robot.command_log()
    with pytest.raises(ValueError) as info:  # a ValueError, so not SystemExit
        getattr(target, method)(*args)
    assert words in str(info.value)
    assert sim.time == t0 and robot.command_log() == log0


def test_valid_calls_still_work(sim):
    robot = sim.robot()
    robot.set_power(1, -1)  # ints are numbers; the ends of the range are allowed
    assert robot.command_log()[-1].command == "SetPower"
    robot.set_speed(5.0, -5.0)
    robot.enable(True)
    robot.all_stop()
    sim.advance(0.0)
    sim.run(0.02, chunk=0.01)


def test_numpy_scalars_are_numbers(sim):
    sim.robot().set_power(np.float64(0.25), np.float32(-0.25))
    assert sim.robot().command_log()[-1].command == "SetPower"
    sim.run(0.01, chunk=np.float64(0.005))


def test_a_second_thread_advancing_or_commanding_is_refused_while_one_advances(sim):
    """While one thread is inside `run` (held in its progress call), another's advance,
    command or reset fails at once with one clear line, and the first run carries on."""
    inside, tried = threading.Event(), threading.Event()
    errors: list[str] = []

    def progress(s):
        if not inside.is_set():
            inside.set()
            assert tried.wait(30)

    def other():
        assert inside.wait(30)
        for call in (lambda: sim.advance(0.01), lambda: sim.robot().set_power(0.1, 0.1),
                     sim.reset, lambda: sim.robot().set_pose(0.0, 0.0)):
            try:
                call()
            except RuntimeError as e:
                errors.append(str(e))
        tried.set()

    t0, log0 = sim.time, sim.robot().command_log()
    thread = threading.Thread(target=other)
    thread.start()
    sim.run(0.04, progress=progress, chunk=0.02)
    thread.join(30)
    assert [e.split(":")[0] for e in errors] == ["advance_to", "command", "reset", "set_pose"]
    assert all("another thread is advancing or commanding this Simulation" in e
               for e in errors)
    assert sim.time == pytest.approx(t0 + 0.04) and sim.robot().command_log() == log0
    sim.advance(0.01)  # the lock is free again


def test_set_pose_into_the_giant_box_is_blocked_and_leaves_the_robot_there(sim):
    robot = sim.robot()
    assert robot.set_pose(0.0, 0.0).wait(5).succeeded
    robot.set_power(0.4, 0.4)
    sim.advance(0.5)  # moving: the blocked SetPose must not teleport it
    before = robot.pose()
    # The box's centre (x = -1.7366 m, a 2 m cube): the robot would be inside it.
    handle = robot.set_pose(-1.7, 0.0, 0.0)
    result = handle.result()
    assert (result.status, result.reason) == ("failed", "blocked")
    assert result.end_time == pytest.approx(sim.time)
    after = robot.pose()
    assert (after.x, after.y, after.yaw) == (before.x, before.y, before.yaw)  # exactly
    sim.advance(1.0)
    # It stays out of the box: at most the braking distance (0.4 x 0.61 m/s over the
    # slew-limited stop, a few cm) further on, and still on the ground.
    assert robot.pose().x == pytest.approx(before.x, abs=0.1)
    assert abs(robot.pose().z) < 0.01
    assert handle.result().reason == "blocked"  # the later not_applied is not recorded


def test_set_pose_near_the_box_is_clear_but_a_wheel_inside_is_blocked(sim):
    """The box's near face is at x = -0.7366 m; the rear wheels reach 0.152 m behind the
    chassis origin (half wheelbase 0.092 + radius 0.060): at x = -0.55 they clear the face by
    35 mm, at -0.60 they are 15 mm inside it."""
    robot = sim.robot()
    assert robot.set_pose(-0.55, 0.0, 0.0).wait(5).succeeded
    assert robot.pose().x == pytest.approx(-0.55, abs=0.005)
    result = robot.set_pose(-0.60, 0.0, 0.0).result()
    assert (result.status, result.reason) == ("failed", "blocked")
    assert robot.obstacle_at(_ground(-0.60)).obstacle.name == "world body 'giant_box'"
    assert robot.obstacle_at(_ground(2.0)) is None


@pytest.mark.parametrize("below", [True, False], ids=["just within", "just beyond"])
def test_set_pose_and_the_loader_allow_the_same_overlap_with_the_box(below):
    """One bound (`placement.OVERLAP_TOLERANCE`) for both: a rear wheel 0.1 mm less deep in
    the giant box than it allows loads and is a free SetPose target; 0.1 mm deeper, the
    loader refuses it and the SetPose is blocked. (The wheel's edge is the robot's rearmost
    point, half wheelbase + radius behind the chassis origin; the point-pair depth of a
    cylinder in a box is its x overlap to well under 0.1 mm.)"""
    from corobot_drake.config.placement import OVERLAP_TOLERANCE

    fresh = make_sim()  # the box where the scenario puts it, untouched
    box = fresh.scenario.world.bodies["giant_box"]
    face = box.pose.GetDeterministicValue().translation()[0] + box.shape.size[0] / 2
    depth = OVERLAP_TOLERANCE + (-1e-4 if below else 1e-4)
    spec = fresh.robot().spec
    x = float(face + spec.wheelbase / 2 + spec.wheel_radius - depth)
    problem = fresh.robot().obstacle_at(_ground(x))
    override = f"robots: {{corobot: {{pose: {{translation: [{x!r}, 0.0, 0.0]}}}}}}"
    if below:
        assert problem is None
        make_sim(override)
    else:  # one check (`placement.overlap_problems`), one wording
        assert problem.message == ("robot 'corobot' starts 5 mm inside world body "
                                   "'giant_box' (at most 5 mm allowed); move it clear")
        with pytest.raises(sc.ScenarioError) as refused:
            make_sim(override)
        assert str(refused.value).endswith(f"robots.corobot.pose: {problem.message}")


def test_scripted_set_pose_into_the_box_is_blocked_and_the_script_goes_on():
    sim = make_sim("robots: {corobot: {commands: [!SetPose {x: -1.7, y: 0}, "
                   "!SetPower {left: 0.5, right: 0.5}]}}")
    sim.advance(1.0)
    log = sim.robot().command_log()
    assert [(r.command, r.status, r.reason) for r in log[:2]] == [
        ("SetPose", "failed", "blocked"), ("SetPower", "succeeded", "")]  # taken by the drive
    assert sim.robot().pose().x > 0.1  # it drove forward from the origin instead


def _ground(x: float):
    from corobot_drake.config.poses import ground_pose

    return ground_pose(x, 0.0, 0.0).GetDeterministicValue()


# --- memory stays flat in long runs ----------------------------------------------------------


def test_a_bounded_run_log_keeps_its_window_and_agrees_with_the_whole_one(monkeypatch):
    """With `run_log_window` the run log keeps the newest window (plus what the sink holds,
    under one chunk of `RUN_LOG_CHUNK` samples), and those rows are the same as a whole
    run's. One long advance (spanning more than a chunk and the window) or many small ones
    (as when serving) bound it alike. Run at a tenth of the shipped chunk (1 s of samples)
    and window: the bounding only counts samples and compares times, so every path it takes
    with the shipped 10 s chunk it takes here in a tenth of the simulated time."""
    from corobot_drake import simulation
    from corobot_drake.systems.runlog import LOG_PERIOD

    chunk = 100
    monkeypatch.setattr(simulation, "RUN_LOG_CHUNK", chunk)
    script = "robots: {corobot: {commands: [!SetPower {left: 0.3, right: -0.3}]}}"
    whole, bounded = make_sim(script), make_sim(script)
    bounded.run_log_window = 0.5
    end = 3.1
    whole.advance(end)
    bounded.advance(2.0)  # one advance: 2 chunks' samples, one chunk spanning the window
    while bounded.time < end - 1e-9:
        bounded.advance_to(min(end, round(bounded.time + 0.05, 6)))
    full, kept = whole.robot().run_log(), bounded.robot().run_log()
    assert len(full) == pytest.approx(end / LOG_PERIOD, abs=2)
    window = 0.5 / LOG_PERIOD
    assert window <= len(kept) <= window + chunk + 1
    assert len(kept) < len(full) - chunk  # something was dropped
    assert (kept == full[-len(kept):]).all()  # bit for bit the whole log's end
    assert (bounded._run_log_chunks["corobot"][0][:, 0] > 0).all()
    bounded.reset()
    assert not bounded._run_log_chunks["corobot"]  # a reset clears the chunks too
    assert bounded.robot().run_log()[:, 0].tolist() == [0.0]  # the sample at the start




def test_under_cenic_stops_within_rounding_of_a_step_are_on_it():
    """A continuous plant's motion depends on where the Simulator stops: a stop a rounding
    error away from a step (2.3 is not 230 x 0.01 in floating point: 2.3000000000000003)
    would be a step of 1e-16 s of its own. `advance_to` puts such a stop on the step, so a
    run advanced in 50 ms chunks of rounded decimals is the run advanced at once, to the
    bit; on a discrete plant stops change nothing and times are kept as given."""
    script = "robots: {corobot: {commands: [!SetPower {left: 0.8, right: 0.4}]}}"
    whole, chunked = make_sim(script, CENIC), make_sim(script, CENIC)
    whole.advance(3.0)
    while chunked.time < 3.0 - 1e-9:
        chunked.advance_to(round(chunked.time + 0.05, 6))
    assert chunked.time == 3.0 == 300 * 0.01
    assert (whole.simulator.get_num_steps_taken()
            == chunked.simulator.get_num_steps_taken())
    assert whole.robot().pose() == chunked.robot().pose()
    assert (whole.robot().run_log() == chunked.robot().run_log()).all()
    assert chunked.on_step(2.3) == 2.3000000000000003 and chunked.on_step(2.305) == 2.305
    sap = make_sim(script, SAP)
    assert sap.on_step(2.3) == 2.3 and sap.stop_time(2.3456) == 2.3456


def test_under_cenic_a_loop_that_may_stop_anywhere_stops_on_steps():
    """The server's and the Meshcat view's targets (wall-clock times) go to the last step at
    or before them on a continuous plant; a discrete plant stops where asked."""
    cenic, sim = make_sim(CENIC), make_sim(SAP)
    assert cenic.continuous and not sim.continuous
    assert cenic.stop_time(0.0333) == 0.03
    assert cenic.stop_time(0.04 - 1e-12) == 4 * 0.01  # rounding below a step is on it
    assert cenic.stop_time(2.3) == 230 * 0.01
    assert sim.stop_time(0.0333) == 0.0333


def test_the_command_log_keeps_the_newest_records(sim, monkeypatch):
    """Past `COMMAND_LOG_CAPACITY` records the oldest go; the newest and running ones stay, and
    a handle to a dropped command says so (KeyError) instead of failing later."""
    from corobot_drake.systems import drive

    monkeypatch.setattr(drive, "COMMAND_LOG_CAPACITY", 50)
    robot = sim.robot()
    first = robot.set_power(0.1, 0.1)
    seqs = [robot.set_power(0.1 * (i % 5), 0.0) for i in range(120)]
    log = robot.command_log()
    assert len(log) == 50
    assert [r.seq for r in log] == seqs[-50:]
    assert robot.last_command() == log[-1] and log[-1].status == "running"
    with pytest.raises(KeyError, match=f"issued no command {first}"):
        robot.command_result(first)
    robot.all_stop()
