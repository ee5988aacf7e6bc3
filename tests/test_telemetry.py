"""Issue 14: dead-reckoning odometry (`systems.dead_reckoning`) and its calibration
(`analysis.odometry_calibration`), and the wheels' contact telemetry (`systems.contact`):
each system alone, then in the simulation."""

import math

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw

from conftest import Stepper
from corobot_drake.analysis import odometry_calibration as oc
from corobot_drake.config.scenario import Drive, load_scenario
from corobot_drake.model import dimensions as dim
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.simulation import Simulation, quiet_drake_warnings
from corobot_drake.study.metrics import METRICS, RobotRun
from corobot_drake.systems.dead_reckoning import DeadReckoning

PERIOD = 1 / 60
TICK = 2 * math.pi / dim.ENCODER_TICKS_PER_REVOLUTION  # rad per encoder count


def odometry(radius=0.06, track=0.3, start=(1.0, 2.0, 0.5)) -> Stepper:
    s = Stepper(DeadReckoning(Drive(effective_wheel_radius=radius, effective_track_width=track),
                              PERIOD), PERIOD)
    s.fix("chassis_pose", RigidTransform(RollPitchYaw(0, 0, start[2]), [start[0], start[1], 0]))
    s.fix("encoder_ticks", [100.0, 100.0])  # the counts at the start are not motion
    return s


def test_odometry_starts_at_the_start_pose_and_integrates_straight_rolling():
    s = odometry()
    s.tick()
    assert s.output("pose") == pytest.approx([1.0, 2.0, 0.5], abs=1e-15)
    s.fix("encoder_ticks", [700.0, 700.0])  # one revolution each: 2 pi R along the heading
    s.tick()
    d = 2 * math.pi * 0.06
    assert s.output("pose") == pytest.approx([1 + d * math.cos(0.5), 2 + d * math.sin(0.5), 0.5],
                                             abs=1e-12)


def test_odometry_turns_by_the_wheel_difference_over_the_track():
    s = odometry(start=(0.0, 0.0, 0.0))
    s.tick()
    s.fix("encoder_ticks", [50.0, 150.0])  # a spin: right +100 counts, left -50
    s.tick()
    x, y, yaw = s.output("pose")
    left, right = -50 * TICK * 0.06, 50 * TICK * 0.06
    assert yaw == pytest.approx((right - left) / 0.3, abs=1e-12)
    assert math.hypot(x, y) == pytest.approx(0.0, abs=1e-12)  # equal and opposite: in place


def synthetic_log(radius: float, track: float) -> oc.PoseLog:
    """True motion from the kinematic model at (radius, track), encoders quantized to whole
    counts: drives, turns both ways, drives at once (an arc)."""
    t = np.arange(0, 40, 0.01)
    left_rate = np.where(t < 10, 2.0, np.where(t < 20, -1.5, np.where(t < 30, 1.5, 3.0)))
    right_rate = np.where(t < 10, 2.0, np.where(t < 20, 1.5, np.where(t < 30, -1.5, 2.0)))
    angle = np.column_stack([np.cumsum(left_rate), np.cumsum(right_rate)]) * 0.01
    pose = [(0.0, 0.0, 0.0)]
    for step in np.diff(angle, axis=0) * radius:
        pose.append(oc.advance_pose(*pose[-1], *step, track))
    ticks = np.floor(angle / TICK) * TICK
    return oc.PoseLog(t, ticks, np.array(pose))


def test_calibration_finds_the_radius_and_track_of_a_synthetic_log():
    log = synthetic_log(0.0598, 0.377)
    fit = oc.fit_odometry(log)
    # Quantization (1 count = 0.6 mm of rim) telescopes over the windows: 0.1% is generous.
    assert fit.effective_wheel_radius == pytest.approx(0.0598, rel=1e-3)
    assert fit.effective_track_width == pytest.approx(0.377, rel=1e-3)
    assert oc.end_error(log, 0.0598, 0.377) < 0.2 * oc.end_error(log, dim.WHEEL_RADIUS, dim.TRACK)


def test_a_log_that_never_turns_cannot_fit_the_track():
    log = synthetic_log(0.06, 0.3)
    log.rotation[:, 1] = log.rotation[:, 0]
    with pytest.raises(oc.LogError, match="both drive and turn"):
        oc.fit_odometry(log)


@pytest.fixture(scope="module")
def sim():
    quiet_drake_warnings()
    return Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[oc.physics_only("corobot")]))


