"""CommandSource and DriveController, each on its own: fixed inputs, evaluated outputs, their
periodic updates stepped by a Simulator on the lone system (conftest.Stepper)."""

import math

import numpy as np
import pytest

from conftest import Stepper
from corobot_drake.config.scenario import (
    AllStop,
    Drive,
    DriveDistance,
    Enable,
    SetPose,
    SetPower,
    SetSpeed,
    SetVelocity,
    Wait,
)
from corobot_drake.robots import robot_spec
from corobot_drake.systems.drive import (
    HOLD_SLACK,
    HOLD_SPEED,
    CommandSource,
    CommandStatus,
    DriveController,
    DriveRequest,
    DriveStatus,
    skid_steer_rim_speeds,
    velocity_track_width,
)

DRIVE = Drive()
K = DRIVE.motor_torque_scaling  # axle rad/s at power 1
RADIUS = robot_spec("corobot").wheel_radius  # m: the Corobot's wheels
STEP = DRIVE.slew_rate * DRIVE.control_period  # the most the axle speed moves per update
EXACT = 1e-12  # the controller adds, clamps and scales doubles: equal to rounding


# --- DriveController ----------------------------------------------------------------------


def controller(wheel_state=None) -> Stepper:
    s = Stepper(DriveController(DRIVE), DRIVE.control_period)
    s.fix("request", DriveRequest())
    s.fix("wheel_state", np.zeros(8) if wheel_state is None else wheel_state)
    return s


def status(s: Stepper):
    return DriveStatus(s.output("drive_status"))


def test_drive_status_fields_are_named_once():
    assert set(DriveStatus.get_fields()) == {
        "enabled", "power_left", "power_right", "target_left", "target_right"}
    size = len(DriveStatus.get_fields())
    assert DriveController(DRIVE).GetOutputPort("drive_status").size() == size


def test_controller_starts_enabled_and_still():
    s = controller()
    st = status(s)
    assert st.enabled == 1.0
    assert [st.power_left, st.power_right, st.target_left, st.target_right] == [0, 0, 0, 0]
    np.testing.assert_array_equal(s.output("desired_state"), np.zeros(8))


def test_set_power_targets_and_slews_by_at_most_one_step_per_update():
    s = controller()
    s.fix("request", DriveRequest(1, SetPower(0.5, -0.25)))
    expected = np.zeros(2)
    target = np.array([0.5 * K, -0.25 * K])
    assert math.isclose(STEP / DRIVE.control_period, 30.0)  # the SPEC's 30 rad/s^2
    for _ in range(25):  # 0.5 K = 5.08 rad/s takes 17 updates at 0.3 rad/s each (10 ms)
        s.tick()
        expected += np.clip(target - expected, -STEP, STEP)
        axle = s.output("axle_speed_command")
        np.testing.assert_allclose(axle, expected, atol=EXACT)
        np.testing.assert_allclose(s.output("desired_state"),
                                   [0, 0, 0, 0, axle[0], axle[1], axle[0], axle[1]], atol=0)
    np.testing.assert_allclose(s.output("axle_speed_command"), target, atol=EXACT)
    st = status(s)
    assert (st.power_left, st.power_right) == (0.5, -0.25)
    assert (st.target_left, st.target_right) == pytest.approx(tuple(target), abs=EXACT)


def test_first_update_moves_exactly_one_slew_step():
    s = controller()
    s.fix("request", DriveRequest(1, SetPower(1.0, -1.0)))
    s.tick()
    np.testing.assert_allclose(s.output("axle_speed_command"), [STEP, -STEP], atol=EXACT)


def test_power_is_clamped_to_one():
    s = controller()
    s.fix("request", DriveRequest(1, SetPower(2.0, -3.0)))
    s.tick()
    st = status(s)
    assert (st.power_left, st.power_right) == (1.0, -1.0)
    assert (st.target_left, st.target_right) == (K, -K)


