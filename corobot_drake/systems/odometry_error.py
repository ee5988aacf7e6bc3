"""The dead-reckoning odometry's error model: the variances /odom and /wheel_odom carry.

Three sources, each a robot's own:

- **Encoder quantization.** A count is `tick` = 2 pi R / N m of rim (R the effective wheel
  radius, N the robot file's `encoder_ticks_per_revolution`); a wheel's distance is known to
  within one count, uniformly: variance tick^2 / 12 m^2 per wheel. The mean of two wheels then
  has tick^2 / 24, their difference over the track B a heading variance tick^2 / (6 B^2) rad^2.
  It does not accumulate (the counts are absolute): the floor a reset pose starts from.
- **What the calibration leaves** (`tuning.odometry_calibration`): the drive test run with
  the calibrated radius and track ends `end_error` m from the true position and
  `heading_error` rad off the true heading after `path_length` m of driving and `turning` rad
  of turns (measured: the robot file's `odometry:`, `RobotSpec.odometry_test`). Taken as a
  random walk whose standard deviation over the test's path is its end error: a position
  variance of end_error^2 / path_length m^2 per metre rolled, a heading variance of
  heading_error^2 / turning rad^2 per radian turned.
- **A radius or track other than the calibrated ones** (the scenario's drive fields): a
  radius off by a fraction e scales every distance by 1 + e, a ratio R / B off by f every
  turn by 1 + f. Systematic, so the standard deviation grows with the travel itself: (e s)^2
  after s m, (f phi)^2 after phi rad.

So after rolling s m and turning phi rad since the last reset (`DeadReckoning`'s `travel`):
x and y each (the odom frame's axes; the error's direction turns with the path) have
tick^2 / 24 + end_error^2 / path_length s + (e s)^2 m^2, yaw tick^2 / (6 B^2) +
heading_error^2 / turning phi + (f phi)^2 rad^2. A robot without a measured drive test gets
the worst measured robot's figures (its nominal radius and track taken as far off as theirs
were). Not modelled: the lever arm of a heading error on the position beyond what the drive
test's end error holds (an uncalibrated track shows in the yaw's variance, not in x and y's),
and the travel before a saved scene was saved (its odometry restarts from the floor).

The twist comes from the encoders' speeds over one control period T (the odometry's rate): a
wheel's speed is the difference of two counts over T, variance 2 tick^2 / 12 / T^2; forward
(the mean of two wheels) tick^2 / (12 T^2) (m/s)^2, yaw rate ((right - left) / B)
tick^2 / (3 B^2 T^2) (rad/s)^2.
"""

from __future__ import annotations

import dataclasses as dc
import math


@dc.dataclass(frozen=True)
class DriveTest:
    """A drive test's dead-reckoning error (`tools/calibrate_odometry.py --simulate
    --drive-test`), with the odometry at the calibrated `radius` and `track` (m), and the
    robot's nominal figures the calibration corrected."""

    radius: float
    """m: the effective wheel radius the odometry ran with."""
    track: float
    """m: the effective track width the odometry ran with."""
    path_length: float
    """m: the distance the test drove (its legs' lengths)."""
    turning: float
    """rad: the turns the test made (their magnitudes' sum)."""
    end_error: float
    """m: the dead-reckoned position's distance from the true one at the end."""
    heading_error: float
    """rad: the dead-reckoned heading's error at the end (its magnitude)."""
    nominal_radius: float
    """m: the wheels' radius (the robot file's)."""
    nominal_track: float
    """m: the wheels' geometric track (the robot file's)."""

    def scale_error(self, radius: float) -> float:
        """`radius`' fractional error against the calibrated one."""
        return abs(radius / self.radius - 1.0)

    def turn_error(self, radius: float, track: float) -> float:
        """The fractional error of `radius` / `track` (the turn per unit of wheel difference)
        against the calibrated ratio."""
        return abs((radius / track) / (self.radius / self.track) - 1.0)


DRIVE_TEST_PATH = (7.64488, math.radians(1177.92))
"""The 3-loop drive test of seed 1 (`study.programs.DriveTest(3).commands(1)`): m driven,
rad turned."""


@dc.dataclass(frozen=True)
class OdometryErrorModel:
    """One robot's odometry error (module docstring): its variances from its travel."""

    tick: float
    """m of rim per encoder count."""
    track: float
    """m: the effective track width the odometry turns with."""
    period: float
    """s: the odometry's sampling period (the drive's control period)."""
    position_per_metre: float
    """m^2 per m rolled: the calibration's leftover random walk."""
    heading_per_radian: float
    """rad^2 per rad turned."""
    scale_error: float
    """The radius' fractional error against the calibrated one."""
    turn_error: float
    """R / B's fractional error against the calibrated one."""

    @classmethod
    def of(cls, ticks_per_revolution: int, drive, test: DriveTest | None,
           measured: tuple[DriveTest, ...] = ()) -> OdometryErrorModel:
        """A robot's: its encoders' `ticks_per_revolution`, its `config.scenario.Drive`, its
        drive test (None: unmeasured; then the worst of the `measured` robots': their random
        walks, and their nominal figures' errors as its radius' and track's)."""
        radius, track = drive.effective_wheel_radius, drive.effective_track_width
        tick = 2 * math.pi * radius / ticks_per_revolution
        if test is not None:
            return cls(tick, track, drive.control_period,
                       test.end_error ** 2 / test.path_length,
                       test.heading_error ** 2 / test.turning,
                       test.scale_error(radius), test.turn_error(radius, track))
        tests = measured
        return cls(tick, track, drive.control_period,
                   max(t.end_error ** 2 / t.path_length for t in tests),
                   max(t.heading_error ** 2 / t.turning for t in tests),
                   max(t.scale_error(t.nominal_radius) for t in tests),
                   max(t.turn_error(t.nominal_radius, t.nominal_track) for t in tests))

    def pose_variances(self, rolled: float, turned: float) -> tuple[float, float, float]:
        """(x m^2, y m^2, yaw rad^2) after rolling `rolled` m and turning `turned` rad."""
        position = (self.tick ** 2 / 24 + self.position_per_metre * rolled
                    + (self.scale_error * rolled) ** 2)
        heading = (self.tick ** 2 / (6 * self.track ** 2) + self.heading_per_radian * turned
                   + (self.turn_error * turned) ** 2)
        return position, position, heading

    def twist_variances(self) -> tuple[float, float]:
        """(forward (m/s)^2, yaw rate (rad/s)^2): the speeds' quantization."""
        speed = self.tick ** 2 / self.period ** 2
        return speed / 12, speed / (3 * self.track ** 2)


def error_model(spec, drive) -> OdometryErrorModel:
    """The error model of a robot (`RobotSpec`, its `odometry_test` from its robot file) with
    its scenario's `drive`; a robot file without one gets the worst of the shipped robots'."""
    if spec.odometry_test is not None:
        return OdometryErrorModel.of(spec.encoder_ticks_per_revolution, drive, spec.odometry_test)
    from corobot_drake.robots import ROBOTS, robot_spec

    measured = tuple(t for t in (robot_spec(name).odometry_test for name in ROBOTS)
                     if t is not None)
    return OdometryErrorModel.of(spec.encoder_ticks_per_revolution, drive, None, measured)