def test_loads_at_rest_sum_to_the_robots_weight(sim):
    sim.reset()
    sim.advance(0.5)  # settled on its tyres (they take the load in ~0.1 s)
    robot = sim.robot()
    plant = sim.station.plant
    mass = plant.CalcTotalMass(plant.GetMyContextFromRoot(sim.context),
                               [sim.station.robots["corobot"].model_instance])
    assert mass == pytest.approx(dim.TOTAL_BODY_MASS + 4 * dim.WHEEL_MASS)  # 4.03 kg
    loads = robot.wheel_loads()
    # At rest the ground carries the robot: the solver's equilibrium matches to ~1e-7; 0.5%
    # allows the creep of a robot at rest (issue 14 point 9) and a coarser step.
    assert sum(loads.values()) == pytest.approx(mass * 9.81, rel=5e-3)
    # Centred mass: each wheel a quarter, within 1% (the chassis' own small asymmetries).
    for load in loads.values():
        assert load == pytest.approx(mass * 9.81 / 4, rel=1e-2)
    assert all(abs(v) < 1e-4 for v in robot.wheel_slip().values())
    summary = robot.summary()
    assert summary["wheel_loads_N"] == list(loads.values())
    run = RobotRun(sim, robot, robot.pose(), robot.heading())
    assert METRICS["wheel_loads"](run) == loads


def test_a_spin_scrubs_every_wheel_sideways_and_full_power_slips_forward(sim):
    sim.reset()
    robot = sim.robot()
    robot.set_power(-0.5, 0.5)
    sim.advance(2.0)
    lateral = robot.wheel_lateral_slip()
    # Spinning at omega, a wheel at (+-a, +-b) moves sideways at omega a (0.092 m x ~1.6 rad/s
    # = 0.15 m/s): front wheels one way, rear the other. Half of that is a clear margin.
    omega = robot.velocity().yaw_rate
    for wheel, v in lateral.items():
        sign = 1.0 if wheel.startswith("front") else -1.0
        assert sign * v == pytest.approx(omega * dim.HALF_WHEELBASE, rel=0.05)
        assert abs(v) > 0.05
    sim.reset()  # facing +x again, away from the box
    robot.set_power(1.0, 1.0)
    sim.advance(2.0)
    slip = robot.wheel_slip()
    speed = robot.velocity().forward
    # Driving at top speed the tyres creep: the wheels turn faster than they travel, by the
    # 0.8% the effective radius and the servo's traction take (less than 2%, more than 0.2%).
    for v in slip.values():
        assert -0.02 * speed < v < -0.002 * speed


def test_odometry_in_the_simulation_is_calibrated_and_the_nominal_one_overcounts(sim):
    sim.reset()
    robot = sim.robot()
    odo = robot.odometry()
    assert (odo.x, odo.y, odo.yaw) == (0.0, 0.0, 0.0)  # the start pose
    drive = sim.scenario.robots["corobot"].drive
    assert drive.effective_wheel_radius < dim.WHEEL_RADIUS  # the shipped calibration
    start = robot.pose()
    assert robot.drive_distance(0.5, 0.5).succeeded
    sim.advance(0.3)
    pose, odo = robot.pose(), robot.odometry()
    travelled = math.hypot(pose.x - start.x, pose.y - start.y)
    # Calibrated: within 0.2% (1 mm of 0.5 m: the ramps' slip and the 0.6 mm quantization).
    assert math.hypot(odo.x - start.x, odo.y - start.y) == pytest.approx(travelled, rel=2e-3)
    log = oc.pose_log_of(robot.run_log())
    # The system's integration and the offline one agree on the same ticks (60 Hz vs 100 Hz
    # sampling of one straight leg: well under a millimetre).
    offline = oc.dead_reckon(log, drive.effective_wheel_radius, drive.effective_track_width)[-1]
    assert math.hypot(offline[0] - odo.x, offline[1] - odo.y) < 5e-4
    # The tyres roll on ~0.0598 m, not 0.060325: the nominal odometry over-counts by ~0.8%
    # (0.5% to 1.2% allows the slip of the ramps and the quantization).
    nominal = oc.dead_reckon(log, dim.WHEEL_RADIUS, dim.TRACK)[-1]
    assert 1.005 < math.hypot(nominal[0] - start.x, nominal[1] - start.y) / travelled < 1.012
    assert robot.summary()["odometry"] == {"x": odo.x, "y": odo.y, "yaw": odo.yaw}