def test_set_speed_clamps_to_the_max_axle_speed_and_reports_power():
    s = controller()
    fast = 2 * DRIVE.max_axle_speed * RADIUS  # m/s: twice what the axle may do
    slow = 0.2  # m/s
    s.fix("request", DriveRequest(1, SetSpeed(fast, -slow)))
    s.tick()
    st = status(s)
    assert st.target_left == DRIVE.max_axle_speed
    assert st.target_right == pytest.approx(-slow / RADIUS, rel=EXACT)
    assert st.power_left == 1.0  # 20 rad/s is past full power (K = 10.16): reported 1
    assert st.power_right == pytest.approx(-slow / RADIUS / K, rel=EXACT)


def test_set_velocity_maps_through_the_skid_steer_kinematics():
    track = velocity_track_width(DRIVE)
    assert skid_steer_rim_speeds(0.3, 0.0, track) == (0.3, 0.3)
    left, right = skid_steer_rim_speeds(0.1, 1.0, track)  # turning left: the right side faster
    assert (left, right) == pytest.approx((0.1 - track / 2, 0.1 + track / 2), rel=EXACT)
    s = controller()
    s.fix("request", DriveRequest(1, SetVelocity(0.1, 1.0)))
    s.tick()
    st = status(s)
    assert st.target_left == pytest.approx(left / RADIUS, rel=EXACT)
    assert st.target_right == pytest.approx(right / RADIUS, rel=EXACT)


def test_set_velocity_past_the_max_axle_speed_keeps_the_curvature():
    s = controller()
    s.fix("request", DriveRequest(1, SetVelocity(3.0, 10.0)))  # 50 and 68.5 rad/s asked
    s.tick()
    st = status(s)
    left, right = skid_steer_rim_speeds(3.0, 10.0, velocity_track_width(DRIVE))
    assert st.target_right == DRIVE.max_axle_speed  # the faster side at the limit
    assert st.target_left / st.target_right == pytest.approx(left / right, rel=EXACT)
    assert st.power_right == 1.0


def test_a_request_acts_once_by_its_sequence_number():
    s = controller()
    s.fix("request", DriveRequest(1, SetPower(0.5, 0.5)))
    s.tick()
    # The same seq with another command is the same message: ignored.
    s.fix("request", DriveRequest(1, SetPower(-0.5, -0.5)))
    s.tick()
    assert status(s).power_left == 0.5
    s.fix("request", DriveRequest(2, AllStop()))
    s.tick()
    st = status(s)
    assert (st.power_left, st.target_left, st.target_right) == (0.0, 0.0, 0.0)
    # AllStop slews down: the axle speed is one step below where it was (2 steps up).
    np.testing.assert_allclose(s.output("axle_speed_command"), [STEP, STEP], atol=EXACT)


def test_an_immediate_request_skips_the_slew_limit():
    s = controller()
    s.fix("request", DriveRequest(1, SetPower(1.0, -1.0)))
    s.tick(10)
    assert s.output("axle_speed_command")[0] == pytest.approx(10 * STEP)
    s.fix("request", DriveRequest(2, AllStop(), immediate=True))  # the seed profile's stop
    s.tick()
    np.testing.assert_array_equal(s.output("axle_speed_command"), [0.0, 0.0])
    np.testing.assert_array_equal(s.output("desired_state"), np.zeros(8))
    s.fix("request", DriveRequest(3, SetPower(1.0, 1.0)))  # an ordinary request slews again
    s.tick()
    np.testing.assert_allclose(s.output("axle_speed_command"), [STEP, STEP], atol=EXACT)


