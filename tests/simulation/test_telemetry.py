"""Dead-reckoning odometry (`systems.dead_reckoning`) and its calibration
(`corobot_drake.tuning.odometry_calibration`), the wheels' contact telemetry
(`systems.contact`), the tip-over margin (`systems.stability`) and the slip in Meshcat
(`systems.slip_markers`): each system alone, and in the simulation."""

import math

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import MultibodyPlant

from conftest import Stepper
from corobot_drake.config.scenario import CENIC_PLANT, Drive, load_scenario
from corobot_drake.model.sdf import corobot_sdf
from corobot_drake.resources import DEFAULT_SCENARIO, make_parser
from corobot_drake.robots import robot_spec
from corobot_drake.simulation import Simulation, quiet_drake_warnings
from corobot_drake.study.metrics import METRICS, RobotRun
from corobot_drake.systems import contact
from corobot_drake.systems.dead_reckoning import (
    HISTORY,
    DeadReckoning,
    PoseIntegrator,
    advance_pose,
    encoder_history,
)
from corobot_drake.systems.slip_markers import MARKER_PERIOD, SlipMarkers
from corobot_drake.systems.stability import TipMargin
from corobot_drake.tuning import odometry_calibration as oc
from lab.bench import physics_only_overrides

PERIOD = 1 / 60
SPEC = robot_spec("corobot")
"""The Corobot as its robot file and model say."""
TICK = 2 * math.pi / SPEC.encoder_ticks_per_revolution  # rad per encoder count


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


def test_odometry_given_a_start_carries_on_from_it():
    """A saved scene's start: the pose (yaw unwrapped) and the counts last integrated, so the
    counts since then (one revolution here) are motion at the first update; with the pose
    alone the counts at the start are the baseline."""
    s = odometry(start=(0.0, 0.0, 0.0))
    context = s.system.GetMyMutableContextFromRoot(s.context)
    s.system.SetStart(context, [3.0, 4.0, 2 * math.pi + 0.1, -500.0, -500.0])
    s.tick()
    d = 2 * math.pi * 0.06
    assert s.output("pose") == pytest.approx([3 + d * math.cos(0.1), 4 + d * math.sin(0.1), 0.1],
                                             abs=1e-12)
    assert s.system.State(context) == pytest.approx(
        [3 + d * math.cos(0.1), 4 + d * math.sin(0.1), 2 * math.pi + 0.1, 100.0, 100.0],
        abs=1e-12)
    posed = odometry(start=(0.0, 0.0, 0.0))
    posed.system.SetStart(posed.system.GetMyMutableContextFromRoot(posed.context),
                          [3.0, 4.0, 0.1])
    posed.tick()
    assert posed.output("pose") == pytest.approx([3.0, 4.0, 0.1], abs=1e-15)
    with pytest.raises(ValueError, match="needs 0, 3 or 5 values, got 4"):
        s.system.SetStart(context, [1.0, 2.0, 3.0, 4.0])


def test_odometry_teleported_integrates_on_from_the_new_pose():
    """A teleport puts the dead reckoning at the new pose; the counts rolled before it are
    folded in first (not motion after it), the counts after it are motion from there."""
    s = odometry(start=(0.0, 0.0, 0.0))
    s.tick()
    s.fix("encoder_ticks", [700.0, 700.0])  # a revolution before the teleport
    s.tick()
    s.system.Teleport(s.system.GetMyMutableContextFromRoot(s.context), 5.0, -1.0, math.pi / 2)
    assert s.output("pose") == pytest.approx([5.0, -1.0, math.pi / 2], abs=1e-15)
    s.fix("encoder_ticks", [1300.0, 1300.0])  # a revolution after it: along +y
    s.tick()
    d = 2 * math.pi * 0.06
    assert s.output("pose") == pytest.approx([5.0, -1.0 + d, math.pi / 2], abs=1e-12)


