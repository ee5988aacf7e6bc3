"""Drive behaviour measured from the simulation of the default scene."""

import math

import numpy as np
import pytest

from conftest import make_sim
from corobot_drake.config import scenario as sc
from corobot_drake.tuning.drive_tuning import COROBOT_TOP_SPEED

R = 0.060325  # wheel radius, m (SPEC)
A, B = 0.092075, 0.11176  # half wheelbase, half track, m (SPEC)


def steady_speed(sim, seconds=1.0, samples=10):
    """Mean forward speed (m/s) over `seconds`, from the chassis velocity."""
    v = []
    for _ in range(samples):
        sim.advance(seconds / samples)
        v.append(sim.robot().velocity().forward)
    return float(np.mean(v))


def test_rests_on_ground_and_stays_still(sim):
    robot = sim.robot()
    sim.advance(0.5)
    start = robot.pose()
    # Hydroelastic tyres sink under 4 kg by ~0.5 mm.
    assert abs(start.z) < 1e-3
    assert robot.max_tilt_deg() < 0.1
    sim.advance(9.5)
    end = robot.pose()
    assert math.dist((start.x, start.y, start.z), (end.x, end.y, end.z)) < 1e-3


def test_top_speed_tuned_scaling(sim):
    sim.robot().set_power(1.0, 1.0)
    sim.advance(2.0)  # the 30 rad/s^2 ramp to 10.16 rad/s takes 0.34 s
    speed = steady_speed(sim)
    assert speed == pytest.approx(0.613, rel=0.03)  # the issue's figure
    # The shipped scaling is tuned to the real robot's 2 ft/s; 1% tells it from a mistuned one
    # (tools/tune_motor_torque_scaling.py converges to 0.5%).
    assert speed == pytest.approx(COROBOT_TOP_SPEED, rel=0.01)


def test_top_speed_untuned_scaling():
    sim = make_sim("robots: {corobot: {drive: {motor_torque_scaling: 20.0}}}")
    sim.robot().set_power(1.0, 1.0)
    sim.advance(2.0)
    assert steady_speed(sim) == pytest.approx(1.21, rel=0.03)


def test_set_speed(sim):
    sim.robot().set_speed(0.3, 0.3)
    sim.advance(1.5)
    # Tyres slip a little under the servo: 1% covers it (measured 0.2%).
    assert steady_speed(sim) == pytest.approx(0.3, rel=0.01)


def test_set_velocity_straight(sim):
    sim.robot().set_velocity(0.3, 0.0)
    sim.advance(1.5)
    # As test_set_speed: both sides at 0.3 m/s, the tyres slip a little (measured 0.2%).
    assert steady_speed(sim) == pytest.approx(0.3, rel=0.01)
    assert abs(sim.robot().velocity().yaw_rate) < 1e-3  # symmetric: no turn


def test_set_velocity_spin_turns_at_the_commanded_rate(sim):
    """(0, 1 rad/s) gives rims at -+ w T / 2 on the drive's effective track T (the shipped
    scenario's is calibrated); a skid-steer spin with isotropic friction then turns at
    (w T / 2) B / (A^2 + B^2), which the calibrated track makes ~1 rad/s, as commanded."""
    robot = sim.robot()
    track = sim.scenario.robots["corobot"].drive.effective_track_width
    assert track > 1.5 * 2 * B  # calibrated: the robot turns slower than its wheels' track says
    robot.set_velocity(0.0, 1.0)
    sim.advance(1.0)
    rates = []
    for _ in range(20):
        sim.advance(0.05)
        rates.append(robot.velocity().yaw_rate)
    predicted = 1.0 * (track / 2) * B / (A**2 + B**2)
    # 5%, as test_spin_in_place_matches_isotropic_coulomb: the hydroelastic patch's width and
    # the servo's slip make Drake's rate differ from the point-contact formula by ~2%.
    assert np.mean(rates) == pytest.approx(predicted, rel=0.05)
    assert np.mean(rates) == pytest.approx(1.0, rel=0.05)  # what the command asked for
    assert abs(robot.velocity().forward) < 0.01


