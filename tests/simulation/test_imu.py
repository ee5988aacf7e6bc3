"""The IMU on the Corobot, through whole simulations: `imus` in the scenario, read with
`robot.reading(name)`, against what the plant says of the chassis (its velocity and pose at
each sample), at rest, in a steady turn and while accelerating, on the default continuous
plant (CENIC) and SAP's discrete one; and the noise's replay.

Samples come every 10 ms (100 Hz, the plant's step): the one at t is taken as the simulator
steps away from t, so after `advance_to(t + 0.01)` the latest reading is t's, and the chassis
state it saw is the one `advance_to(t)` left."""

import copy
import math

import numpy as np
import pytest
from pydrake.math import RollPitchYaw

from conftest import SAP, make_sim

G = 9.81  # m/s^2: Drake's default gravity
IDEAL = ("gyro_noise_density: 0, gyro_random_walk: 0, accel_noise_density: 0, "
         "accel_random_walk: 0")
STEP = 0.01  # s: the plant's step and the IMU's period
PLANTS = [pytest.param((), id="cenic"), pytest.param((SAP,), id="sap")]


def imus(**sensors: str) -> str:
    """A scenario override giving the robot these IMUs ({name: YAML fields})."""
    maps = ", ".join(f"{name}: {{{fields}}}" for name, fields in sensors.items())
    return f"robots: {{corobot: {{imus: {{{maps}}}}}}}"


def at(k: int) -> float:
    """s: the k-th step's time (k x 0.01 in one rounding, as the plant's own)."""
    return k * STEP


def specific_force(pose, a_B) -> np.ndarray:
    """m/s^2: what a chassis-aligned accelerometer reads when the chassis accelerates by a_B
    (in its own axes) at `pose`: a - g in the chassis frame."""
    R_WB = RollPitchYaw(pose.roll, pose.pitch, pose.yaw).ToRotationMatrix()
    return np.asarray(a_B) + R_WB.inverse() @ np.array([0.0, 0.0, G])


@pytest.mark.parametrize("plant", PLANTS)
def test_at_rest_it_reads_gravity_up_in_its_frame_and_no_rotation(plant):
    """Settled on its tyres, the chassis is level to 0.1 mrad and still: the chassis-aligned
    IMU reads (0, 0, 9.81) m/s^2 and no rotation; one rolled 90 deg reads the up on its +y;
    the default one (noisy) reads the same to within its noise (2e-3 m/s^2/sqrt(Hz) x 10
    sqrt(Hz) = 0.02 m/s^2 a sample; 1.7e-3 rad/s)."""
    sim = make_sim(imus(imu="", level=IDEAL, rolled=f"{IDEAL}, X_PB: {{base_frame: chassis, "
                        "rotation: !Rpy {deg: [90, 0, 0]}}"), *plant)
    robot = sim.robot()
    sim.advance_to(0.5)
    level, rolled, noisy = (robot.reading(name) for name in ("level", "rolled", "imu"))
    assert level.time == rolled.time == pytest.approx(0.49, abs=1e-9)
    np.testing.assert_allclose(level.linear_acceleration, (0.0, 0.0, G), atol=5e-3)
    np.testing.assert_allclose(rolled.linear_acceleration, (0.0, G, 0.0), atol=5e-3)
    np.testing.assert_allclose(level.angular_velocity, 0.0, atol=1e-3)
    np.testing.assert_allclose(noisy.linear_acceleration, (0.0, 0.0, G), atol=5 * 0.02)
    np.testing.assert_allclose(noisy.angular_velocity, 0.0, atol=5 * 1.7e-3)
    assert level.orientation == pytest.approx((0.0, 0.0, 0.0, 1.0), abs=1e-4)
    assert rolled.orientation == pytest.approx(
        (math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4)), abs=1e-4)