def test_disable_stops_at_once_and_ignores_motion_until_enabled():
    s = controller()
    s.fix("request", DriveRequest(1, SetPower(1.0, 1.0)))
    s.tick(4)
    assert s.output("axle_speed_command")[0] == pytest.approx(4 * STEP)
    s.fix("request", DriveRequest(2, Enable(False), enabled=False))
    s.tick()
    st = status(s)
    assert st.enabled == 0.0
    np.testing.assert_array_equal(s.output("axle_speed_command"), [0.0, 0.0])  # not slewed
    assert [st.power_left, st.power_right, st.target_left, st.target_right] == [0, 0, 0, 0]
    s.fix("request", DriveRequest(3, SetPower(1.0, 1.0), enabled=False))
    s.tick(3)
    np.testing.assert_array_equal(s.output("axle_speed_command"), [0.0, 0.0])
    s.fix("request", DriveRequest(4, Enable(True), enabled=True))
    s.tick()
    assert status(s).enabled == 1.0
    np.testing.assert_array_equal(s.output("axle_speed_command"), [0.0, 0.0])  # no target
    s.fix("request", DriveRequest(5, SetPower(1.0, 1.0), enabled=True))
    s.tick()
    np.testing.assert_allclose(s.output("axle_speed_command"), [STEP, STEP], atol=EXACT)


def test_halt_and_set_axle_speeds_write_the_state():
    s = controller()
    c = s.system
    c.SetAxleSpeeds(s.context, 3.0, -2.0)
    np.testing.assert_array_equal(s.output("axle_speed_command"), [3.0, -2.0])
    st = status(s)
    assert (st.target_left, st.target_right) == (3.0, -2.0)
    assert (st.power_left, st.power_right) == (3.0 / K, -2.0 / K)
    c.Halt(s.context)
    np.testing.assert_array_equal(s.output("axle_speed_command"), [0.0, 0.0])
    st = status(s)
    assert [st.power_left, st.power_right, st.target_left, st.target_right] == [0, 0, 0, 0]
    assert st.enabled == 1.0  # a halt is not a disable


def test_axle_speed_is_the_measured_wheel_velocities():
    wheel_state = np.array([0.1, 0.2, 0.3, 0.4, 1.5, -2.5, 3.5, -4.5])  # [q, v] per axle
    s = controller(wheel_state)
    np.testing.assert_array_equal(s.output("axle_speed"), [1.5, -2.5, 3.5, -4.5])


def wheels(q, v=(0.0, 0.0, 0.0, 0.0)) -> np.ndarray:
    """The `wheel_state` input [q, v] (rad, rad/s), actuator order."""
    return np.array([*q, *v], dtype=float)


def test_a_resting_wheel_is_held_at_the_angle_it_stopped_at():
    s = controller(wheels([0.5, -0.2, 0.5, -0.2]))
    s.tick()  # at rest on zero command: the hold angles latch here
    np.testing.assert_array_equal(s.output("desired_state"), np.zeros(8))
    rolled = wheels([0.5 + 2e-5, -0.2 - 3e-5, 0.5, -0.2], [1e-5, -1e-5, 0.0, 0.0])
    s.fix("wheel_state", rolled)  # the tyres' mesh rolls two wheels (1e-5 rad/s: at rest)
    s.tick()
    # Pulled back at hold_gain x the error: the creep's 2e-5 rad gives 2e-4 rad/s at 10/s.
    gain = DRIVE.hold_gain
    np.testing.assert_allclose(s.output("desired_state")[4:],
                               [-gain * 2e-5, gain * 3e-5, 0.0, 0.0], rtol=1e-9)
    np.testing.assert_array_equal(s.output("axle_speed_command"), [0.0, 0.0])  # still 0
    s.fix("wheel_state", wheels([0.5 + 2e-3, -0.2, 0.5, -0.2]))
    s.tick()  # pushed past the slack: held where it is now, no pull back
    assert HOLD_SLACK < 2e-3
    np.testing.assert_array_equal(s.output("desired_state"), np.zeros(8))


def test_hold_angles_given_at_the_start_pull_the_wheels_back_to_them():
    """A saved scene's hold angles: a resting wheel a little off its hold angle is pulled
    back to it from the first update (without them it would be held where it is)."""
    s = controller(wheels([0.5, -0.2, 0.5, -0.2]))
    hold = [0.5 - 3e-5, -0.2, 0.5, -0.2 + 1e-5]
    s.system.SetHoldAngles(s.context, hold)
    s.tick()
    gain = DRIVE.hold_gain
    np.testing.assert_allclose(s.output("desired_state")[4:],
                               [-gain * 3e-5, 0.0, 0.0, gain * 1e-5], rtol=1e-9, atol=1e-15)
    assert s.system.hold_angles(s.context) == hold


