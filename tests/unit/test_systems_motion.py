"""MotionCommands on its own: requests, position and heading fixed by the test, its updates
stepped by a Simulator on the lone system (conftest.Stepper)."""

import math

import pytest

from conftest import Stepper
from corobot_drake.config.scenario import (
    AllStop,
    Drive,
    DriveDistance,
    Motion,
    RotateDegrees,
    SetPose,
    SetPower,
)
from corobot_drake.robots import robot_spec
from corobot_drake.systems.drive import DriveRequest
from corobot_drake.systems.motion import (
    POSE_SETTLE_TIME,
    POSE_TIMEOUT,
    SPIN_YAW_PER_RIM_SPEED,
    STILL_TIME,
    MotionCommands,
    wrap,
)

DRIVE = Drive()
PERIOD = DRIVE.control_period
K = DRIVE.motor_torque_scaling
STILL_FRAMES = round(STILL_TIME / PERIOD)  # updates at rest before a closed-loop success
EXACT = 1e-12  # products and sums of a few doubles


def motion(profile: str = "closed_loop", x: float = 0.0, heading: float = 0.0) -> Stepper:
    s = Stepper(MotionCommands(DRIVE, Motion(profile=profile)), PERIOD)
    s.fix("request", DriveRequest())
    at(s, x, heading)
    return s


def at(s: Stepper, x: float, heading: float, y: float = 0.0) -> None:
    """Fixes the measured pose: GPS (x, y, 0) m and compass `heading` rad."""
    s.fix("position", [x, y, 0.0])
    s.fix("heading", [heading])


def out(s: Stepper) -> DriveRequest:
    return s.output("drive_request")


def status(s: Stepper):
    return s.output("command_status")


def ticks_until_ended(s: Stepper, limit: int = 200) -> int:
    for n in range(1, limit + 1):
        s.tick()
        if status(s).seq:
            return n
    raise AssertionError(f"still running after {limit} updates")


def test_ordinary_commands_pass_through_with_their_own_sequence_numbers():
    s = motion()
    s.fix("request", DriveRequest(5, SetPower(0.3, -0.3)))
    s.tick()
    assert (out(s).seq, out(s).command, out(s).enabled) == (1, SetPower(0.3, -0.3), True)
    s.fix("request", DriveRequest(6, SetPower(0.3, -0.3)))  # the same command again
    s.tick()
    assert out(s).seq == 1  # not re-sent
    s.fix("request", DriveRequest(7, AllStop()))
    s.tick()
    assert (out(s).seq, out(s).command) == (2, AllStop())
    assert status(s).seq == 0  # only completing commands report an end


def test_closed_loop_drive_cruises_then_succeeds_after_resting_on_the_goal():
    s = motion()
    s.fix("request", DriveRequest(1, DriveDistance(1.0, 0.5)))
    s.tick()
    # Far from the goal the speed is the cruise speed: power 0.5 on both sides.
    assert out(s).command.left == pytest.approx(0.5, abs=EXACT)
    assert out(s).command.right == out(s).command.left
    at(s, 0.3, 0.0)
    s.tick()
    # Carried on (a saved scene): the distance counted from where it started, with the
    # progress at the last update (the closed loop's speed estimate starts from it).
    assert s.system.remaining_command(s.context) == DriveDistance(1.0, 0.5, [0.0, 0.0, 0.0],
                                                                  [0.3])
    at(s, 1.0, 0.0)  # on the goal: the first update sees it arrive fast, then at rest
    assert STILL_TIME == 0.05  # docs/commands.md: "succeeds after 0.05 s at rest there"
    assert ticks_until_ended(s) == 1 + STILL_FRAMES
    st = status(s)
    assert (st.seq, st.status, st.reason) == (1, "succeeded", "")
    assert st.time == pytest.approx(s.last_tick_time, abs=EXACT)
    assert out(s).command == AllStop()