def test_odometry_turns_by_the_wheel_difference_over_the_track():
    s = odometry(start=(0.0, 0.0, 0.0))
    s.tick()
    s.fix("encoder_ticks", [50.0, 150.0])  # a spin: right +100 counts, left -50
    s.tick()
    x, y, yaw = s.output("pose")
    left, right = -50 * TICK * 0.06, 50 * TICK * 0.06
    assert yaw == pytest.approx((right - left) / 0.3, abs=1e-12)
    assert math.hypot(x, y) == pytest.approx(0.0, abs=1e-12)  # equal and opposite: in place


def test_the_encoder_history_keeps_exact_samples_newest_first():
    s = Stepper(encoder_history(PERIOD, length=3), PERIOD)
    samples = [[0.1, -7.0], [1e9 + 0.3, 2.0 / 3.0], [-1e-300, 5.0], [12345.678, -0.25]]
    for sample in samples:
        s.fix("u0", sample)
        s.tick()
    history = s.system.get_output_port().Eval(s.context)
    assert history.tolist() == [4.0, *samples[3], *samples[2], *samples[1]]  # bit for bit


def test_odometry_folds_the_samples_as_an_update_every_period_would():
    """A random walk of counts over a number of periods that is not a multiple of the fold's:
    the pose read after every period is, bit for bit, the per-period integration's."""
    s = odometry(start=(0.3, -0.2, 3.0))
    rng = np.random.default_rng(7)
    counts = np.array([100.0, 100.0])
    x, y, yaw, last = 0.3, -0.2, 3.0, counts.copy()
    k = 2 * math.pi * 0.06 / SPEC.encoder_ticks_per_revolution
    for period in range(5 * HISTORY + 3):
        s.tick()  # takes the counts fixed before it
        assert s.output("pose").tolist() == [x, y, math.remainder(yaw, 2 * math.pi)], period
        counts = counts + rng.integers(-3, 12, size=2)
        s.fix("encoder_ticks", counts)
        x, y, yaw = advance_pose(x, y, yaw, *(k * (counts - last)), 0.3)
        last = counts
    context = s.system.GetMyMutableContextFromRoot(s.context)
    s.tick()
    assert s.system.State(context) == [x, y, yaw, *counts]


def test_odometry_refuses_a_history_it_has_fallen_behind():
    """More samples since the last fold than the history holds would lose motion: an error,
    not a wrong pose."""
    integrator = PoseIntegrator(Drive(), 1.0, length=2)
    context = integrator.CreateDefaultContext()
    integrator.GetInputPort("encoder_history").FixValue(context, [3.0, 1, 1, 0, 0])
    with pytest.raises(RuntimeError, match="3 encoder samples to fold, the history holds 2"):
        integrator.GetOutputPort("pose").Eval(context)


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
    nominal = oc.end_error(log, SPEC.wheel_radius, SPEC.track)
    assert oc.end_error(log, 0.0598, 0.377) < 0.2 * nominal


def test_a_log_that_never_turns_cannot_fit_the_track():
    log = synthetic_log(0.06, 0.3)
    log.rotation[:, 1] = log.rotation[:, 0]
    with pytest.raises(oc.LogError, match="both drive and turn"):
        oc.fit_odometry(log)


@pytest.fixture(scope="module")
def sim():
    quiet_drake_warnings()
    return Simulation(load_scenario(DEFAULT_SCENARIO, overrides=physics_only_overrides()))


def test_loads_at_rest_sum_to_the_robots_weight(sim):
    sim.reset()
    sim.advance(0.5)  # settled on its tyres (they take the load in ~0.1 s)
    robot = sim.robot()
    plant = sim.station.plant
    mass = plant.CalcTotalMass(plant.GetMyContextFromRoot(sim.context),
                               [sim.station.robots["corobot"].model_instance])
    assert mass == pytest.approx(SPEC.mass)  # 4.03 kg
    loads = robot.wheel_loads()
    # At rest the ground carries the robot: the solver's equilibrium matches to ~1e-7; 0.5%
    # allows the creep of a robot at rest and a coarser step.
    assert sum(loads.values()) == pytest.approx(mass * 9.81, rel=5e-3)
    # Centred mass: each wheel a quarter, within 1% (the chassis' own small asymmetries).
    for load in loads.values():
        assert load == pytest.approx(mass * 9.81 / 4, rel=1e-2)
    # At rest the wheels creep by ~1e-5 m/s: against the 1 cm/s floor, ~0 (measured 2e-7
    # and 0.05 deg); 1e-3 and 0.2 deg leave room for the creep to grow fourfold.
    assert all(abs(v) < 1e-3 for v in robot.wheel_slip_ratio().values())
    assert all(abs(v) < 0.2 for v in robot.wheel_slip_angle().values())
    summary = robot.summary()
    assert summary["wheel_loads_N"] == list(loads.values())  # WHEEL_NAMES order: FL FR RL RR
    assert summary["slip"] == {"ratio": list(robot.wheel_slip_ratio().values()),
                               "angle_deg": list(robot.wheel_slip_angle().values())}
    run = RobotRun(sim, robot, robot.pose(), robot.heading())
    assert METRICS["wheel_loads"](run) == loads
    assert METRICS["wheel_slip"](run) == robot.wheel_slip_ratio()