def test_the_hold_pulls_at_most_half_the_rest_speed_and_lets_a_driven_wheel_go():
    s = controller(wheels([0.0] * 4))
    s.tick()
    s.fix("wheel_state", wheels([-HOLD_SLACK] * 4))  # a big error, inside the slack
    s.tick()
    np.testing.assert_allclose(s.output("desired_state")[4:], [0.5 * HOLD_SPEED] * 4)
    s.fix("request", DriveRequest(1, SetPower(0.0, 1.0)))  # the right side drives
    s.tick()
    v_d = s.output("desired_state")[4:]
    np.testing.assert_allclose(v_d, [0.5 * HOLD_SPEED, STEP, 0.5 * HOLD_SPEED, STEP])
    s.fix("wheel_state", wheels([-HOLD_SLACK] * 4, [0.0, 2 * HOLD_SPEED, 0.0, 0.0]))
    s.fix("request", DriveRequest(2, AllStop(), immediate=True))
    s.tick()  # commanded 0 but still turning: not at rest, so not held
    np.testing.assert_allclose(s.output("desired_state")[4:], [0.5 * HOLD_SPEED, 0.0] * 2)


def test_no_hold_at_hold_gain_zero():
    s = Stepper(DriveController(Drive(hold_gain=0.0)), DRIVE.control_period)
    s.fix("request", DriveRequest())
    s.fix("wheel_state", wheels([0.0] * 4))
    s.tick()
    s.fix("wheel_state", wheels([1e-5] * 4))
    s.tick()
    np.testing.assert_array_equal(s.output("desired_state"), np.zeros(8))


# --- CommandSource --------------------------------------------------------------------------

PERIOD = 1.0 / 60.0  # the script tests count 1/60 s ticks (the source works at any period)


def source(script=(), status=None) -> Stepper:
    s = Stepper(CommandSource(list(script), PERIOD), PERIOD)
    if status is not None:
        s.fix("command_status", status)
    return s


def request(s: Stepper) -> DriveRequest:
    return s.output("request")


def log(s: Stepper):
    return s.system.current_state(s.context).log


def test_script_runs_in_order_with_waits_and_completing_commands():
    script = [SetPower(0.1, 0.1), Wait(0.04), SetSpeed(0.2, 0.2), DriveDistance(1.0, 0.5),
              AllStop()]
    s = source(script, CommandStatus())
    assert request(s).seq == 0  # nothing before the simulation starts
    # Initialization issues the SetPower; the update at t = 0, the Wait: held until 0.04 s.
    s.tick()
    assert (request(s).seq, request(s).command, request(s).time) == (1, SetPower(0.1, 0.1), 0)
    s.tick(2)  # t = 1/60, 2/60 s: held
    assert request(s).seq == 1
    s.tick()  # t = 3/60 s
    assert (request(s).seq, request(s).command) == (2, SetSpeed(0.2, 0.2))
    assert request(s).time == pytest.approx(3 * PERIOD, abs=1e-12)
    s.tick()
    assert (request(s).seq, request(s).command) == (3, DriveDistance(1.0, 0.5))
    s.tick(10)  # the DriveDistance runs (no end reported): the script waits for it
    assert request(s).seq == 3
    s.fix("command_status", CommandStatus(3, "succeeded", "", 0.2))
    s.tick()
    assert (request(s).seq, request(s).command) == (4, AllStop())
    assert [(r.seq, r.command) for r in log(s)] == [
        (1, "SetPower"), (0, "Wait"), (2, "SetSpeed"), (3, "DriveDistance"), (4, "AllStop")]
    # Level commands end at the update after their issue, when the drive takes them; the
    # AllStop, issued at this update, runs until the next.
    assert [r.status for r in log(s)] == ["succeeded"] * 4 + ["running"]
    assert log(s)[0].end_time == 0.0  # issued and handed over at initialization
    wait = log(s)[1]
    assert (wait.start_time, wait.end_time) == pytest.approx((0.0, 0.04), abs=1e-12)
    assert log(s)[3].end_time == 0.2  # the reported end time
    s.tick()
    assert log(s)[4].status == "succeeded"