def test_closed_loop_drive_holds_its_start_heading():
    s = motion()
    s.fix("request", DriveRequest(1, DriveDistance(1.0, 0.5)))
    s.tick()
    at(s, 0.01, 0.1)  # drifted 0.1 rad to the left
    s.tick()
    command = out(s).command
    # 5 axle rad/s per rad of error, per side: the left speeds up, the right slows down.
    assert (command.left - command.right) * K == pytest.approx(2 * 5.0 * 0.1, abs=1e-9)


def test_seed_drive_succeeds_as_soon_as_the_goal_is_reached():
    s = motion("seed")
    s.fix("request", DriveRequest(1, DriveDistance(-0.5, 1.0)))  # backwards
    s.tick()
    assert (out(s).command.left, out(s).command.right) == pytest.approx((-1.0, -1.0), abs=EXACT)
    at(s, -0.4999, 0.0)
    s.tick()
    assert status(s).seq == 0
    at(s, -0.5, 0.0)
    s.tick()
    assert (status(s).seq, status(s).status) == (1, "succeeded")
    assert out(s).command == AllStop()
    assert out(s).immediate  # the book: axle speed 0 at once, not slewed


def test_seed_halves_the_speed_when_under_a_tenth_of_a_second_remains():
    s = motion("seed")
    s.fix("request", DriveRequest(1, DriveDistance(1.0, 1.0)))
    s.tick()  # starts at x = 0, full power
    speed = 0.45  # m/s, steady: the 0.1 s threshold (0.045 m left) falls between updates
    x, n = 0.0, 0
    while out(s).command.left == pytest.approx(1.0, abs=EXACT):
        x += speed * PERIOD
        at(s, x, 0.0)
        s.tick()
        n += 1
        assert n < 1000
    # Halved at the first update whose estimate of the time left (from the progress over
    # the last 0.1 s: the distance left / the speed) is under 0.1 s.
    assert (1.0 - x) / speed < 0.1
    assert (1.0 - (x - speed * PERIOD)) / speed > 0.1
    assert out(s).command.left == pytest.approx(0.5, abs=EXACT)
    assert not out(s).immediate  # slowing down slews


def test_a_drive_that_does_not_move_fails_stalled_after_the_stall_time():
    s = motion()
    s.fix("request", DriveRequest(1, DriveDistance(1.0, 0.5)))
    stall_ticks = round(Motion().stall_time / PERIOD)  # updates in 1 s
    s.tick(stall_ticks)  # the last one period before 1 s
    assert status(s).seq == 0
    s.tick()  # t = 1 s
    st = status(s)
    assert (st.seq, st.status, st.reason) == (1, "failed", "stalled")
    assert st.time == pytest.approx(Motion().stall_time, abs=EXACT)
    assert out(s).command == AllStop()


def test_a_completing_command_to_a_disabled_drive_fails_at_once():
    s = motion()
    s.fix("request", DriveRequest(1, RotateDegrees(90.0, 0.5), enabled=False))
    s.tick()
    st = status(s)
    assert (st.seq, st.status, st.reason) == (1, "failed", "disabled")
    assert (out(s).command, out(s).enabled) == (AllStop(), False)


def test_a_new_request_supersedes_the_running_command():
    s = motion()
    s.fix("request", DriveRequest(1, DriveDistance(1.0, 0.5)))
    s.tick(3)
    s.fix("request", DriveRequest(2, SetPower(0.2, 0.2)))
    s.tick()
    assert out(s).command == SetPower(0.2, 0.2)
    assert s.system.remaining_command(s.context) is None
    s.tick(100)  # the superseded drive never reports (the command source records it)
    assert status(s).seq == 0


