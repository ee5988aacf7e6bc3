"""The motor's effort limit, chosen by the worst case (`tools/tune_tire_grip.py`).

Two studies, physics only (no camera, no IR):

- `scenarios/studies/tire_grip.yaml`: per effort limit, the robot driven into the giant box at
  half and full power, backwards and forwards, square and at 30 deg, at CENIC steps 1, 2, 5 and
  10 ms (the `box_approach` program): the largest tilt of each run. A limit's worst case is its
  largest tilt over all of them.
- `scenarios/studies/tire_grip_drive.yaml`: per effort limit, the steady speed driving straight
  and the yaw rate spinning in place at full power, on open ground.

:func:`pick`: a limit passes when its worst-case tilt stays below `FLIP_DEG`, it slows
neither the straight drive (`SPEED_SLACK`) nor the spin (`SPIN_SLACK`) against the strongest
limit measured, and it can still slip a wheel on level ground (at least `traction_limit`: the
tyre, not the motor, limits traction, as on the robot with its velocity servo). Of those, the
smallest: a wheel against the box's face climbs with at most limit / R, so the smallest limit
keeps the most margin to a flip that the sweep's steps might not show. Deterministic, as the
runs are.
"""

from __future__ import annotations

import dataclasses as dc
import math
from pathlib import Path

from corobot_drake.model.sdf import WheelContact
from corobot_drake.resources import SCENARIOS_DIR
from corobot_drake.robots import corobot
from corobot_drake.study import engine, finished

ROBOT = "corobot"
GRAVITY = 9.81
LIMIT = f"robots.{ROBOT}.contact.effort_limit"
STEP = "simulator_config.max_step_size"
NEEDS = {"box": (f"{ROBOT}.max_tilt_deg",),
         "drive": (f"{ROBOT}.steady_speed", f"{ROBOT}.steady_yaw_rate")}
"""The metric columns `limits` reads (numbers in every ok run)."""
STUDIES = {"box": "tire_grip.yaml", "drive": "tire_grip_drive.yaml"}
QUICK = {"box": "tire_grip_quick.yaml", "drive": "tire_grip_drive.yaml"}
FLIP_DEG = 20.0
"""deg: a run whose largest tilt reaches this has begun to climb the box (pushing against its
face without climbing pitches the chassis 1-2 deg; a climb that goes over ends near 110 deg)."""
SPEED_SLACK = 0.01
"""A limit may cost at most this share of the strongest limit's straight-line speed."""
SPIN_SLACK = 0.05
"""... and this share of its spin yaw rate."""


def traction_limit() -> float:
    """N m: the axle torque at which a wheel slips on level ground, mu (m g / 4) R (the robot's
    weight shared by the four wheels; the tyre's friction combined with the ground's equal one
    is the same mu); the Corobot's, from its robot file and model."""
    spec = corobot.spec()
    return WheelContact().friction * spec.mass * GRAVITY / 4 * spec.wheel_radius


def predicted_spin_rate(rim_speed: float) -> float:
    """Yaw rate (rad/s) of a skid-steer spinning in place on isotropic Coulomb friction (the
    Corobot's half wheelbase a and half track b)."""
    spec = corobot.spec()
    a, b = spec.wheelbase / 2, spec.half_track
    return b * rim_speed / (a * a + b * b)


@dc.dataclass
class Limit:
    """One effort limit's figures from both studies."""

    effort_limit: float
    worst_tilt_deg: float
    """Largest tilt over every box run."""
    worst_case: str
    """The run that tilted most (step, direction, angle, power)."""
    tilt_by_step: dict[float, float]
    """Plant step (s) -> largest tilt over that step's runs."""
    speed: float
    """m/s: steady speed driving straight at full power."""
    spin_rate: float
    """rad/s: steady yaw rate spinning in place at full power."""
    errors: int
    """Runs of either study that failed (a failed run fails the limit)."""


def study_files(quick: bool) -> dict[str, Path]:
    return {kind: SCENARIOS_DIR / "studies" / name
            for kind, name in (QUICK if quick else STUDIES).items()}


def run_studies(out: Path, quick: bool = False, workers: int | None = None) -> dict:
    """Both studies on Ray (files in `out/box`, `out/drive`); {kind: rows}."""
    return {kind: engine.read_rows(engine.run_study(path, out / kind, workers=workers))
            for kind, path in study_files(quick).items()}


def read_studies(out: Path) -> dict:
    """The rows of finished studies in `out/box`, `out/drive`, checked against the study files
    and the metrics read here (ScenarioError: one line naming the file, line and column)."""
    return finished.read_studies(out, study_files(quick=False), NEEDS)


def _case(row: dict) -> str:
    return (f"{float(row[STEP]) * 1000:g} ms, {row['box_approach.direction']}, "
            f"{float(row['box_approach.angle_deg']):g} deg, power "
            f"{float(row['box_approach.power']):g}")


