"""The tire-grip sweep: wheel contact parameters measured one at a time
(`tools/tune_tire_grip.py`).

For each setting (friction, hydroelastic modulus, mesh resolution, Hunt-Crossley dissipation,
motor effort limit, plant time step, contact approximation; one changed at a time from the
current defaults), headless and physics only (no camera, no IR), :func:`measure` gives:

- spin: the yaw rate spinning in place at 5 rad/s wheel speed, as a ratio of the
  isotropic-Coulomb prediction b u / (a^2 + b^2) (a half wheelbase, b half track, u rim speed);
- jitter while spinning: std of the chassis' vertical velocity and of its roll and pitch rates;
- max tilt driving at full power into the giant box forwards and backwards (a flip is > 20 deg);
- top speed at full power (the MotorTorqueScaling as shipped);
- real-time factor of all those runs: simulated s per CPU s of this process (the machine is
  shared: CPU time is steadier than wall time, which is also given).

:func:`recommend` picks: no flip and spin within 5% of the prediction, smooth (vertical
velocity std < 1 mm/s, roll and pitch rate std < 1 deg/s), then the fastest (within 15%, the
run-to-run noise here, the smoother wins).
"""

import csv
import dataclasses as dc
import math
import time
from pathlib import Path

import numpy as np

from corobot_drake.analysis.bench import physics_only_overrides
from corobot_drake.config import scenario as sc
from corobot_drake.model import dimensions as dim
from corobot_drake.simulation import Simulation

SPIN_WHEEL_SPEED = 5.0
"""rad/s: the spin test's wheel speed (the figure DRAKE_NOTES quotes)."""
FLIP_DEG = 20.0
SMOOTH_VZ = 1e-3
"""m/s: vertical-velocity std below which turning counts as smooth."""
SMOOTH_RATE_DEG = 1.0
"""deg/s: roll- and pitch-rate std below which turning counts as smooth."""


def predicted_spin_rate(rim_speed: float) -> float:
    """Yaw rate (rad/s) of a skid-steer spinning in place on isotropic Coulomb friction."""
    a, b = dim.HALF_WHEELBASE, dim.HALF_TRACK
    return b * rim_speed / (a * a + b * b)


@dc.dataclass
class Setting:
    label: str
    contact: dict = dc.field(default_factory=dict)
    """WheelContact fields changed from the defaults."""
    plant: dict = dc.field(default_factory=dict)
    """plant_config fields changed from the scenario's."""

    def overrides(self, robot: str) -> list[str]:
        out = []
        if self.contact:
            fields = ", ".join(f"{k}: {v!r}" for k, v in self.contact.items())
            out.append(f"robots: {{{robot}: {{contact: {{{fields}}}}}}}")
        if self.plant:
            fields = ", ".join(f"{k}: {v}" for k, v in self.plant.items())
            out.append(f"plant_config: {{{fields}}}")
        return out


def default_sweep(quick: bool = False) -> list[Setting]:
    """One parameter at a time around the defaults (WheelContact, scenario plant_config)."""
    sweep = [Setting("defaults")]
    if quick:
        return [*sweep, Setting("effort_limit 1000 (unlimited)", {"effort_limit": 1000.0}),
                Setting("time_step 10 ms", plant={"time_step": 0.01})]
    for field, values in (
        ("friction", (0.3, 0.8)),
        ("hydroelastic_modulus", (3e5, 3e6, 1e7)),
        ("resolution_hint", (0.008, 0.012)),
        ("hunt_crossley_dissipation", (1.0, 20.0)),
        ("effort_limit", (0.2, 0.5, 1000.0)),
    ):
        for v in values:
            label = f"{field} {v:g}" + (" (unlimited)" if v == 1000.0 else "")
            sweep.append(Setting(label, {field: v}))
    for step in (0.001, 0.002, 0.01):
        sweep.append(Setting(f"time_step {step * 1000:g} ms", plant={"time_step": step}))
    sweep.append(Setting("approximation similar",
                         plant={"discrete_contact_approximation": "similar"}))
    # Combinations toward speed: the coarser step with a coarser mesh or the other solver.
    sweep.append(Setting("time_step 10 ms + resolution_hint 0.008", {"resolution_hint": 0.008},
                         {"time_step": 0.01}))
    sweep.append(Setting("time_step 10 ms + approximation similar",
                         plant={"time_step": 0.01, "discrete_contact_approximation": "similar"}))
    return sweep


class Clock:
    """Adds up the simulated, CPU and wall seconds spent in `advance`."""

    def __init__(self):
        self.sim = self.cpu = self.wall = 0.0

    def advance(self, sim: Simulation, seconds: float) -> None:
        c, w = time.process_time(), time.perf_counter()
        sim.advance(seconds)
        self.cpu += time.process_time() - c
        self.wall += time.perf_counter() - w
        self.sim += seconds