def test_rotation_unwraps_across_180_degrees_and_lands():
    s = motion(heading=3.0)
    s.fix("request", DriveRequest(1, RotateDegrees(90.0, 0.5)))
    s.tick()
    assert out(s).command.left < 0 < out(s).command.right  # counter-clockwise
    at(s, 0.0, -3.0)  # turned 2 pi - 6 = 0.283 rad through +-pi
    s.tick()
    turned = 2 * math.pi - 6.0
    left = s.system.remaining_command(s.context)
    assert left.degrees == pytest.approx(90.0 - math.degrees(turned), abs=1e-9)
    at(s, 0.0, wrap(3.0 + math.pi / 2))
    assert ticks_until_ended(s) == 1 + STILL_FRAMES
    assert (status(s).seq, status(s).status) == (1, "succeeded")


def test_set_pose_succeeds_once_the_robot_has_settled_where_it_was_put():
    s = motion()
    s.fix("request", DriveRequest(1, SetPose(1.0, 2.0, 90.0)))
    s.tick()
    assert out(s).command == AllStop()
    at(s, 1.0, math.pi / 2, y=2.0)  # the Simulation teleported it
    s.tick()
    landed = s.last_tick_time
    settle_ticks = round(POSE_SETTLE_TIME / PERIOD)
    s.tick(settle_ticks - 1)
    assert status(s).seq == 0
    s.tick()
    st = status(s)
    assert (st.seq, st.status) == (1, "succeeded")
    assert st.time - landed == pytest.approx(POSE_SETTLE_TIME, abs=EXACT)


def test_set_pose_not_applied_fails_after_the_timeout():
    s = motion()
    s.fix("request", DriveRequest(1, SetPose(1.0, 2.0, 90.0)))
    n = ticks_until_ended(s)
    st = status(s)
    assert (st.seq, st.status, st.reason) == (1, "failed", "not_applied")
    assert n == round(POSE_TIMEOUT / PERIOD) + 1  # the update at t = 1 s


@pytest.mark.parametrize("profile", ["closed_loop", "seed"])
def test_a_drive_given_its_start_counts_from_there(profile):
    s = motion(profile, x=0.3)
    s.fix("request", DriveRequest(1, DriveDistance(1.0, 0.5, [0.0, 0.0, 0.0])))
    s.tick()
    assert out(s).command.left == pytest.approx(0.5, abs=EXACT)  # far from the goal: cruise
    assert s.system.get_state(s.context).active.progress == pytest.approx(0.3, abs=EXACT)
    if profile == "seed":
        at(s, 1.0, 0.0)  # 1 m from the start given, not from where it began
        s.tick()
        assert (status(s).status, out(s).command, out(s).immediate) == (
            "succeeded", AllStop(), True)


def test_a_turn_given_its_start_heading_counts_from_it():
    s = motion(heading=0.5)
    s.fix("request", DriveRequest(1, RotateDegrees(60.0, 0.5, [0.0, 0.0, 0.0])))
    s.tick()
    # Already 0.5 rad of the 60 deg turned: 60 - 28.6 deg are left.
    left = s.system.remaining_command(s.context)
    assert left.degrees == pytest.approx(60.0 - math.degrees(0.5), abs=1e-9)
    assert left.start == [0.0, 0.0, pytest.approx(math.degrees(0.5))]


def test_a_seed_turn_saved_past_its_goal_resumes_as_done():
    s = motion("seed")
    s.fix("request", DriveRequest(1, RotateDegrees(30.0, 1.0)))
    s.tick()
    at(s, 0.0, math.radians(29.0))
    s.tick()
    at(s, 0.0, math.radians(31.0))  # overshot since the last update: the next one ends it
    left = s.system.remaining_command(s.context)
    assert left.degrees == pytest.approx(1.0, abs=1e-9)  # counted from the last update
    resumed = motion("seed", heading=math.radians(31.0))
    resumed.fix("request", DriveRequest(1, left))
    resumed.tick()  # its first update sees the overshoot, as the saved run's next one would
    assert (status(resumed).status, out(resumed).command, out(resumed).immediate) == (
        "succeeded", AllStop(), True)


