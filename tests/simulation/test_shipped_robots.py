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