def momentum(step=0.01, com_in_chassis=(0.0, 0.0, 0.05)) -> contact.RobotMomentum:
    return contact.RobotMomentum(mass=4.0, com_in_chassis=com_in_chassis, gravity=9.81, chassis=1,
                                 bodies=frozenset(), geometries=frozenset(), step=step)


def test_the_last_physics_step_before_a_time_is_on_the_grid():
    m = momentum()
    # On the grid (within rounding, either side) the step before; between, the one below.
    for t, last in ((0.3, 0.29), (0.30000000000000004, 0.29), (0.29999999999999993, 0.29),
                    (0.3005, 0.3), (0.01, 0.0), (2.3, 2.29)):
        assert m.last_step(t) == pytest.approx(last, abs=1e-12), t


def test_the_robot_s_vertical_force_is_its_momentum_change_and_weight():
    m = momentum()
    upright, still = np.eye(3), np.zeros(6)
    assert m.vertical_force(upright, still, still, 0.01) == pytest.approx(4.0 * 9.81)
    # The origin rose 1 cm/s faster over 10 ms: a_z 1 m/s^2.
    assert m.vertical_force(upright, [0, 0, 0, 0, 0, 0.01], still, 0.01) == pytest.approx(
        4.0 * (9.81 + 1.0))
    # Spinning at 2 rad/s about x with the CoM 5 cm up: its centripetal acceleration points
    # down the CoM's lever, -w^2 r = -0.2 m/s^2; and an angular acceleration of 10 rad/s^2
    # about y moves a CoM 5 cm ahead (x) down at alpha x r_x = 0.5 m/s^2.
    spin = [2.0, 0, 0, 0, 0, 0]
    assert m.vertical_force(upright, spin, spin, 0.01) == pytest.approx(4.0 * (9.81 - 0.2))
    ahead = momentum(com_in_chassis=(0.05, 0.0, 0.0))
    assert ahead.vertical_force(upright, [0, 0.1, 0, 0, 0, 0], still, 0.01) == pytest.approx(
        4.0 * (9.81 - 0.5))


def test_the_momentum_s_force_is_shared_as_the_contact_law_shares_it():
    assert contact.momentum_shares([1.0, 2.0, 3.0, 4.0], 10.0, 20.0) == [2.0, 4.0, 6.0, 8.0]
    # The chassis carries part of the law's total (against a box): the wheels keep their share.
    assert contact.momentum_shares([1.0, 1.0, 1.0, 1.0], 8.0, 16.0) == [2.0] * 4
    assert contact.momentum_shares([0.0] * 4, 0.0, 39.0) == [0.0] * 4  # nothing touches


