"""Odometry calibration (`tools/calibrate_odometry.py`): the effective wheel radius and track
width that make dead reckoning from the encoders match the true path.

The log is a CSV with a header line (the simulator's run log, or a real robot's logger with a
ground-truth tracker): `time` (s), `left_ticks`, `right_ticks` (front-left / front-right
encoder counts, forward rolling counts up), `x`, `y` (m, the chassis origin in the world, from
ground truth: GPS, motion capture) and `yaw` (rad, ground-truth heading); other columns may
follow. docs/tuning.md describes the columns.

The fit, by least squares over windows of the log (`WINDOW` s): in each, the wheels' mean rotation
(rad) against the true distance travelled along the heading gives the effective radius R
(distance = R x mean rotation), and their difference against the true turn gives R / B, B the
effective track width (turn = R x (right - left) / B). Windows average the encoders'
quantization; straight legs inform R, turns B. UMBmark's squares (`square_commands`, driven both
ways) excite both; any logged run that drives and turns does too.
"""

import dataclasses as dc
import math
from pathlib import Path

import numpy as np

from corobot_drake.config import scenario as sc
from corobot_drake.robots import corobot
from corobot_drake.study.programs import DriveTest
from corobot_drake.systems.dead_reckoning import advance_pose
from corobot_drake.tuning.sysid import LogError, read_columns

COLUMNS = ("time", "left_ticks", "right_ticks", "x", "y", "yaw")
WINDOW = 0.5
"""s: the fit's window (50 samples of the 100 Hz run log)."""
SQUARE_SIDE = 1.0
"""m: the side of the calibration squares."""
CALIBRATION_POWER = 0.2
"""The power of the calibration squares and of the drive test."""


@dc.dataclass
class PoseLog:
    """Encoders and ground truth: time (s), wheel rotation [n, 2] (rad, left, right, from the
    ticks), true pose [n, 3] (x m, y m, yaw rad unwrapped)."""

    time: np.ndarray
    rotation: np.ndarray
    pose: np.ndarray
    source: str = ""


TICKS = corobot.drive("encoder_ticks_per_revolution")
"""The Corobot's encoder ticks per revolution (its robot file's): a log's default."""


def read_pose_log(path, ticks_per_revolution: int = TICKS) -> PoseLog:
    """Reads a log with the `COLUMNS`; LogError naming the file and line of a problem."""
    a = read_columns(path, COLUMNS)
    return PoseLog(a[:, 0], a[:, 1:3] * (2 * math.pi / ticks_per_revolution),
                   np.column_stack([a[:, 3:5], np.unwrap(a[:, 5])]), str(path))


def pose_log_of(rows: np.ndarray,
                ticks_per_revolution: int = TICKS) -> PoseLog:
    """A PoseLog from run-log rows (`Robot.run_log()`, columns `runlog.COLUMNS`) of a robot
    whose encoders count `ticks_per_revolution` (the Corobot's 600)."""
    ticks = rows[:, 3:5] * (2 * math.pi / ticks_per_revolution)
    return PoseLog(rows[:, 0], ticks, np.column_stack([rows[:, 5:7], np.unwrap(rows[:, 7])]))


def dead_reckon(log: PoseLog, radius: float, track_width: float) -> np.ndarray:
    """The dead-reckoned path [n, 3] (x, y, yaw) from the log's first true pose, integrating
    each sample's encoder increments as `systems.dead_reckoning.DeadReckoning` does."""
    path = np.empty_like(log.pose)
    x, y, yaw = log.pose[0]
    path[0] = x, y, yaw
    rolled = np.diff(log.rotation, axis=0) * radius
    for i, (left, right) in enumerate(rolled, start=1):
        x, y, yaw = advance_pose(x, y, yaw, left, right, track_width)
        path[i] = x, y, yaw
    return path


@dc.dataclass
class OdometryFit:
    effective_wheel_radius: float
    """m."""
    effective_track_width: float
    """m."""
    windows: int
    distance_rms: float
    """m: RMS of a window's true minus modelled distance."""
    turn_rms: float
    """rad: RMS of a window's true minus modelled turn."""

    def describe(self, nominal: tuple[float, float] = (
            corobot.wheels("radius"), corobot.wheels("track"))) -> str:
        """The fit beside the robot's `nominal` (wheel radius, track) m (the Corobot's)."""
        return (f"effective_wheel_radius: {self.effective_wheel_radius:.6f} m "
                f"(nominal {nominal[0]:.6f})\n"
                f"effective_track_width: {self.effective_track_width:.5f} m "
                f"(geometric {nominal[1]:.5f})\n"
                f"residuals over {self.windows} windows of {WINDOW} s: distance "
                f"{self.distance_rms * 1000:.2f} mm RMS, turn "
                f"{math.degrees(self.turn_rms):.3f} deg RMS")


