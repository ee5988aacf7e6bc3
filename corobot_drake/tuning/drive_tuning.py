"""Tuning the drive by simulation (`tools/tune_motor_torque_scaling.py`,
`tools/fit_drive_log.py --simulate`).

- :func:`measure_top_speed`: the robot's steady speed at full power for a MotorTorqueScaling
  (the mean forward speed over a window after the ramp, not the average including it);
- :func:`run_sweep`, :func:`scaling_for`: the same speed over a grid of scalings as a study
  (`scenarios/studies/motor_torque_scaling.yaml`), and the scaling that gives a target speed;
- :func:`simulate_log`: a run log made by the simulator at known drive parameters, for the
  least-squares fit (`sysid.fit_drive`) to find again;
- their plots.
"""

from pathlib import Path

import numpy as np

from corobot_drake.config.scenario import load_scenario
from corobot_drake.resources import DEFAULT_SCENARIO, SCENARIOS_DIR
from corobot_drake.simulation import Simulation, quiet_drake_warnings
from corobot_drake.tuning import sysid

COROBOT_TOP_SPEED = 2 * 12 * 0.0254
"""m/s: the real Corobot's top speed at full power, 2 ft/s (0.6096): what its robot file's
MotorTorqueScaling is tuned to give (`tools/tune_motor_torque_scaling.py`)."""
COROBOT_UNTUNED_SCALING = 20.0
"""The chapter's untuned MotorTorqueScaling (axle rad/s at power 1, ~1.2 m/s): where the
Corobot's tuning starts."""

SAMPLE_PERIOD = 0.02
"""s between the speed samples of `measure_top_speed`."""
EXCITATION = ((1.0, 1.0, 1.5), (0.0, 0.0, 1.0), (0.5, 0.5, 1.0), (-0.6, -0.6, 1.5),
              (0.0, 0.0, 1.0))
"""(left power, right power, seconds): straight ramps and plateaus both ways. A skid-steer turn
drags the tyres sideways and loads the motors to their effort limit (0.3 N m), and then the
wheels no longer follow the drive's command (the encoders lag or overrun it): log straight runs
for this fit, on a real robot too."""
STALL_EXCITATION = (*EXCITATION, (-1.0, -1.0, 5.0), (0.0, 0.0, 0.5))
"""`EXCITATION`, then full power backwards for 5 s: the robot backs into the giant box and
stalls against it for ~2.5 s (a log with a stall, for `sysid.robust_fit` to drop)."""


def measure_top_speed(scenario_path, robot_name, scaling: float, settle: float, measure: float):
    """(steady speed m/s, slope over the window m/s^2, times, speeds) at full power."""
    override = f"robots: {{{robot_name}: {{drive: {{motor_torque_scaling: {scaling!r}}}}}}}"
    scenario = load_scenario(scenario_path, overrides=[override])
    sim = Simulation(scenario)
    robot = sim.robot(robot_name)
    robot.set_power(1.0, 1.0)
    times, speeds = [], []
    t0 = sim.time
    steps = round((settle + measure) / SAMPLE_PERIOD)
    for _ in range(steps):
        sim.advance(SAMPLE_PERIOD)
        times.append(sim.time - t0)
        speeds.append(robot.velocity().forward)
    times, speeds = np.array(times), np.array(speeds)
    window = times > settle + 1e-9
    slope = float(np.polyfit(times[window], speeds[window], 1)[0]) if window.sum() > 2 else 0.0
    return float(np.mean(speeds[window])), slope, times, speeds


SWEEP_STUDY = SCENARIOS_DIR / "studies" / "motor_torque_scaling.yaml"
SCALING = "robots.corobot.drive.motor_torque_scaling"