@pytest.mark.parametrize("plant", ["sap", "cenic"])
def test_loads_while_driving_fast_sum_to_the_robot_s_weight(plant):
    """Straight at full power (0.6 m/s) the centre of mass barely moves up or down, so the
    wheels carry the weight: SAP's contact results are its solver's forces; a continuous
    plant's law alone reads a third low here (0.60-0.70 of the weight), CENIC's loads come
    from the momentum. Measured within 4% at every step over 1-1.5 s (the chassis rocks on
    its polygonal tyres), 0.1% on average: 5% and 1%."""
    overrides = ["robots: {corobot: {commands: [!SetPower {left: 1, right: 1}]}}",
                 *physics_only_overrides()]
    if plant == "cenic":
        overrides.append(CENIC_PLANT % 0.01)
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=overrides))
    weight = SPEC.mass * 9.81
    sim.advance(1.0)
    sums = []
    for k in range(1, 51):
        sim.advance_to(1.0 + k * 0.01)
        sums.append(sum(sim.robot().wheel_loads().values()) / weight)
    assert sums == pytest.approx([1.0] * len(sums), abs=0.05)
    assert np.mean(sums) == pytest.approx(1.0, abs=0.01)


def com_height() -> float:
    """The robot's centre of mass above the ground, m, as its model's masses place it (its
    measured spec: chassis and platform boxes at their centres, the wheels at their axles,
    0.1204)."""
    return SPEC.com[2]


def pitched_margin_deg(pitch_deg: float) -> float:
    """The tip margin of the rigid robot pitched by `pitch_deg` (either way) about one axle,
    its wheels there on the ground: the angle at that wheel's bottom between the vertical and
    the centre of mass, which sits half a wheelbase in and `com_height() - R` above the axle."""
    a, up, R = SPEC.wheelbase / 2, com_height() - SPEC.wheel_radius, SPEC.wheel_radius
    phi = math.radians(abs(pitch_deg))
    return math.degrees(math.atan2(a * math.cos(phi) - up * math.sin(phi),
                                   a * math.sin(phi) + up * math.cos(phi) + R))


def test_the_tip_margin_at_rest_is_the_pitch_one_of_the_dimensions(sim):
    sim.reset()
    robot = sim.robot()
    sim.advance(0.5)
    # Upright on level ground the least margin is about the front (or rear) wheels:
    # atan(half wheelbase / CoM height) = 37.4 deg (the sides': atan(half track / h) = 42.9).
    expected = math.degrees(math.atan2(SPEC.wheelbase / 2, com_height()))
    assert expected == pytest.approx(37.41, abs=0.01)
    # The settled chassis pitches by ~1e-7 rad: 1e-3 deg is that with a wide margin.
    assert robot.tip_margin_deg() == pytest.approx(expected, abs=1e-3)
    assert robot.min_tip_margin_deg() == pytest.approx(expected, abs=1e-3)
    summary = robot.summary()
    assert summary["tip_margin_deg"] == robot.tip_margin_deg()
    assert summary["min_tip_margin_deg"] == robot.min_tip_margin_deg()


def test_a_spin_scrubs_every_wheel_sideways_and_full_power_slips_forward(sim):
    sim.reset()
    robot = sim.robot()
    robot.set_power(-0.5, 0.5)
    sim.advance(2.0)
    angles = robot.wheel_slip_angle()
    # Spinning in place each wheel at (+-a, +-b) moves at right angles to its radius: across
    # its heading by atan(a / b) = 39.5 deg, front wheels to the left (+), rear to the right
    # (-), whichever way it turns. Drake spins about the centre within 2% (DRAKE_NOTES), so
    # 1 deg; at rest the angle is under 0.05 deg.
    expected = math.degrees(math.atan2(SPEC.wheelbase / 2, SPEC.half_track))
    for wheel, angle in angles.items():
        sign = 1.0 if wheel.startswith("front") else -1.0
        assert sign * angle == pytest.approx(expected, abs=1.0)
    # Each side's rim outruns its travel: ground speed b omega against the rim's u, with
    # omega = b u / (a^2 + b^2) (isotropic friction), a ratio of a^2 / (a^2 + b^2) = 0.40
    # on every wheel; 0.03 allows the spin's 2% and the tyres' compliance (measured 0.412).
    a, b = SPEC.wheelbase / 2, SPEC.half_track
    for ratio in robot.wheel_slip_ratio().values():
        assert ratio == pytest.approx(a**2 / (a**2 + b**2), abs=0.03)
    sim.reset()  # facing +x again, away from the box
    robot.set_power(1.0, 1.0)
    sim.advance(2.0)
    # Driving at top speed the tyres creep: the wheels turn faster than they travel, by the
    # 0.8% the effective radius and the servo's traction take (less than 2%, more than 0.2%).
    for ratio in robot.wheel_slip_ratio().values():
        assert 0.002 < ratio < 0.02
    for angle in robot.wheel_slip_angle().values():
        assert abs(angle) < 0.1  # straight: no sideways scrub (measured 0.005 deg)