def test_a_request_not_yet_taken_is_saved_as_issued():
    s = motion("seed")
    s.fix("request", DriveRequest(1, DriveDistance(0.3, 1.0)))
    s.tick()
    s.fix("request", DriveRequest(2, RotateDegrees(-45.0, 0.5)))  # the next update takes it
    assert s.system.remaining_command(s.context) == RotateDegrees(-45.0, 0.5)


def _plant(s: Stepper, x: float, heading: float) -> tuple[float, float]:
    """One control period of a toy robot whose wheels turn at the commanded power at once
    (rim speed = axle speed x wheel radius; yaw rate = the skid-steer spin rate)."""
    command = out(s).command
    left, right = (command.left, command.right) if isinstance(command, SetPower) else (0, 0)
    rim_left, rim_right = (p * K * robot_spec("corobot").wheel_radius for p in (left, right))
    x += 0.5 * (rim_left + rim_right) * PERIOD
    heading = wrap(heading + 0.5 * (rim_right - rim_left) * SPIN_YAW_PER_RIM_SPEED * PERIOD)
    at(s, x, heading)
    return x, heading


def _same_request(resumed: Stepper, s: Stepper) -> None:
    assert (status(resumed).seq, status(resumed).status) == (status(s).seq, status(s).status)
    assert out(resumed).immediate == out(s).immediate
    if isinstance(out(s).command, SetPower):
        assert out(resumed).command.left == pytest.approx(out(s).command.left, abs=1e-9)
        assert out(resumed).command.right == pytest.approx(out(s).command.right, abs=1e-9)
    else:
        assert out(resumed).command == out(s).command


@pytest.mark.parametrize("profile", ["closed_loop", "seed"])
@pytest.mark.parametrize("command", [DriveDistance(0.3, 1.0), RotateDegrees(-60.0, 1.0),
                                     DriveDistance(0.3, 0.5), RotateDegrees(-60.0, 0.5)],
                         ids=lambda c: f"{type(c).__name__}-{c.power:g}")
def test_a_command_resumed_at_any_update_replays_the_same_requests(profile, command):
    """What `remaining_command` writes (start, power, `recent_progress`) is all of
    a command's memory its requests depend on. Saved before each update of a run on a toy
    robot (through the seed profile's halvings and the refills of its 0.1 s of progress
    samples after them), a fresh MotionCommands given it requests what the running one does
    for the next 0.15 s (past a refill), and the seed profile ends it at the same update.
    Only float rounding differs (degrees and back, the progress counted from the last
    update), so the powers agree to 1e-9."""
    follow = round(0.15 / PERIOD)
    s = motion(profile)
    s.fix("request", DriveRequest(1, command))
    runs, x, heading, halvings = [], 0.0, 0.0, 0
    for tick in range(400):
        runs = [r for r in runs if r[1] > tick]
        left = s.system.remaining_command(s.context)
        if left is not None:
            resumed = motion(profile, x, heading)
            resumed.fix("request", DriveRequest(1, left))
            runs.append((resumed, tick + follow))
        s.tick()
        if status(s).seq and profile == "closed_loop":
            break  # its count of updates at rest on the goal is not saved: a resumed one
            # may succeed up to STILL_TIME later (at rest on the same spot)
        for resumed, _ in runs:
            resumed.tick()
            _same_request(resumed, s)
        if status(s).seq:
            break
        halvings = max(halvings, round(-math.log2(s.system.get_state(s.context).active.scale)))
        x, heading = _plant(s, x, heading)
        for resumed, _ in runs:
            at(resumed, x, heading)
    assert status(s).status == "succeeded"
    assert halvings >= (1 if profile == "seed" else 0)  # the refills are covered


def test_an_update_that_changes_nothing_is_not_applied():
    """With nothing new and nothing running the update reports DidNothing (Drake copies
    nothing back); a running command changes the state at every update."""
    s = motion()
    s.tick(10)
    assert s.simulator.get_num_unrestricted_updates() == 0
    s.fix("request", DriveRequest(1, DriveDistance(1.0, 0.5), 0.0))
    s.tick(10)
    assert s.simulator.get_num_unrestricted_updates() == 10