def limits(rows: dict) -> list[Limit]:
    """Each effort limit's figures, in increasing limit."""
    out = []
    for value in sorted({float(r[LIMIT]) for r in rows["box"]}):
        box = [r for r in rows["box"] if float(r[LIMIT]) == value]
        drive = [r for r in rows["drive"] if float(r[LIMIT]) == value]
        ok = [r for r in box if r["status"] == "ok"]
        tilt = lambda r: float(r[f"{ROBOT}.max_tilt_deg"])  # noqa: E731
        worst = max(ok, key=tilt) if ok else None
        by_step = {}
        for r in ok:
            step = float(r[STEP])
            by_step[step] = max(by_step.get(step, 0.0), tilt(r))
        straight = [r for r in drive if float(r[f"robots.{ROBOT}.commands.0.left"]) > 0]
        spin = [r for r in drive if float(r[f"robots.{ROBOT}.commands.0.left"]) < 0]
        out.append(Limit(
            value, tilt(worst) if worst else math.nan, _case(worst) if worst else "-",
            dict(sorted(by_step.items())), _steady(straight, "steady_speed"),
            _steady(spin, "steady_yaw_rate"),
            sum(r["status"] != "ok" for r in box + drive)))
    return out


def _steady(rows: list[dict], metric: str) -> float:
    values = [float(r[f"{ROBOT}.{metric}"]) for r in rows if r["status"] == "ok"]
    return values[0] if len(values) == 1 else math.nan


def verdict(limit: Limit, strongest: Limit) -> str:
    """`ok`, or why the limit fails."""
    if limit.errors:
        return f"{limit.errors} runs failed"
    if not limit.worst_tilt_deg < FLIP_DEG:
        return f"flips ({limit.worst_tilt_deg:.0f} deg: {limit.worst_case})"
    if not limit.speed >= (1 - SPEED_SLACK) * strongest.speed:
        return f"slows the straight drive ({limit.speed:.4f} m/s)"
    if not abs(limit.spin_rate) >= (1 - SPIN_SLACK) * abs(strongest.spin_rate):
        return f"slows the spin ({abs(limit.spin_rate):.3f} rad/s)"
    if limit.effort_limit < traction_limit():
        return f"cannot slip a wheel (traction limit {traction_limit():.3f} N m)"
    return "ok"


def pick(table: list[Limit]) -> Limit | None:
    """The smallest passing limit (`verdict`)."""
    passing = [t for t in table if verdict(t, table[-1]) == "ok"]
    return min(passing, key=lambda t: t.effort_limit, default=None)


def _limit_label(value: float) -> str:
    return "unlimited (1000)" if value >= 1000 else f"{value:g}"


def markdown(table: list[Limit], picked: Limit | None) -> str:
    """A row per limit: the worst tilt per step and overall, the open-ground figures, verdict."""
    steps = sorted({s for t in table for s in t.tilt_by_step})
    prediction = predicted_spin_rate(corobot.spec().top_speed())
    head = (["effort limit (N m)"] + [f"worst tilt {s * 1000:g} ms (deg)" for s in steps]
            + ["worst tilt (deg)", "worst case", "straight speed (m/s)",
               "spin / prediction", "verdict"])
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for t in table:
        label = _limit_label(t.effort_limit)
        if t is picked:
            label = f"**{label} (picked)**"
        cells = ([label] + [f"{t.tilt_by_step.get(s, math.nan):.1f}" for s in steps]
                 + [f"{t.worst_tilt_deg:.1f}", t.worst_case, f"{t.speed:.4f}",
                    f"{abs(t.spin_rate) / prediction:.3f}", verdict(t, table[-1])])
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def plot(rows: dict, path: Path) -> None:
    """Largest tilt against the step, a panel per effort limit, a line per approach."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    box = [r for r in rows["box"] if r["status"] == "ok"]
    values = sorted({float(r[LIMIT]) for r in box})
    fig, axes = plt.subplots(1, len(values), figsize=(4 * len(values), 3.8), sharey=True,
                             squeeze=False)
    for ax, value in zip(axes[0], values, strict=True):
        cases: dict[str, list] = {}
        for r in box:
            if float(r[LIMIT]) == value:
                case = _case(r).split(", ", 1)[1]
                cases.setdefault(case, []).append(
                    (float(r[STEP]) * 1000, float(r[f"{ROBOT}.max_tilt_deg"])))
        for case, points in sorted(cases.items()):
            ax.plot(*zip(*sorted(points), strict=True), "o-", label=case, alpha=0.7)
        ax.axhline(FLIP_DEG, color="r", linestyle="--", linewidth=1)
        ax.set_yscale("log")
        ax.set_xlabel("plant time step (ms)")
        ax.set_title(f"effort limit {_limit_label(value)} N m", fontsize=10)
        ax.grid(True, alpha=0.3)
    axes[0][0].set_ylabel("largest tilt into the giant box (deg)")
    axes[0][-1].legend(fontsize=6)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
