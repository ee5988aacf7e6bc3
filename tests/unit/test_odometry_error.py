"""The dead reckoning's travel and the odometry's error model (`systems.odometry_error`):
the distance and turning it counts since a reset, the variances it grows with them, per robot,
and /wheel_odom's covariances made from them in a simulation."""

import math

import pytest
from pydrake.math import RigidTransform, RollPitchYaw

from conftest import Stepper
from corobot_drake.config.scenario import Drive, load_scenario
from corobot_drake.robots import robot_spec
from corobot_drake.systems.dead_reckoning import DeadReckoning
from corobot_drake.systems.odometry_error import (
    DRIVE_TEST_PATH,
    OdometryErrorModel,
    error_model,
)

PERIOD = 0.01
RADIUS, TRACK, TICKS = 0.06, 0.3, 600
METRES_PER_TICK = 2 * math.pi * RADIUS / TICKS


def dead_reckoning() -> Stepper:
    s = Stepper(DeadReckoning(Drive(effective_wheel_radius=RADIUS, effective_track_width=TRACK),
                              PERIOD, TICKS), PERIOD)
    s.fix("chassis_pose", RigidTransform(RollPitchYaw(0, 0, 0.3), [1.0, 2.0, 0.0]))
    s.fix("encoder_ticks", [100.0, 100.0])  # the counts at the start are not travel
    return s


def test_travel_counts_distance_both_ways_and_turning_either_way():
    """Forward and back add up (the error grows either way), as do turns left and right; a
    spin in place turns without rolling."""
    s = dead_reckoning()
    s.tick()
    assert s.output("travel").tolist() == [0.0, 0.0]
    for ticks in ([200.0, 200.0], [150.0, 150.0], [100.0, 200.0], [200.0, 100.0]):
        s.fix("encoder_ticks", ticks)
        s.tick()
    rolled, turned = s.output("travel")
    # 100 counts forward, 50 back; the spins roll 0 (equal and opposite wheels)
    assert rolled == pytest.approx(150 * METRES_PER_TICK, rel=1e-12)
    # the spins' wheel differences: +100 counts (left -50, right +50), then -200
    assert turned == pytest.approx(300 * METRES_PER_TICK / TRACK, rel=1e-12)


def test_a_teleport_resets_the_travel_and_it_counts_on_from_there():
    s = dead_reckoning()
    s.tick()
    s.fix("encoder_ticks", [700.0, 700.0])  # a revolution before the teleport
    s.tick()
    assert s.output("travel")[0] == pytest.approx(2 * math.pi * RADIUS, rel=1e-12)
    s.system.Teleport(s.system.GetMyMutableContextFromRoot(s.context), 0.0, 0.0, 0.0)
    assert s.output("travel").tolist() == [0.0, 0.0]
    s.fix("encoder_ticks", [760.0, 760.0])  # a tenth of one after it
    s.tick()
    assert s.output("travel")[0] == pytest.approx(0.2 * math.pi * RADIUS, rel=1e-12)


def test_travel_replays_bit_identically_after_a_reset():
    """The travel is the Context's state: a second run from a fresh context is the first."""
    runs = []
    for _ in range(2):
        s = dead_reckoning()
        for k in range(20):
            s.fix("encoder_ticks", [100.0 + 7 * k, 100.0 + 3 * k * k % 11])
            s.tick()
        runs.append(s.output("travel").tolist())
    assert runs[0] == runs[1]


CALIBRATED = Drive(effective_wheel_radius=0.059815, effective_track_width=0.37728)
"""The Corobot's drive with the odometry its drive test was measured with."""


def test_the_variances_grow_with_the_distance_and_the_turning():
    model = error_model(robot_spec("corobot"), CALIBRATED)
    x0, y0, yaw0 = model.pose_variances(0.0, 0.0)
    x1, _, yaw1 = model.pose_variances(1.0, 0.0)
    x2, _, yaw2 = model.pose_variances(2.0, math.pi)
    assert x0 == y0 > 0 and yaw0 > 0  # the encoders' quantization: never exact
    assert x0 < x1 < x2 and yaw0 == yaw1 < yaw2  # a straight leg leaves the heading's
    tick = 2 * math.pi * 0.059815 / 600
    assert x0 == pytest.approx(tick ** 2 / 24, rel=1e-12)
    assert yaw0 == pytest.approx(tick ** 2 / (6 * 0.37728 ** 2), rel=1e-12)


def test_after_the_drive_test_the_calibrated_deviation_is_its_measured_error():
    """The stated derivation: a random walk whose deviation over the drive test's path is the
    end error it measured (the quantization floor and the calibration's rounding aside)."""
    for robot in ("corobot", "burger"):  # the shipped robots whose files state a drive test
        test = robot_spec(robot).odometry_test
        drive = Drive(effective_wheel_radius=test.radius, effective_track_width=test.track)
        model = error_model(robot_spec(robot), drive)
        position, _, heading = model.pose_variances(*DRIVE_TEST_PATH)
        assert math.sqrt(position) == pytest.approx(test.end_error, rel=0.02), robot
        assert math.sqrt(heading) == pytest.approx(test.heading_error, rel=0.02), robot