def run_sweep(out: Path, workers: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The sweep study on Ray (files in `out`): (scalings, steady speeds m/s), by scaling."""
    from corobot_drake.study import engine

    rows = engine.read_rows(engine.run_study(SWEEP_STUDY, out, workers=workers))
    bad = [r["error"] for r in rows if r["status"] != "ok"]
    if bad:
        raise RuntimeError(f"{len(bad)} sweep runs failed: {bad[0]}")
    pairs = sorted((float(r[SCALING]), float(r["corobot.steady_speed"])) for r in rows)
    return np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])


def scaling_for(target: float, scalings: np.ndarray, speeds: np.ndarray) -> float:
    """The scaling whose speed is `target`, linear between the two measured scalings around it
    (the speed is nearly proportional to the scaling); ValueError outside the sweep."""
    if not speeds.min() <= target <= speeds.max():
        raise ValueError(f"target {target:g} m/s is outside the sweep's {speeds.min():.4f}-"
                         f"{speeds.max():.4f} m/s")
    return float(np.interp(target, speeds, scalings))


def plot_sweep(scalings, speeds, target: float, tuned: float, path: Path) -> None:
    """Steady speed against scaling, the target and the interpolated scaling."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.plot(scalings, speeds, "o-", label="steady speed at full power")
    ax.axhline(target, color="k", linestyle="--", linewidth=1, label=f"target {target:.4f} m/s")
    ax.axvline(tuned, color="tab:red", linewidth=1, label=f"scaling {tuned:.3f}")
    ax.set_xlabel("MotorTorqueScaling (axle rad/s at power 1)")
    ax.set_ylabel("forward speed (m/s)")
    ax.set_title("MotorTorqueScaling sweep")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_top_speed(curves, target: float, settle: float, path: Path) -> None:
    """Speed vs time at full power of each (scaling, measured, times, speeds) iteration."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for i, (scaling, measured, times, speeds) in enumerate(curves, start=1):
        ax.plot(times, speeds, label=f"iteration {i}: scaling {scaling:.3f} -> {measured:.4f} m/s")
    ax.axhline(target, color="k", linestyle="--", linewidth=1, label=f"target {target:.4f} m/s")
    ax.axvspan(settle, max(c[2][-1] for c in curves), color="0.9", label="measured window")
    ax.set_xlabel("time at full power (s)")
    ax.set_ylabel("forward speed (m/s)")
    ax.set_title("MotorTorqueScaling tuning: speed at full power")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def simulate_log(path: Path, scaling: float, slew: float, scenario=DEFAULT_SCENARIO,
                 robot: str | None = None, excitation=EXCITATION) -> None:
    """Runs `excitation` on `robot` (None: the scenario's first) in the simulator at the
    given drive parameters and writes its log."""
    quiet_drake_warnings()
    robots = load_scenario(scenario).robots
    name = robot or next(iter(robots))
    sim = Simulation(load_scenario(scenario, overrides=[
        f"robots: {{{name}: {{drive: {{motor_torque_scaling: {scaling!r}, "
        f"slew_rate: {slew!r}}}}}}}"]))
    robot = sim.robot(name)
    for left, right, seconds in excitation:
        robot.set_power(left, right)
        sim.advance(seconds)
    path.parent.mkdir(parents=True, exist_ok=True)
    robot.write_log(path)


def plot_fit(log: sysid.DriveLog, fit: sysid.DriveFit, path: Path) -> None:
    """Measured (encoder) and modelled front-wheel speeds of a fit."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path.parent.mkdir(parents=True, exist_ok=True)
    t, measured, model = sysid.fit_speeds(log, fit)
    fig, ax = plt.subplots(figsize=(9, 4.5))
    for side, name in enumerate(("left", "right")):
        ax.plot(t, measured[:, side], ".", markersize=2, alpha=0.5,
                label=f"{name} measured (encoder)")
        ax.plot(t, model[:, side], linewidth=1.5, label=f"{name} model")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("front wheel speed (rad/s)")
    ax.set_title(f"fit: scaling {fit.motor_torque_scaling:.3f}, slew {fit.slew_rate:.2f} rad/s^2,"
                 f" residual {fit.residual_rms:.3f} rad/s RMS")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