@pytest.mark.parametrize("plant", PLANTS)
def test_in_a_steady_turn_it_reads_the_yaw_rate_and_the_centripetal_acceleration(plant):
    """SetVelocity(0.3 m/s, 1 rad/s): once the turn is steady, an IMU 0.1 m ahead of the
    chassis origin reads the chassis' yaw rate and the acceleration of a point on a turning
    body, w x v + w x (w x p): (-w v_lat - w^2 d, w v_fwd, 0) with v the chassis origin's
    velocity in its axes, plus gravity as the chassis' tilt puts it. Compared over 0.5 s
    (50 samples) of means: each sample carries the tyres' contact vibration (its
    difference from the smooth w x v is about 0.04 m/s^2 on y), and the tolerance is 4
    standard errors of the mean of the differences (0.011 m/s^2 on y)."""
    d = 0.1
    sim = make_sim(imus(ahead=f"{IDEAL}, X_PB: {{base_frame: chassis, translation: "
                        f"[{d}, 0, 0]}}"), *plant)
    robot = sim.robot()
    robot.set_velocity(0.3, 1.0)
    sim.advance_to(at(70))  # steady from ~0.6 s: yaw rate 0.98 rad/s, forward 0.28 m/s
    expected, read = [], []
    for k in range(70, 120):
        v, pose = robot.velocity(), robot.pose()
        w = v.yaw_rate
        expected.append((*specific_force(pose, (-w * v.lateral - w * w * d, w * v.forward, 0.0)),
                         w))
        sim.advance_to(at(k + 1))
        r = robot.reading("ahead")
        assert r.time == pytest.approx(at(k), abs=1e-9)
        read.append((*r.linear_acceleration, r.angular_velocity[2]))
    expected, read = np.asarray(expected), np.asarray(read)
    error = read - expected
    tolerance = 4 * error.std(axis=0) / math.sqrt(len(error)) + 1e-6
    assert (abs(error.mean(axis=0)) < tolerance).all(), (error.mean(axis=0), tolerance)
    assert tolerance[1] < 0.015  # m/s^2, 5% of the 0.28 centripetal: a real check
    assert expected[:, 1].mean() == pytest.approx(0.28, abs=0.01)  # 0.3 m/s x ~0.98 rad/s


@pytest.mark.parametrize("plant", PLANTS)
def test_while_accelerating_it_reads_the_forward_specific_force(plant):
    """SetPower(1, 1) from rest: an IMU at the chassis origin reads, each sample, the
    chassis' forward speed gained over the sample period / 0.01 s, minus g sin(pitch) (the
    chassis pitches back by ~1 mrad under the torque), to within 1e-3 m/s^2 (the chassis'
    small vertical and yaw motion) while the acceleration is ~1.8 m/s^2."""
    sim = make_sim(imus(origin=f"{IDEAL}, X_PB: {{base_frame: chassis, translation: "
                        "[0, 0, 0]}"), *plant)
    robot = sim.robot()
    sim.advance_to(at(30))
    robot.set_power(1.0, 1.0)
    speed = [robot.velocity().forward]
    forward = []
    for k in range(30, 60):
        pitch = robot.pose().pitch
        sim.advance_to(at(k + 1))
        speed.append(robot.velocity().forward)
        r = robot.reading("origin")
        assert r.time == pytest.approx(at(k), abs=1e-9)
        if k > 30:  # the sample at k: the speed gained from k - 1 to k
            gained = (speed[-2] - speed[-3]) / STEP
            assert r.linear_acceleration[0] == pytest.approx(gained - G * math.sin(pitch),
                                                             abs=1e-3)
        forward.append(r.linear_acceleration[0])
    assert max(forward) > 1.5  # m/s^2: it did accelerate


def readings(sim, name: str, steps: int) -> list:
    out = []
    for k in range(1, steps + 1):
        sim.advance_to(at(k))
        out.append(sim.robot().reading(name))
    return out


def test_the_noise_replays_bit_for_bit_and_follows_the_seed():
    """The default (noisy) IMU while driving: a reset replays the readings exactly, as does
    another simulation of the same scenario; another random_seed draws other noise, the
    same whether built with it or reset to it."""
    drive = "robots: {corobot: {commands: [!SetVelocity {linear: 0.3, angular: 1.0}]}}"
    sim = make_sim(imus(imu=""), drive)
    first = readings(sim, "imu", 30)
    sim.reset()
    assert readings(sim, "imu", 30) == first
    assert readings(make_sim(imus(imu=""), drive), "imu", 30) == first
    other = readings(make_sim(imus(imu=""), drive, "random_seed: 7"), "imu", 30)
    assert other != first
    assert [r.time for r in other] == [r.time for r in first]
    reseeded = copy.deepcopy(sim.scenario)
    reseeded.random_seed = 7
    sim.reset(reseeded)  # the same diagram, keyed by the new seed
    assert readings(sim, "imu", 30) == other