def test_the_corobot_and_the_burger_differ_as_their_error_models_do():
    """Each in its shipped scenario: the Corobot's carries its calibration, the Burger's its
    nominal figures, 0.9% off in radius and 1.9% in radius over track; the Burger's encoders
    count 4096 a revolution of a 33 mm wheel (51 um) against the Corobot's 600 of 60 mm
    (0.63 mm)."""
    corobot, burger = (error_model(robot_spec(name), next(iter(load_scenario(
        f"scenarios/{name}.yaml").robots.values())).drive) for name in ("corobot", "burger"))
    assert burger.scale_error == pytest.approx(0.033 / 0.0327 - 1, rel=1e-9)
    assert corobot.scale_error < 1e-4  # the scenario's calibration, rounded
    for rolled, turned in ((1.0, 0.0), (5.0, 2 * math.pi), (20.0, 10.0)):
        c, b = corobot.pose_variances(rolled, turned), burger.pose_variances(rolled, turned)
        assert b[0] > 10 * c[0]  # uncalibrated: its radius' error soon dominates
    # at rest, just reset: the Burger's fine encoders know its pose better
    assert burger.pose_variances(0, 0)[0] < corobot.pose_variances(0, 0)[0] / 100
    assert burger.twist_variances()[0] < corobot.twist_variances()[0] / 100


def test_a_robot_not_measured_gets_the_worst_measured_errors():
    """The Pioneer has no drive test: its nominal figures are taken as far off as the
    measured robots' were (the Corobot's skid steer: 70% in radius over track)."""
    model = error_model(robot_spec("pioneer"), Drive(effective_wheel_radius=0.1075,
                                                     effective_track_width=0.4))
    corobot = robot_spec("corobot").odometry_test
    assert model.turn_error == pytest.approx(
        corobot.turn_error(corobot.nominal_radius, corobot.nominal_track), rel=1e-12)
    assert model.turn_error > 0.5


def test_the_twist_variances_are_the_encoder_speeds_quantization():
    model = OdometryErrorModel.of(TICKS, Drive(effective_wheel_radius=RADIUS,
                                               effective_track_width=TRACK,
                                               control_period=PERIOD),
                                  robot_spec("corobot").odometry_test)
    speed = (METRES_PER_TICK / PERIOD) ** 2  # one count per period, (m/s)^2
    assert model.twist_variances() == pytest.approx((speed / 12, speed / (3 * TRACK ** 2)),
                                                    rel=1e-12)


def test_wheel_odom_covariances_grow_as_the_robot_drives_and_reset_on_set_pose():
    """End to end: the Corobot's ROS 2 state publisher in a simulation (no DDS: a bus without
    sinks) makes /wheel_odom's message from the dead reckoning's travel; 0.6 s at 0.3 m/s
    grows its covariances, a /set_pose (the same command) puts them back at the floor."""
    pytest.importorskip("rosbags", reason="the [ros2] extra (tools/setup installs it)")
    from functools import partial

    from corobot_drake.config.presets import physics_only_overrides
    from corobot_drake.resources import DEFAULT_SCENARIO
    from corobot_drake.ros2.bus import Bus
    from corobot_drake.ros2.publishers import add_ros2_topics
    from corobot_drake.simulation import Simulation, quiet_drake_warnings

    quiet_drake_warnings()
    scenario = load_scenario(DEFAULT_SCENARIO, overrides=[*physics_only_overrides()])
    sim = Simulation(scenario, extras=[partial(add_ros2_topics, Bus())])
    publisher = sim.station.diagram.GetSubsystemByName("corobot.ros2_state")
    model = error_model(robot_spec("corobot"), scenario.robots["corobot"].drive)

    def variances():
        msg = publisher.wheel_odometry(publisher.GetMyContextFromRoot(sim.context))
        return [msg.pose.covariance[i] for i in (0, 7, 35)]

    sim.advance(0.05)
    floor = variances()
    # at rest: the quantization's floor, and the ~1 mm the tyres roll settling at the start
    assert floor == pytest.approx(model.pose_variances(0.0, 0.0), rel=0.05)
    robot = sim.robot()
    start = robot.odometry().x  # facing +x
    robot.set_velocity(0.3, 0.0)
    grown = []
    for _ in range(3):
        sim.advance(0.2)
        grown.append(variances())
    x = [v[0] for v in grown]
    assert floor[0] < x[0] < x[1] < x[2]
    rolled = robot.odometry().x - start  # straight ahead: the distance rolled
    assert x[2] == pytest.approx(model.pose_variances(rolled, 0.0)[0], rel=0.05)
    robot.set_velocity(0.0, 0.0)
    assert robot.set_pose(0.0, 0.0, 0.0).wait(5.0).status == "succeeded"
    # the travel since: the settling's ~1 mm again, as at the start
    assert variances() == pytest.approx(floor, rel=0.05) and variances()[0] < x[0]