@pytest.mark.parametrize("effort_limit, least_drop", [(None, 0.5), (1000.0, 5.0)])
def test_backing_into_the_giant_box_shrinks_the_tip_margin_as_the_chassis_pitches(
        effort_limit, least_drop):
    # The box is 0.59 m behind the robot's tyres: full power backwards reaches it in ~1.1 s.
    # The shipped axle effort limit (0.3 N m) only rocks the chassis at the impact (~1.3 deg
    # nose up); an unlimited motor climbs the rear wheels up the face (~13 deg nose down).
    overrides = physics_only_overrides()
    if effort_limit is not None:
        overrides.append(f"robots: {{corobot: {{contact: {{effort_limit: {effort_limit}}}}}}}")
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=overrides))
    robot = sim.robot()
    at_rest = robot.tip_margin_deg()
    robot.set_power(-1.0, -1.0)
    sim.advance(2.5)
    tilt, least = robot.max_tilt_deg(), robot.min_tip_margin_deg()
    assert robot.pose().x < -0.57  # at the box (its face at x = -0.7366, tyres 0.1524 back)
    # Rest to impact the margin falls by a clear amount (measured 0.9 and 8.6 deg) ...
    assert least < at_rest - least_drop
    # ... and by what the pitch explains: the chassis pitches without rolling, its largest
    # tilt and least margin (both of the run log's rows, every 10 ms) are the same sample,
    # and the rigid geometry (the pitch about one axle, wheels there on the ground) gives
    # the margin within 0.05 deg (the tyres' compression: ~1 mm of the 60 mm lever).
    assert least == pytest.approx(pitched_margin_deg(tilt), abs=0.05)


def test_odometry_in_the_simulation_is_calibrated_and_the_nominal_one_overcounts(sim):
    sim.reset()
    robot = sim.robot()
    odo = robot.odometry()
    assert (odo.x, odo.y, odo.yaw) == (0.0, 0.0, 0.0)  # the start pose
    drive = sim.scenario.robots["corobot"].drive
    assert drive.effective_wheel_radius < SPEC.wheel_radius  # the shipped calibration
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
    nominal = oc.dead_reckon(log, SPEC.wheel_radius, SPEC.track)[-1]
    assert 1.005 < math.hypot(nominal[0] - start.x, nominal[1] - start.y) / travelled < 1.012
    assert robot.summary()["odometry"] == {"x": odo.x, "y": odo.y, "yaw": odo.yaw}


# --- the systems alone ---------------------------------------------------------------------

def test_slip_ratio_signs_traction_plus_and_braking_minus_either_way():
    rim = [0.3, -0.3, 0.0, 0.0, 0.3, -0.3, 0.61, 1e-6, 0.3]
    ground = [0.0, 0.0, 0.3, -0.3, 0.3, -0.3, 0.6, 0.0, -0.1]
    # spinning on the spot +1 (both ways), locked -1 (both ways), rolling 0, rolling free at
    # top speed on a tyre 1/61 smaller +1/61, a creep below the floor ~0, turning against the
    # travel beyond 1.
    assert [contact.slip_ratio(r, g) for r, g in zip(rim, ground, strict=True)] == \
        pytest.approx([1, 1, -1, -1, 0, 0, 0.01 / 0.61, 1e-6 / contact.SLIP_SPEED_FLOOR, 4 / 3],
                      abs=1e-12)
    # Sideways 0.1 m/s at 0.1 m/s forwards or backwards: 45 deg to the left; at rest the
    # floor keeps a creep's angle small.
    assert [contact.slip_angle_deg(g, v) for g, v in ((0.1, 0.1), (-0.1, 0.1), (0.0, 1e-5))] \
        == pytest.approx([45.0, 45.0, math.degrees(math.atan2(1e-5, contact.SLIP_SPEED_FLOOR))],
                         abs=1e-12)