def _make(scenario_path, robot, setting: Setting, extra=()) -> Simulation:
    overrides = [*physics_only_overrides(robot), *setting.overrides(robot), *extra]
    return Simulation(sc.load_scenario(scenario_path, overrides=overrides))


def _body_rates(sim: Simulation, robot: str):
    """(vertical velocity m/s, roll rate, pitch rate, yaw rate rad/s) of the chassis; roll and
    pitch rates about the chassis' own x and y axes."""
    plant = sim.station.plant
    chassis = sim.station.robots[robot].chassis
    context = plant.GetMyContextFromRoot(sim.context)
    V = plant.EvalBodySpatialVelocityInWorld(context, chassis)
    R = plant.EvalBodyPoseInWorld(context, chassis).rotation()
    w_B = R.inverse().multiply(V.rotational())
    return float(V.translational()[2]), float(w_B[0]), float(w_B[1]), float(V.rotational()[2])


def _spin(scenario_path, robot: str, setting: Setting, time_step: float, clock: Clock) -> dict:
    """Spin in place, wheels at +-5 rad/s: the yaw rate against the prediction, the jitter."""
    sim = _make(scenario_path, robot, setting)
    rim = SPIN_WHEEL_SPEED * dim.WHEEL_RADIUS
    sim.robot(robot).set_speed(-rim, rim)
    clock.advance(sim, 1.5)
    period = max(time_step, 0.005)
    samples = []
    for _ in range(round(1.0 / period)):
        clock.advance(sim, period)
        samples.append(_body_rates(sim, robot))
    vz, roll, pitch, yaw = np.array(samples).T
    return {
        "yaw_rate": float(np.mean(yaw)),
        "yaw_ratio": float(np.mean(yaw)) / predicted_spin_rate(rim),
        "vz_std_mm_s": float(np.std(vz)) * 1000,
        "roll_rate_std_deg_s": math.degrees(float(np.std(roll))),
        "pitch_rate_std_deg_s": math.degrees(float(np.std(pitch))),
        "spin_tilt_deg": sim.robot(robot).max_tilt_deg(),
    }


def _into_the_box(scenario_path, robot: str, setting: Setting, box_seconds: float,
                  clock: Clock) -> dict:
    """Full power into the giant box (behind the robot): forwards (turned round), backwards."""
    out = {}
    for direction, power, yaw_deg in (("forwards", 1.0, 180.0), ("backwards", -1.0, 0.0)):
        turned = f"{{rotation: !Rpy {{deg: [0, 0, {yaw_deg}]}}}}"
        sim = _make(scenario_path, robot, setting, [f"robots: {{{robot}: {{pose: {turned}}}}}"])
        sim.robot(robot).set_power(power, power)
        clock.advance(sim, box_seconds)
        out[f"tilt_{direction}_deg"] = sim.robot(robot).max_tilt_deg()
        out[f"box_x_{direction}"] = sim.robot(robot).pose().x
    return out


def _top_speed(scenario_path, robot: str, setting: Setting, clock: Clock) -> float:
    """Mean forward speed at full power after 2 s, away from the box."""
    sim = _make(scenario_path, robot, setting)
    sim.robot(robot).set_power(1.0, 1.0)
    clock.advance(sim, 2.0)
    speeds = []
    for _ in range(10):
        clock.advance(sim, 0.05)
        speeds.append(sim.robot(robot).velocity().forward)
    return float(np.mean(speeds))


def measure(scenario_path, robot: str, setting: Setting, time_step: float,
            box_seconds: float = 4.0) -> dict:
    """All the figures of one setting (see the module docstring)."""
    clock = Clock()
    out = _spin(scenario_path, robot, setting, time_step, clock)
    out.update(_into_the_box(scenario_path, robot, setting, box_seconds, clock))
    out["top_speed"] = _top_speed(scenario_path, robot, setting, clock)
    out["rtf_cpu"] = clock.sim / clock.cpu
    out["rtf_wall"] = clock.sim / clock.wall
    return out


def verdict(row: dict) -> tuple[bool, bool]:
    """(passes: no flip and spin within 5%, smooth)."""
    passes = (row["tilt_forwards_deg"] < FLIP_DEG and row["tilt_backwards_deg"] < FLIP_DEG
              and abs(row["yaw_ratio"] - 1.0) < 0.05)
    smooth = (row["vz_std_mm_s"] < SMOOTH_VZ * 1000
              and row["roll_rate_std_deg_s"] < SMOOTH_RATE_DEG
              and row["pitch_rate_std_deg_s"] < SMOOTH_RATE_DEG)
    return passes, smooth