def test_set_speed_reports_power_within_full_range(sim):
    """A SetSpeed past full power reports power 1: power is a fraction of the motor's range."""
    robot = sim.robot()
    robot.set_speed(1.0, 0.3)  # 16.6 rad/s on the left: above 10.16 rad/s = power 1
    sim.advance(0.5)
    state = robot.drive_state().two_wheel()
    assert state.left.commanded_power == pytest.approx(1.0)
    assert state.right.commanded_power == pytest.approx(0.3 / R / 10.16)


def test_set_speed_clamps_axle_speed(sim):
    robot = sim.robot()
    robot.set_speed(5.0, -5.0)  # 83 rad/s asked
    sim.advance(2.0)
    command = sim.station.diagram.GetOutputPort("corobot.axle_speed_command").Eval(sim.context)
    np.testing.assert_allclose(command, [20.0, -20.0])


def test_power_is_clamped(sim):
    """The Python API refuses power outside [-1, 1] (test_api_errors); the drive still clamps
    what reaches it by another way (here the command source itself)."""
    source = sim.robot()._parts.command_source
    source.Issue(source.GetMyMutableContextFromRoot(sim.context), sc.SetPower(3.0, -7.0))
    sim.advance(1.0)
    command = sim.station.diagram.GetOutputPort("corobot.axle_speed_command").Eval(sim.context)
    np.testing.assert_allclose(command, [10.16, -10.16])


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
def test_non_finite_power_is_rejected(sim, value):
    with pytest.raises(ValueError, match="finite"):
        sim.robot().set_power(value, 0.0)


def test_slew_limit_holds(sim):
    robot = sim.robot()
    robot.set_power(1.0, -1.0)
    port = sim.station.diagram.GetOutputPort("corobot.axle_speed_command")
    period = sim.scenario.robots["corobot"].drive.control_period
    commands = []
    for k in range(50):
        sim.advance_to((k + 0.5) * period)  # between two updates
        commands.append(port.Eval(sim.context).copy())
    steps = np.abs(np.diff(np.array(commands), axis=0))
    assert steps.max() <= 30.0 * period + 1e-9  # 30 rad/s^2 x the control period
    assert commands[-1] == pytest.approx([10.16, -10.16])  # reached in 0.34 s
    measured = robot.axle_speeds()
    assert measured["front_left"] == pytest.approx(10.16, rel=0.02)
    assert measured["rear_right"] == pytest.approx(-10.16, rel=0.02)


def test_disabled_drive_does_not_move(sim):
    robot = sim.robot()
    robot.enable(False)
    sim.advance(0.1)
    robot.set_power(1.0, 1.0)
    sim.advance(2.0)
    assert not robot.is_enabled()
    assert abs(robot.pose().x) < 1e-3
    robot.enable(True)
    sim.advance(0.1)
    robot.set_power(1.0, 1.0)
    sim.advance(1.0)
    assert robot.pose().x > 0.3


@pytest.mark.parametrize("wheel_speed", [5.0, -5.0])
def test_spin_in_place_matches_isotropic_coulomb(sim, wheel_speed):
    """Skid-steer spin with isotropic friction: yaw rate = b u / (a^2 + b^2)."""
    rim = wheel_speed * R
    sim.robot().set_speed(-rim, rim)
    sim.advance(1.5)
    yaw_rates = []
    for _ in range(20):
        sim.advance(0.05)
        yaw_rates.append(sim.robot().velocity().yaw_rate)
    predicted = B * rim / (A**2 + B**2)
    assert np.mean(yaw_rates) == pytest.approx(predicted, rel=0.05)


@pytest.mark.parametrize("direction", ["forwards", "backwards"])
def test_driving_into_the_giant_box_does_not_flip(direction):
    # The box is behind the robot: turn it round to drive in forwards.
    if direction == "forwards":
        sim = make_sim("robots: {corobot: {pose: {rotation: !Rpy {deg: [0, 0, 180]}}}}")
        sim.robot().set_power(1.0, 1.0)
    else:
        sim = make_sim()
        sim.robot().set_power(-1.0, -1.0)
    sim.advance(8.0)
    robot = sim.robot()
    # It reached the box: the tyres (0.1524 m from the centre) touch the face at x = -0.7366.
    assert robot.pose().x < -0.57
    assert robot.max_tilt_deg() < 20.0