def _windows(log: PoseLog, window: float):
    """Per window: (mean wheel rotation, right - left rotation, true distance along the
    heading, true turn)."""
    edges = np.searchsorted(log.time, np.arange(log.time[0], log.time[-1], window))
    edges = np.unique(np.append(edges, len(log.time) - 1))
    x, y, yaw = log.pose.T
    mid_yaw = 0.5 * (yaw[1:] + yaw[:-1])
    step = np.diff(x) * np.cos(mid_yaw) + np.diff(y) * np.sin(mid_yaw)  # signed, along heading
    along = np.concatenate([[0.0], np.cumsum(step)])
    a, b = edges[:-1], edges[1:]
    rotation = log.rotation[b] - log.rotation[a]
    return (rotation.mean(axis=1), rotation[:, 1] - rotation[:, 0], along[b] - along[a],
            yaw[b] - yaw[a])


def fit_odometry(log: PoseLog, window: float = WINDOW) -> OdometryFit:
    """Least-squares effective wheel radius and track width (module docstring)."""
    mean, difference, distance, turn = _windows(log, window)
    if not np.any(np.abs(mean) > 1e-3) or not np.any(np.abs(difference) > 1e-3):
        raise LogError(f"{log.source or 'the log'}: it must both drive and turn to fit the "
                       "wheel radius and the track width")
    radius = float(mean @ distance / (mean @ mean))
    turn_per_difference = float(difference @ turn / (difference @ difference))  # R / B
    track = radius / turn_per_difference
    return OdometryFit(radius, track, len(mean),
                       float(np.sqrt(np.mean((distance - radius * mean) ** 2))),
                       float(np.sqrt(np.mean((turn - turn_per_difference * difference) ** 2))))


def end_error(log: PoseLog, radius: float, track_width: float) -> float:
    """m: the dead-reckoned position's distance from the true one at the log's end."""
    path = dead_reckon(log, radius, track_width)
    return float(np.hypot(*(path[-1, :2] - log.pose[-1, :2])))


def square_commands(side: float = SQUARE_SIDE, power: float = CALIBRATION_POWER) -> list:
    """UMBmark: a square counter-clockwise, then clockwise (each side driven, then a 90 deg
    turn), so the errors of the radius and the track show in both turn directions."""
    return [c for sign in (1.0, -1.0) for _ in range(4)
            for c in (sc.DriveDistance(side, power), sc.RotateDegrees(sign * 90.0, power))]


def run_script(scenario_path, robot: str, commands: list, overrides=(), progress=None):
    """Runs `commands` on `robot` (physics only: the odometry needs neither the camera nor
    the IR sensors) until they end, and 0.5 s more at rest; returns the Simulation.
    `progress(sim)` after every simulated second and at the end."""
    from corobot_drake.config.presets import physics_only_overrides
    from corobot_drake.simulation import Simulation, quiet_drake_warnings
    from corobot_drake.study.runner import commands_ended

    quiet_drake_warnings()
    scenario = sc.load_scenario(scenario_path, overrides=[*physics_only_overrides(robot),
                                                               *overrides])
    scenario.robots[robot].commands = list(commands)
    sim = Simulation(scenario)
    while not commands_ended(sim):
        sim.advance(1.0)
        if progress is not None:
            progress(sim)
    sim.advance(0.5)  # at rest
    if progress is not None:
        progress(sim)
    return sim


def drive_test_odometry_error(scenario_path, robot: str, radius: float, track_width: float,
                              seed: int = 0, loops: int = 3, progress=None) -> dict:
    """The drive test (`loops`, `seed`) with the odometry at (radius, track_width): the end
    position error of `Robot.odometry()` against the true pose, m, and the run log."""
    override = (f"robots: {{{robot}: {{drive: {{effective_wheel_radius: {radius!r}, "
                f"effective_track_width: {track_width!r}}}}}}}")
    sim = run_script(scenario_path, robot, DriveTest(loops, CALIBRATION_POWER, robot)
                     .commands(seed), [override], progress)
    r = sim.robot(robot)
    odometry, pose = r.odometry(), r.pose()
    return {"error": math.hypot(odometry.x - pose.x, odometry.y - pose.y),
            "yaw_error_deg": math.degrees(math.remainder(odometry.yaw - pose.yaw, 2 * math.pi)),
            "log": pose_log_of(r.run_log(), r.spec.encoder_ticks_per_revolution),
            "sim_time": sim.time}


def plot_paths(log: PoseLog, nominal: tuple[float, float], fitted: tuple[float, float],
               path, title: str) -> None:
    """The true path and the dead-reckoned ones before (nominal) and after calibration."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(6.5, 6.5))
    ax.plot(log.pose[:, 0], log.pose[:, 1], "k-", lw=2.0, label="true path")
    for (radius, track), name, style in ((nominal, "before (nominal)", "r--"),
                                         (fitted, "after calibration", "b-")):
        p = dead_reckon(log, radius, track)
        error = math.hypot(*(p[-1, :2] - log.pose[-1, :2]))
        ax.plot(p[:, 0], p[:, 1], style, lw=1.2,
                label=f"{name}: R {radius * 1000:.2f} mm, B {track * 1000:.1f} mm, "
                      f"end error {error * 1000:.1f} mm")
    ax.plot(*log.pose[0, :2], "g*", ms=14, label="start")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, alpha=0.3)
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