def test_a_zero_wait_defers_the_rest_of_the_script_to_an_update():
    """What a saved scene writes before a script's rest that is due: the start issues what
    comes before the 0 s Wait alone, the update at the start time the rest (as the saved run
    would have issued it), and the log holds no Wait."""
    s = source([SetPower(0.1, 0.1), Wait(0.0), AllStop()], CommandStatus())
    s.simulator.Initialize()
    assert (request(s).seq, request(s).command) == (1, SetPower(0.1, 0.1))
    s.tick()  # the update at t = 0
    assert (request(s).seq, request(s).command, request(s).time) == (2, AllStop(), 0.0)
    assert [r.command for r in log(s)] == ["SetPower", "AllStop"]


def test_api_commands_take_the_next_sequence_numbers_at_once():
    s = source([SetPower(0.3, 0.3)])
    s.tick()
    assert request(s).seq == 1
    assert s.system.Issue(s.context, SetSpeed(0.1, -0.1)) == 2
    assert (request(s).seq, request(s).command) == (2, SetSpeed(0.1, -0.1))  # no update needed
    assert s.system.Issue(s.context, AllStop()) == 3
    assert [(r.seq, r.status) for r in log(s)] == [(1, "succeeded"), (2, "succeeded"),
                                                   (3, "running")]
    s.tick()  # the drive takes the AllStop at the next update
    assert [(r.seq, r.status) for r in log(s)][-1] == (3, "succeeded")
    assert s.system.record(s.context, 2).command == "SetSpeed"
    assert s.system.record(s.context, 9) is None


def test_a_new_command_supersedes_a_running_completing_one():
    s = source()
    s.system.Issue(s.context, DriveDistance(1.0, 0.5))
    s.tick(2)
    s.system.Issue(s.context, SetPower(0.2, 0.2))
    first = log(s)[0]
    assert (first.status, first.reason, first.end_time) == ("failed", "superseded",
                                                            s.context.get_time())
    assert log(s)[1].status == "running"


def test_disable_fails_a_running_completing_command_and_is_carried_as_a_level():
    s = source()
    s.system.Issue(s.context, DriveDistance(1.0, 0.5))
    s.system.Issue(s.context, Enable(False))
    assert (log(s)[0].status, log(s)[0].reason) == ("failed", "disabled")
    assert request(s).enabled is False
    s.system.Issue(s.context, SetPower(0.5, 0.5))
    assert request(s).enabled is False  # the level stays with the next requests
    s.system.Issue(s.context, Enable(True))
    assert request(s).enabled is True


def test_a_reported_end_is_recorded_only_once():
    s = source(status=CommandStatus())
    seq = s.system.Issue(s.context, DriveDistance(1.0, 0.5))
    s.fix("command_status", CommandStatus(seq, "failed", "stalled", 0.5))
    s.tick()
    record = s.system.record(s.context, seq)
    assert (record.status, record.reason, record.end_time) == ("failed", "stalled", 0.5)
    s.fix("command_status", CommandStatus(seq, "succeeded", "", 0.9))  # too late: ignored
    s.tick()
    assert s.system.record(s.context, seq).status == "failed"


def test_set_pose_is_held_for_the_simulation_to_apply():
    s = source()
    assert not s.system.has_teleport(s.context)
    seq = s.system.Issue(s.context, SetPose(1.0, 2.0, 90.0))
    assert s.system.has_teleport(s.context)
    taken = s.system.TakeTeleport(s.context)
    assert (taken.seq, taken.command) == (seq, SetPose(1.0, 2.0, 90.0))
    assert not s.system.has_teleport(s.context)
    assert s.system.TakeTeleport(s.context) is None


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_non_finite_commands_are_rejected(bad):
    with pytest.raises(ValueError, match=r"SetPower\.left must be a finite number"):
        CommandSource([SetPower(bad, 0.0)], PERIOD)
    s = source()
    with pytest.raises(ValueError, match=r"SetSpeed\.right"):
        s.system.Issue(s.context, SetSpeed(0.0, bad))
    assert request(s).seq == 0  # nothing issued


