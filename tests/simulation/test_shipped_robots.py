"""The shipped robots besides the Corobot, in their own scenarios: the Burger (differential
drive, caster, lidar) and the Pioneer (four-wheel skid steer, sonar ring) drive at their
robot files' top speed and spin in place at the analytic rate, and their sensors, mounted on
their own links, read their scenes' walls and pillars."""

import math

import pytest

from corobot_drake.resources import SCENARIOS_DIR
from corobot_drake.simulation import Simulation
from lab import robot_figures

SPEED_TOLERANCE = 0.012
"""The steady speed at power 1 against the robot file's top speed: measured 0.8% under on
both (0.9% on the Corobot), the compliant tyres rolling on a patch a little inside their
radius."""
SPIN_TOLERANCE = 0.025
"""The spin in place against b u / (a^2 + b^2) (2u/track for the Burger): measured 1.9%
under on the Burger (its caster's drag and its tyres' patches), 1.7% on the Pioneer."""
STEP = 0.01
"""s: the scenarios' own CENIC step (the figures at 1, 2 and 5 ms are within 0.2% of it:
docs/gallery.md)."""


@pytest.mark.parametrize("robot", ["burger", "pioneer"])
def test_top_speed_and_spin_in_place_as_analytic(robot):
    spec, u = robot_figures.spec_and_rim_speed(robot)
    speed, _ = robot_figures.steady(robot, 1.0, STEP)
    assert speed == pytest.approx(u, rel=SPEED_TOLERANCE)
    _, yaw_rate = robot_figures.steady(robot, -1.0, STEP)
    assert yaw_rate == pytest.approx(u * spec.spin_yaw_per_rim_speed, rel=SPIN_TOLERANCE)


def test_the_burgers_lidar_on_its_own_link_reads_the_arena_walls():
    """The scan plane is the lidar link's origin, 32 mm behind the base's; at the start
    (-0.4, -0.4) facing +x, the rays straight ahead and behind pass between the pillars to
    the east and west walls' inner faces (x = +-1.5)."""
    sim = Simulation.from_file(SCENARIOS_DIR / "burger.yaml")
    burger = sim.robot("burger")
    sim.advance(0.01)
    scan = burger.reading("scan")
    assert (len(scan.ranges), scan.range_min, scan.range_max) == (360, 0.12, 3.5)
    ahead = round((0.0 - scan.angle_min) / scan.angle_increment)
    lidar_x = -0.4 - 0.032
    assert scan.ranges[ahead] == pytest.approx(1.5 - lidar_x, abs=1e-3)  # the tyres' sink
    assert scan.ranges[0] == pytest.approx(lidar_x + 1.5, abs=1e-3)      # straight back
    assert burger.reading("imu") is not None


def test_the_pioneers_front_sonar_sees_the_pillar_ahead_and_the_side_ones_nothing():
    sim = Simulation.from_file(SCENARIOS_DIR / "pioneer.yaml")
    pioneer = sim.robot("pioneer")
    sim.advance(0.1)
    # The pillar's face is 1.3 m ahead, 1.085 m from the ring; the 10-degree sonars' 30-degree
    # cones reach it.
    for name in ("sonar_left_10", "sonar_right_10"):
        assert 1.0 < pioneer.ir(name).raw < 1.2
    for name in ("sonar_left_90", "sonar_right_90"):
        assert pioneer.ir(name).raw == 5.0
    assert math.isclose(pioneer.ir("sonar_left_10").raw, pioneer.ir("sonar_right_10").raw,
                        abs_tol=2e-3)  # the pillar is on the axis: both see it alike


def test_the_pioneer_backs_over_the_5_cm_kerb_and_lands_level():
    """The yard's kerb (x from -1.65 to -1.35 m, 5 cm high) is within the P3-AT's 215 mm
    tyres' reach: backing over it at power 0.6 the robot pitches (measured 11.6 deg at most)
    and comes down level beyond it, still on course."""
    sim = Simulation.from_file(SCENARIOS_DIR / "pioneer.yaml", overrides=[
        "robots: {pioneer: {pose: {translation: [-1.0, 0, 0], "
        "rotation: !Rpy {deg: [0, 0, 180]}}}}"])
    pioneer = sim.robot()
    pioneer.set_power(0.6, 0.6)
    sim.advance(3.0)
    pose = pioneer.pose()
    assert pose.x + 0.13 + 0.1075 < -1.65  # its front tyres are past the kerb's far face
    assert abs(pose.z) < 2e-3 and abs(pose.pitch) < 1e-2 and abs(pose.y) < 0.01
    assert 5.0 < pioneer.max_tilt_deg() < 20.0


def test_the_burger_pushes_against_the_arena_wall_without_climbing_it():
    """Its 1.4 N m motors are far above its tyres' traction (0.5 x 3.1 N x 0.033 m): at the
    wall they slip; the robot stays upright with its body's face at the wall's."""
    sim = Simulation.from_file(SCENARIOS_DIR / "burger.yaml", overrides=[
        "robots: {burger: {pose: {translation: [1.0, -0.4, 0]}}}"])
    burger = sim.robot()
    burger.set_power(1.0, 1.0)
    sim.advance(4.0)  # at the wall after 2.1 s, pushing for 1.9 s
    pose = burger.pose()
    assert pose.x - 0.032 + 0.069 == pytest.approx(1.5, abs=2e-3)  # the body's front face
    assert burger.max_tilt_deg() < 2.0 and abs(pose.z) < 1e-3