SPEED_TIE = 0.15
"""Real-time factors within this fraction of the best count as equally fast: run to run, the
same setting's figure moves by about that much on a shared 2-core machine."""


def recommend(rows: list[dict]) -> dict | None:
    """No flip and spin within 5%; smooth; the fastest (CPU real-time factor), where settings
    within `SPEED_TIE` of the fastest tie and the least vertical jitter wins among them."""
    passing = [r for r in rows if verdict(r)[0]]
    if not passing:
        return None
    smooth = [r for r in passing if verdict(r)[1]]
    if not smooth:
        return min(passing, key=lambda r: r["roll_rate_std_deg_s"] + r["pitch_rate_std_deg_s"])
    fastest = max(r["rtf_cpu"] for r in smooth)
    tied = [r for r in smooth if r["rtf_cpu"] >= (1 - SPEED_TIE) * fastest]
    return min(tied, key=lambda r: r["vz_std_mm_s"])


COLUMNS = (
    ("setting", "setting", "{}"),
    ("yaw_ratio", "spin yaw / prediction", "{:.3f}"),
    ("vz_std_mm_s", "vz std (mm/s)", "{:.3f}"),
    ("roll_rate_std_deg_s", "roll rate std (deg/s)", "{:.3f}"),
    ("pitch_rate_std_deg_s", "pitch rate std (deg/s)", "{:.3f}"),
    ("tilt_forwards_deg", "box tilt fwd (deg)", "{:.1f}"),
    ("tilt_backwards_deg", "box tilt back (deg)", "{:.1f}"),
    ("top_speed", "top speed (m/s)", "{:.4f}"),
    ("rtf_cpu", "RTF (CPU)", "{:.2f}x"),
    ("rtf_wall", "RTF (wall)", "{:.2f}x"),
)


def markdown(rows: list[dict], recommended: dict | None) -> str:
    lines = ["| " + " | ".join(h for _, h, _ in COLUMNS) + " |",
             "|" + "---|" * len(COLUMNS)]
    for r in rows:
        cells = [fmt.format(r[key]) for key, _, fmt in COLUMNS]
        if r is recommended:
            cells[0] = f"**{cells[0]} (recommended)**"
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def plot(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = [r["setting"] for r in rows]
    y = np.arange(len(rows))
    fig, axes = plt.subplots(1, 4, figsize=(16, 0.35 * len(rows) + 2), sharey=True)
    axes[0].barh(y, [r["yaw_ratio"] for r in rows], color="tab:blue")
    axes[0].axvspan(0.95, 1.05, color="0.85")
    axes[0].set_xlabel("spin yaw rate / isotropic prediction")
    axes[0].set_xlim(0.5, 1.2)
    axes[1].barh(y - 0.2, [r["roll_rate_std_deg_s"] for r in rows], 0.4, label="roll rate")
    axes[1].barh(y + 0.2, [r["pitch_rate_std_deg_s"] for r in rows], 0.4, label="pitch rate")
    axes[1].set_xscale("log")
    axes[1].set_xlabel("std while spinning (deg/s)")
    axes[1].legend(fontsize=7)
    axes[2].barh(y - 0.2, [r["tilt_forwards_deg"] for r in rows], 0.4, label="forwards")
    axes[2].barh(y + 0.2, [r["tilt_backwards_deg"] for r in rows], 0.4, label="backwards")
    axes[2].axvline(FLIP_DEG, color="r", linestyle="--", linewidth=1)
    axes[2].set_xlabel("max tilt into the giant box (deg)")
    axes[2].legend(fontsize=7)
    axes[3].barh(y, [r["rtf_cpu"] for r in rows], color="tab:green")
    axes[3].set_xlabel("real-time factor (sim s / CPU s)")
    axes[0].set_yticks(y, labels, fontsize=8)
    axes[0].invert_yaxis()
    for ax in axes:
        ax.grid(True, axis="x", alpha=0.3)
    fig.suptitle("Tire grip sweep (one parameter changed at a time from the defaults)")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def write_outputs(rows: list[dict], recommended: dict | None, out: Path) -> str:
    """Writes OUT.csv, OUT.md and OUT.png; returns the markdown table."""
    out.parent.mkdir(parents=True, exist_ok=True)
    keys = [k for k in rows[0] if not k.startswith("_")]
    with open(out.with_suffix(".csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(rows)
    table = markdown(rows, recommended)
    out.with_suffix(".md").write_text(table)
    plot(rows, out.with_suffix(".png"))
    return table