LEVEL_AND_WAIT = [SetPower(0.3, 0.3), SetSpeed(0.1, 0.1), AllStop(), Enable(True), Wait(0.05)]
LATER = [SetPower(0.2, 0.2), Wait(0.05), AllStop(), Enable(True), Enable(False),
         SetSpeed(0.1, 0.1)]


@pytest.mark.parametrize("first", LEVEL_AND_WAIT, ids=lambda c: type(c).__name__)
@pytest.mark.parametrize("later", LATER, ids=lambda c: f"then_{c}")
def test_every_scripted_command_ends_whatever_follows(first, later):
    """No command of a script is left `running` once the script is done,
    whatever follows it (a Wait's record used to hide the command before it)."""
    s = source([first, later], CommandStatus())
    s.tick(8)  # 8 updates: both issued, the Waits (3 updates each) elapsed
    records = log(s)
    assert len(records) == 2
    assert all(r.end_time is not None for r in records), records
    assert all(r.status == "succeeded" for r in records), records
    assert records[0].end_time <= records[1].start_time + 1e-12


def test_power_to_a_disabled_drive_fails_disabled():
    s = source([Enable(False), SetPower(0.5, 0.5), SetSpeed(0.1, 0.1), Enable(True),
                SetPower(0.2, 0.2)], CommandStatus())
    s.tick(7)
    assert [(r.command, r.status, r.reason) for r in log(s)] == [
        ("Enable", "succeeded", ""), ("SetPower", "failed", "disabled"),
        ("SetSpeed", "failed", "disabled"), ("Enable", "succeeded", ""),
        ("SetPower", "succeeded", "")]


def test_a_wait_runs_until_it_has_elapsed():
    s = source([Wait(0.1)], CommandStatus())
    s.tick(3)  # t = 2/60 s: 0.1 s not yet elapsed
    assert (log(s)[0].status, log(s)[0].end_time) == ("running", None)
    s.tick(5)  # t = 7/60 s > 0.1 s
    assert log(s)[0].status == "succeeded"
    assert log(s)[0].end_time == pytest.approx(0.1, abs=1e-12)


def test_an_update_that_changes_nothing_is_not_applied():
    """Idle updates report DidNothing, so Drake copies nothing back: the Simulator counts
    only the updates that changed the state."""
    s = source([SetPower(0.1, 0.1), Wait(0.05), AllStop()], CommandStatus())
    s.tick(20)
    # The first update ends the SetPower (issued at initialization) and starts the Wait;
    # the update at or after 0.05 s ends it and issues the AllStop; the next ends that.
    assert s.simulator.get_num_unrestricted_updates() == 3
    assert [r.command for r in log(s) if r.status == "succeeded"] == [
        "SetPower", "Wait", "AllStop"]
    s.tick(20)
    assert s.simulator.get_num_unrestricted_updates() == 3


def test_a_steady_drive_writes_no_state():
    """Both sides turning at their targets: the updates change nothing, however the wheels
    turn (no hold is tracked), and `hold_angles` reads the wheels' angles now."""
    s = controller()
    s.fix("request", DriveRequest(1, SetPower(0.1, -0.2)))
    s.tick(round(0.2 * K / STEP) + 1)  # slewed to the targets (0.2 K rad/s at STEP a tick)
    np.testing.assert_allclose(s.output("axle_speed_command"), [0.1 * K, -0.2 * K],
                               atol=EXACT)
    state = s.context.get_discrete_state()
    before = [state.get_vector(i).CopyToVector() for i in range(state.num_groups())]
    turned = wheels([1.0, -2.0, 1.5, -2.5], [0.1 * K / 2, -0.2 * K, 0.1 * K, -0.2 * K])
    s.fix("wheel_state", turned)
    s.tick(3)
    updates = s.simulator.get_num_discrete_updates()
    s.tick(3)
    for i, values in enumerate(before):
        np.testing.assert_array_equal(state.get_vector(i).CopyToVector(), values)
    assert s.simulator.get_num_discrete_updates() == updates  # DidNothing: nothing copied back
    assert s.system.hold_angles(s.context) == [1.0, -2.0, 1.5, -2.5]
    s.fix("request", DriveRequest(2, SetPower(0.1, -0.2)))  # the same again: still steady
    s.tick()
    np.testing.assert_array_equal(s.output("desired_state")[4:],
                                  [0.1 * K, -0.2 * K, 0.1 * K, -0.2 * K])