@pytest.fixture(scope="module")
def robot_plant():
    """A plant with the robot alone (default contact), the robot's model instance, chassis
    and wheels ({name: body})."""
    plant = MultibodyPlant(0.0)
    (instance,) = make_parser(plant).AddModelsFromString(corobot_sdf("corobot"), "sdf")
    plant.Finalize()
    wheels = {w: plant.GetBodyByName(f"{w}_wheel", instance) for w in SPEC.wheel_names}
    return plant, instance, plant.GetBodyByName("chassis", instance), wheels


def about_line(point, rpy) -> RigidTransform:
    """A rotation by `rpy` (deg) about the point `point` (chassis frame, m)."""
    R = RollPitchYaw(*np.radians(rpy))
    p = np.asarray(point, dtype=float)
    return RigidTransform(R, p - R.ToRotationMatrix() @ p)


def test_tip_margin_alone_follows_the_tilt_about_an_edge(robot_plant):
    plant, instance, chassis, wheels = robot_plant
    s = Stepper(TipMargin.of_robot(plant, instance, chassis, wheels), PERIOD)
    a, b, h = SPEC.wheelbase / 2, SPEC.half_track, com_height()

    def margin(X_WC):
        s.fix("chassis_pose", X_WC)
        return s.output("tip_margin")[0]

    # Its centre of mass is the plant's (all bodies, wheels included) at any chassis pose and
    # wheel angles: the wheels turn about their own centres of mass.
    X_WC = RigidTransform(RollPitchYaw(0.3, -0.2, 2.0), [3.0, -1.0, 0.5])
    moved = plant.CreateDefaultContext()
    plant.SetFreeBodyPose(moved, chassis, X_WC)
    for k, w in enumerate(SPEC.wheel_names):
        plant.GetJointByName(f"{w}_axle", instance).set_angle(moved, 0.7 * k + 0.1)
    s.fix("chassis_pose", X_WC)
    assert s.system.com(s.context) == pytest.approx(
        plant.CalcCenterOfMassPositionInWorld(moved, [instance]), abs=1e-12)
    # Upright: the pitch margin from the dimensions, wherever the robot stands and faces.
    # (Rigid geometry, no simulation: to 1e-9 deg.)
    upright = math.degrees(math.atan2(a, h))
    assert margin(RigidTransform()) == pytest.approx(upright, abs=1e-9)
    assert margin(RigidTransform(RollPitchYaw(0, 0, 2.0), [3.0, -1.0, 0.5])) == \
        pytest.approx(upright, abs=1e-9)
    # Pitched about the front axle (front wheels on the ground, nose down) or the rear (nose
    # up): the margin the test above checks in the simulation.
    for pitch in (10.0, 30.0):
        assert margin(about_line([a, 0, SPEC.wheel_radius], [0, pitch, 0])) == \
            pytest.approx(pitched_margin_deg(pitch), abs=1e-9)
        assert margin(about_line([-a, 0, SPEC.wheel_radius], [0, -pitch, 0])) == \
            pytest.approx(pitched_margin_deg(pitch), abs=1e-9)
    # Rolled about the left tyres' ground line: the tyre's mid-plane bottom stays on it, so the
    # side margin atan(b / h) = 42.9 deg falls by the roll, and goes negative past it.
    side = math.degrees(math.atan2(b, h))
    for roll in (-10.0, -50.0):  # - rolls the right side up (about +x)
        assert margin(about_line([0, b, 0], [roll, 0, 0])) == pytest.approx(side + roll,
                                                                            abs=1e-9)


