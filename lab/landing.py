"""Landing errors of DriveDistance and RotateDegrees, both profiles, as two studies
(`scenarios/studies/landing_drive.yaml`, `landing_rotate.yaml`; `tools/landing_errors.py`).

Each run starts the default scene (the robot at the origin facing +x, the giant box behind
it), runs the one command, lets the robot come to rest (1 s) and measures from the run log
(the `landing_error` metric): distance error = straight-line distance from the start - target
(mm), angle error = heading change - target (deg, wrapped). Also the command's duration (s).
"""

from pathlib import Path

from corobot_drake.resources import SCENARIOS_DIR
from corobot_drake.study import engine, finished

ROBOT = "corobot"
KINDS = {
    "drive": ("landing_drive.yaml", "distance", "mm", "distance (m)", "{:+.2f}"),
    "rotate": ("landing_rotate.yaml", "degrees", "deg", "angle (deg)", "{:+.3f}"),
}
"""kind -> (study file, the command's target field, error unit, table label, error format)."""
PROFILE = f"robots.{ROBOT}.motion.profile"
POWER = f"robots.{ROBOT}.commands.0.power"


def study_file(kind: str) -> Path:
    return SCENARIOS_DIR / "studies" / KINDS[kind][0]


def target_column(kind: str) -> str:
    return f"robots.{ROBOT}.commands.0.{KINDS[kind][1]}"


def run_studies(out: Path, workers: int | None = None, progress: bool = True) -> dict:
    """Both studies on Ray (files in `out/drive`, `out/rotate`); {kind: runs.csv rows}."""
    return {kind: engine.read_rows(engine.run_study(study_file(kind), out / kind,
                                                    workers=workers, progress=progress))
            for kind in KINDS}


def read_studies(out: Path) -> dict:
    """The rows of finished studies in `out/drive`, `out/rotate`, checked against the study
    files (ScenarioError: one line naming the file, line and column)."""
    return finished.read_studies(out, {kind: study_file(kind) for kind in KINDS})


def results(rows: dict) -> dict:
    """{profile: {(kind, target, power): (error, duration s, status)}} from the studies' rows."""
    out: dict = {}
    for kind, table in rows.items():
        for r in table:
            status = (r.get(f"{ROBOT}.command_status.0") or r["error"]) if r["status"] == "ok" \
                else f"error: {r['error']}"
            error = float(r.get(f"{ROBOT}.landing_error.0") or "nan")
            duration = float(r.get(f"{ROBOT}.command_duration.0") or "nan")
            key = (kind, float(r[target_column(kind)]), float(r[POWER]))
            out.setdefault(r[PROFILE], {})[key] = (error, duration, status)
    return out


def table(all_results: dict) -> str:
    """The markdown tables: per kind, a row per (target, power), a column per profile."""
    profiles = list(all_results)
    lines = []
    for kind, (_, _, unit, label, fmt) in KINDS.items():
        keys = sorted({k for p in profiles for k in all_results[p] if k[0] == kind})
        head = [label, "power"] + [f"{p} error ({unit})" for p in profiles] + [
            f"{p} time (s)" for p in profiles]
        lines.append("| " + " | ".join(head) + " |")
        lines.append("|" + "---|" * len(head))
        for key in keys:
            rows = [all_results[p][key] for p in profiles]
            cells = [f"{key[1]:g}", f"{key[2]:g}"]
            cells += [fmt.format(r[0]) + ("" if r[2] == "succeeded" else f" ({r[2]})")
                      for r in rows]
            cells += [f"{r[1]:.2f}" for r in rows]
            lines.append("| " + " | ".join(cells) + " |")
        for p in profiles:
            worst = max(abs(v[0]) for k, v in all_results[p].items() if k[0] == kind)
            lines.append(f"\nLargest |error|, {p}: {worst:.3f} {unit}.")
        lines.append("")
    return "\n".join(lines)


def plot(all_results: dict, path: Path) -> None:
    """Landing error against the target, a line per power, a column per profile; drives on top,
    turns below."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    profiles = list(all_results)
    fig, axes = plt.subplots(2, len(profiles), figsize=(5 * len(profiles), 7), squeeze=False)
    for row, (kind, (_, _, unit, label, _)) in enumerate(KINDS.items()):
        for col, profile in enumerate(profiles):
            ax = axes[row][col]
            cases = {k: v for k, v in all_results[profile].items() if k[0] == kind}
            for power in sorted({k[2] for k in cases}):
                points = sorted((k[1], v[0]) for k, v in cases.items() if k[2] == power)
                ax.plot(*zip(*points, strict=True), "o-", label=f"power {power:g}")
            ax.axhline(0.0, color="k", linewidth=0.8)
            ax.set_xlabel(label)
            ax.set_ylabel(f"landing error ({unit})")
            ax.set_title(f"{'DriveDistance' if kind == 'drive' else 'RotateDegrees'}, "
                         f"profile {profile}", fontsize=10)
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