def test_a_wheel_stopped_from_a_steady_drive_is_held_where_it_stops():
    """Hold angles are not tracked while both sides turn: a wheel at rest when its side
    stops (at once: disabled) is held at its angle at that update (not at its angle at the
    update before, within `HOLD_SLACK` of it), and pulled back to it."""
    s = controller()
    s.fix("request", DriveRequest(1, SetPower(0.05, 0.05)))
    stopped = [0.7, 0.8, 0.9, 1.0]
    s.fix("wheel_state", wheels([a - 5e-5 for a in stopped], [1e-4] * 4))  # slow (a wall)
    s.tick(round(0.05 * K / STEP) + 3)  # steady
    s.fix("wheel_state", wheels(stopped))  # at rest
    s.fix("request", DriveRequest(2, Enable(False), enabled=False))
    s.tick()
    np.testing.assert_array_equal(s.output("desired_state"), np.zeros(8))
    assert s.system.hold_angles(s.context) == stopped
    s.fix("wheel_state", wheels([0.7 + 2e-5, 0.8, 0.9, 1.0 - 1e-5]))
    s.tick()
    gain = DRIVE.hold_gain
    np.testing.assert_allclose(s.output("desired_state")[4:],
                               [-gain * 2e-5, 0.0, 0.0, gain * 1e-5], rtol=1e-9, atol=1e-15)


def test_what_comes_during_a_quiet_wait_is_taken_at_the_next_update():
    """While the script waits, the updates skip their work (`quiet_until`); a command issued
    then still ends at the next update, and a completing command's reported end is recorded
    at the next update, as on any other step."""
    s = source([SetPower(0.1, 0.1), Wait(1.0), AllStop()], CommandStatus())
    s.tick(5)
    updates = s.simulator.get_num_unrestricted_updates()
    s.tick(5)
    assert s.simulator.get_num_unrestricted_updates() == updates  # nothing to do, nothing done
    seq = s.system.Issue(s.context, SetSpeed(0.2, 0.2))
    s.tick()
    assert (s.system.record(s.context, seq).status,
            s.system.record(s.context, seq).end_time) == ("succeeded", s.last_tick_time)
    seq = s.system.Issue(s.context, DriveDistance(0.5, 0.5))
    s.tick(3)
    assert s.system.record(s.context, seq).status == "running"
    s.fix("command_status", CommandStatus(seq, "succeeded", "", s.context.get_time()))
    s.tick()
    assert s.system.record(s.context, seq).status == "succeeded"
    s.tick(round(1.0 / PERIOD))  # the Wait ends and the script carries on with the AllStop
    assert [r.command for r in log(s)][-1] == "AllStop"
    assert log(s)[-1].start_time == pytest.approx(1.0, abs=PERIOD)


def test_a_failed_scripted_set_pose_lets_the_script_carry_on_at_the_next_update():
    """The Simulation fails a SetPose it cannot apply (`Fail`) between updates, while the
    script waits on it and the motion still reports it running: the next update goes on."""
    s = source([SetPose(1.0, 0.0), SetPower(0.1, 0.1)], CommandStatus(1, "running"))
    s.tick(3)
    assert [r.command for r in log(s)] == ["SetPose"]
    s.system.Fail(s.context, 1, "blocked")
    s.tick()
    assert [(r.command, r.status) for r in log(s)] == [("SetPose", "failed"),
                                                        ("SetPower", "running")]
