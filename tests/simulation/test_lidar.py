"""The lidar-carrying Corobot (scenarios/corobot_lidar.yaml) driving in its room: each scan
read exactly against the room's walls, the crate and the pillar at the scan's own pose, the
step below its plane unseen; its summary, Meshcat drawing and seeded noise end to end."""

import copy
import math

import numpy as np
import pytest
from pydrake.geometry import Meshcat

from conftest import make_sim
from corobot_drake.config.scenario import load_scenario
from corobot_drake.resources import SCENARIOS_DIR
from corobot_drake.sensors.lidar import POSE, LaserScan
from corobot_drake.simulation import Simulation

SCENARIO = SCENARIOS_DIR / "corobot_lidar.yaml"
EXACT = 1e-9
"""m: closed-form intersections in doubles, posed by the same X_WS."""
TURN = "robots: {corobot: {commands: [!SetPower {left: 0.5, right: 0.2}]}}"
"""An arc to the right: the scans move across the room."""
NO_CAMERA = "robots: {corobot: {cameras: {front: {rgb: false}}}}"


def lidar_of(sim):
    return sim.station.robots["corobot"].sensors["lidars"]["top"].system


def walls(o, d):
    """Distance to the room's inner faces (x = +-3, y = +-2) along each ray: the nearest
    crossing ahead (the room is convex and the rays start inside it)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.stack([(3.0 - o[0]) / d[:, 0], (-3.0 - o[0]) / d[:, 0],
                      (2.0 - o[1]) / d[:, 1], (-2.0 - o[1]) / d[:, 1]])
    return np.where(t > 0, t, np.inf).min(axis=0)


def crate(o, d, X_WC, half=0.2):
    """The crate (a 0.4 m cube at X_WC): the slab test in its frame, inf for a miss."""
    R, p = X_WC.rotation().matrix(), X_WC.translation()
    oc, dc = R.T @ (o - p), d @ R
    with np.errstate(divide="ignore", invalid="ignore"):
        t1, t2 = (-half - oc) / dc, (half - oc) / dc
    near = np.minimum(t1, t2).max(axis=1)
    far = np.maximum(t1, t2).min(axis=1)
    return np.where((near <= far) & (near >= 0), near, np.inf)


def pillar(o, d, center=(1.0, -1.0), r=0.15):
    """The upright pillar: the first crossing of its circle in x-y (its height, 1 m, holds the
    scan plane), inf for a miss."""
    c = np.asarray(center) - o[:2]
    a = (d[:, :2] ** 2).sum(axis=1)
    b = d[:, :2] @ c
    disc = b * b - a * (c @ c - r * r)
    t = (b - np.sqrt(np.maximum(disc, 0.0))) / a
    return np.where((disc >= 0) & (t >= 0), t, np.inf)


def test_each_scan_reads_the_room_the_crate_and_the_pillar_exactly_while_it_drives():
    sim = make_sim(TURN, scenario=SCENARIO)
    lidar = lidar_of(sim)
    plant = sim.station.plant
    crate_body = sim.station.bodies["crate"]
    for t in (0.3, 0.6, 0.9):
        sim.advance_to(t)
        X_WC = plant.EvalBodyPoseInWorld(plant.GetMyContextFromRoot(sim.context), crate_body)
        sim.advance_to(t + 0.001)  # the scan due at t is taken leaving t, from its state
        scan = sim.robot().reading("top")
        assert isinstance(scan, LaserScan) and scan.time == pytest.approx(t, abs=1e-12)
        x = lidar.GetOutputPort("scan_state").Eval(lidar.GetMyContextFromRoot(sim.context))
        X_WS = x[POSE].reshape(3, 4)
        a = scan.bearings()
        o, d = X_WS[:, 3], np.column_stack([np.cos(a), np.sin(a), np.zeros_like(a)]) \
            @ X_WS[:, :3].T
        each = np.stack([walls(o, d), crate(o, d, X_WC), pillar(o, d)])
        expected = each.min(axis=0)
        np.testing.assert_allclose(scan.ranges, expected, rtol=0, atol=EXACT)
        assert all(np.sum(each.argmin(axis=0) == k) >= 5 for k in (1, 2))  # both are seen
        assert np.all(np.abs((o + expected[:, None] * d)[:, 2] - 0.27225) < 0.01)  # level
    assert sim.body_pose(sim.station.plant.GetBodyByName("chassis")).x > 0.1  # it drove


def test_a_still_robot_sees_the_pillar_nearest_and_the_summary_says_so():
    sim = make_sim(scenario=SCENARIO)
    sim.advance(0.25)
    scan = sim.robot().reading("top")
    ranges = np.array(scan.ranges)
    assert scan.time == pytest.approx(0.2) and len(ranges) == 360
    assert np.isfinite(ranges).all()  # the walls close every bearing within 12 m
    nearest = int(np.argmin(ranges))
    assert scan.bearings()[nearest] == pytest.approx(-math.pi / 4, abs=1e-12)
    assert ranges[nearest] == pytest.approx(math.sqrt(2) - 0.15, abs=1e-5)  # settled on tyres
    brief = sim.summary()["robots"]["corobot"]["sensors"]["lidars"]["top"]
    assert brief["rays"] == brief["in_range"] == 360 and brief["dropped"] == 0
    assert brief["nearest"] == ranges[nearest]


def test_the_seeded_noise_replays_and_a_reset_to_another_seed_is_that_seeds_run():
    """A reset to random_seed 5 reads what a simulation built with seed 5 reads (the kind
    keys the noise at each run's start: a study's runs share one diagram), and a reset back to
    0 replays the first run to the bit."""
    noisy = "robots: {corobot: {lidars: {top: {noise_std: 0.01, dropout: 0.02}}}}"

    def ranges(sim, scenario=None):
        if scenario is not None:
            sim.reset(scenario)
        sim.advance(0.25)
        return np.array(sim.robot().reading("top").ranges)

    sim = make_sim(noisy, scenario=SCENARIO)
    first = ranges(sim)
    assert 0 < np.isnan(first).sum() < 30  # 2% of 360: 7 expected
    seed_5 = copy.deepcopy(sim.scenario)
    seed_5.random_seed = 5
    other = ranges(sim, seed_5)
    assert not np.array_equal(first, other, equal_nan=True)
    assert np.array_equal(other, ranges(make_sim(noisy, "random_seed: 5", scenario=SCENARIO)),
                          equal_nan=True)
    back = copy.deepcopy(seed_5)
    back.random_seed = 0
    assert np.array_equal(first, ranges(sim, back), equal_nan=True)


def test_meshcat_draws_the_rays_and_hits_once_a_scan():
    meshcat = Meshcat()
    sim = Simulation(load_scenario(SCENARIO, overrides=[NO_CAMERA]), meshcat)
    viz = sim.station.diagram.GetSubsystemByName("corobot.lidar.top.meshcat")
    assert viz.draws == 1
    for path in ("/lidar/corobot/top/rays", "/lidar/corobot/top/hits"):
        assert meshcat.HasPath(path), path
    sim.advance(0.55)
    assert viz.draws == 6  # the scans at 0 (at initialization), 0.1, ... 0.5


def test_under_cenic_the_scans_fall_on_the_steps_and_change_nothing_of_the_motion():
    """The default scene is a continuous plant stepped by CENIC: the scans are taken on its
    steps (none splits one), so the robot drives the same with a lidar as without, to the bit,
    and each scan is at a step's time, every 0.1 s."""
    lidar = "robots: {corobot: {lidars: {top: {}}}}"
    poses = []
    for overrides in ((TURN,), (TURN, lidar)):
        sim = make_sim(*overrides)
        sim.advance(0.55)
        poses.append(sim.body_pose(sim.station.plant.GetBodyByName("chassis")))
    assert poses[0] == poses[1]
    assert sim.robot().reading("top").time == 0.5


def test_another_robot_is_seen_and_a_lidar_on_top_sees_over_it():
    """Two Corobots in the default scene, `corobot_2` 1.5 m ahead facing the same way: a lidar
    at the platform's height (0.18 m) reads corobot_2's platform, its rear face at
    1.5 - 0.10795 m, straight ahead; corobot_2's lidar on top (the default mount, above every
    part of a Corobot) reads the giant box behind both, 1.5 + 0.7366 m back, over corobot."""
    sim = make_sim("robots: {corobot: {lidars: {low: {X_PB: {translation: [0, 0, 0.18]}}}}, "
                   "corobot_2: {pose: {translation: [1.5, 0, 0]}, lidars: {top: {}}}}")
    sim.advance(0.15)
    ahead = sim.robot("corobot").reading("low").ranges[180]
    behind = sim.robot("corobot_2").reading("top").ranges[0]  # bearing -pi
    assert ahead == pytest.approx(1.5 - 0.10795, abs=1e-4)  # the robots settle ~0.5 mm
    assert behind == pytest.approx(1.5 + 0.7366, abs=1e-4)