def test_slip_markers_alone_colour_each_wheel_by_its_slip():
    import msgpack
    from pydrake.geometry import Meshcat

    meshcat = Meshcat()
    s = Stepper(SlipMarkers(meshcat, "/slip/r"), MARKER_PERIOD)
    X_WC = RigidTransform(RollPitchYaw(0, 0, 0.5), [1.0, 2.0, 0.0])
    s.fix("chassis_pose", X_WC)
    s.fix("wheel_slip_ratio", [0.0, 0.25, -1.0, 0.004])
    s.fix("wheel_slip_angle", [0.0, 0.0, 0.0, -40.0])
    s.tick()

    def sent(path, what):
        packed = (meshcat._GetPackedProperty(path, "color") if what == "color"
                  else meshcat._GetPackedTransform(path))
        return msgpack.unpackb(packed)

    # Gripping green, a quarter slip yellowish, locked red, a 40 deg scrub nearly red.
    colours = {w: sent(f"/slip/r/{w}", "color")["value"] for w in SPEC.wheel_names}
    assert colours == {"front_left": [0.0, 0.8, 0.0, 1.0], "front_right": [0.5, 0.8, 0.0, 1.0],
                       "rear_left": [1.0, 0.0, 0.0, 1.0],
                       "rear_right": pytest.approx([1.0, 0.8 * 2 * 5 / 45, 0.0, 1.0])}
    # Each ball beside its wheel, outside the hub: at the wheel centre, moved outward.
    matrix = sent("/slip/r/front_right", "transform")["matrix"]
    x, y, z = SPEC.wheels[SPEC.wheel_names.index("front_right")].center  # m, chassis frame
    expected = X_WC @ np.array([x, y - SPEC.wheels[0].width / 2 - 0.015, z])
    assert matrix[12:15] == pytest.approx(expected, abs=1e-12)


def test_a_simulation_with_meshcat_draws_the_slip_markers():
    from pydrake.geometry import Meshcat

    meshcat = Meshcat()
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=physics_only_overrides()),
                     meshcat)
    sim.advance(0.2)
    assert all(meshcat.HasPath(f"/slip/corobot/{w}") for w in SPEC.wheel_names)
    headless = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=physics_only_overrides()))
    with pytest.raises(RuntimeError):  # not in headless runs' diagram at all
        headless.station.diagram.GetSubsystemByName("corobot.slip_markers")


@pytest.mark.parametrize("plant_config", ["cenic", "sap"])
def test_the_run_log_holds_the_contact_telemetry_sampled_every_tenth_of_a_second(
        plant_config, monkeypatch):
    """Under CENIC a row's loads and slip are the wheel contacts' outputs at the latest 0.1 s
    sample before it, made from the plant's state sampled then when the log is read: nothing
    evaluates them while the simulation runs. SAP samples them live, every 0.1 s."""
    from corobot_drake.systems.runlog import COLUMNS, HELD_COLUMNS

    overrides = ["robots: {corobot: {commands: [!SetPower {left: 1.0, right: -0.4}]}}",
                 *physics_only_overrides()]
    if plant_config == "sap":
        overrides.append("{plant_config: {time_step: 0.01}, "
                         "simulator_config: {integration_scheme: runge_kutta3}}")
    evaluations = []
    calc = contact.WheelContacts._calc_loads
    monkeypatch.setattr(contact.WheelContacts, "_calc_loads",  # before the ports bind it
                        lambda self, c, o: (evaluations.append(c.get_time()), calc(self, c, o)))
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=overrides))
    robot = sim.robots["corobot"]
    sim.advance_to(1.0)  # a sample (10 x 0.1) and a step (100 x 0.01): the same double
    live = np.array([value for name in ("wheel_loads", "wheel_slip_ratio", "wheel_slip_angle")
                     for value in robot.signal(name).values()])
    sim.advance_to(1.05)
    # The signal's own read above, and under SAP each sample (11 of them, from t = 0).
    assert len(evaluations) == (1 if plant_config == "cenic" else 12)
    if plant_config == "sap":
        return
    rows = robot.run_log()
    held = rows[:, [COLUMNS.index(c) for c in HELD_COLUMNS]]
    times = rows[:, 0]
    after = (times > 1.0 + 1e-9) & (times < 1.05 + 1e-9)
    assert after.sum() == 5
    np.testing.assert_array_equal(held[after], np.tile(live, (5, 1)))
    assert not np.array_equal(held[np.isclose(times, 1.0)][0], live)  # the sample before
    np.testing.assert_array_equal(held[0], np.zeros(len(HELD_COLUMNS)))  # no sample before
