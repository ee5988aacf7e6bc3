"""A study's report from its rows: `summary.md` (per grid point: mean, sd, min and max of each
numeric metric) and plots (each metric against each grid parameter; histograms over seeds)."""

from __future__ import annotations

import contextlib
import math
import re
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from corobot_drake.study.runner import TIMING_COLUMNS
from corobot_drake.study.spec import DIGEST_COLUMN, Study

NOT_METRICS = {"run", "seed", "status", "error", DIGEST_COLUMN, *TIMING_COLUMNS}


class OutputError(OSError):
    """One of a study's output files could not be written (a full disk, a quota); its
    `filename` is that file."""


@contextlib.contextmanager
def writing(path: Path, partial: Path | None = None) -> Iterator[None]:
    """Turns an OSError while `path` is written into an OutputError naming `path`, and
    removes `partial` (the half-written file `path` was to be made from) when there is one."""
    try:
        yield
    except OSError as e:
        if partial is not None:
            with contextlib.suppress(OSError):
                partial.unlink()
        raise OutputError(e.errno, e.strerror or str(e), str(path)) from e


def _number(text: str) -> float | None:
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


def metric_columns(rows: list[dict], study: Study) -> list[str]:
    """Metric columns holding numbers (command statuses are text: counted, not averaged)."""
    params = {*study.grid, *study.random}
    names = [k for k in (rows[0] if rows else {}) if k not in NOT_METRICS and k not in params]
    return [k for k in names if any(_number(r[k]) is not None for r in rows)]


def grid_points(rows: list[dict], study: Study) -> dict[tuple, list[dict]]:
    points: dict[tuple, list[dict]] = {}
    for row in rows:
        points.setdefault(tuple(row[k] for k in study.grid), []).append(row)
    return points


def _stats(values: list[float]) -> str:
    v = np.asarray([x for x in values if x is not None and math.isfinite(x)])
    if v.size == 0:
        return "| - | - | - | - |"
    sd = float(v.std(ddof=1)) if v.size > 1 else 0.0
    return f"| {v.mean():.6g} | {sd:.3g} | {v.min():.6g} | {v.max():.6g} |"


def summary_markdown(rows: list[dict], study: Study) -> str:
    ok = [r for r in rows if r["status"] == "ok"]
    lines = [f"# Study summary\n\n{len(rows)} runs, {len(rows) - len(ok)} errors.\n"]
    metrics = metric_columns(ok, study)
    for key, point_rows in grid_points(ok, study).items():
        title = ", ".join(f"{k} = {v}" for k, v in zip(study.grid, key, strict=True))
        lines += [f"## {title or 'all runs'} ({len(point_rows)} runs)\n",
                  "| metric | mean | sd | min | max |", "|---|---|---|---|---|"]
        lines += [f"| {m} " + _stats([_number(r[m]) for r in point_rows]) for m in metrics]
        lines.append("")
    errors = [r for r in rows if r["status"] != "ok"]
    if errors:
        lines += ["## Errors\n", "| run | seed | error |", "|---|---|---|"]
        lines += [f"| {r['run']} | {r['seed']} | {r['error']} |" for r in errors]
    return "\n".join(lines) + "\n"


def _file_name(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text)


def _label(name: str, unit: str) -> str:
    return f"{name} ({unit})" if unit else name


def plot(out: Path, rows: list[dict], study: Study, name: str = "",
         units: dict[str, str] | None = None, user: dict | None = None) -> list[Path]:
    """One PNG per metric: against each grid parameter (points, mean line), or a histogram
    over seeds when the study has no grid; titled with the study's `name` and the metric,
    each axis with its unit (the metric's from the registry or the user metric `user[name]`,
    a parameter's from `units`: `resolve.parameter_units`)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from corobot_drake.study.metrics import unit_of

    ok = [r for r in rows if r["status"] == "ok"]
    written = []
    for metric in metric_columns(ok, study):
        params = list(study.grid) or [None]
        fig, axes = plt.subplots(1, len(params), figsize=(4.5 * len(params), 3.6),
                                 squeeze=False)
        y_label = _label(metric, unit_of(metric, study.metrics, user))
        for ax, param in zip(axes[0], params, strict=True):
            x_label = None if param is None else _label(param.split(".")[-1],
                                                        (units or {}).get(param, ""))
            _draw(ax, ok, metric, param, x_label, y_label)
        runs = f"{len(ok)} run{'s' if len(ok) != 1 else ''}"
        fig.suptitle(f"{name}: {metric} ({runs})" if name else f"{metric} ({runs})")
        fig.tight_layout()
        path = out / "plots" / f"{_file_name(metric)}.png"
        try:
            with writing(path):
                path.parent.mkdir(exist_ok=True)
                fig.savefig(path, dpi=90)
        finally:
            plt.close(fig)
        written.append(path)
    return written


def _draw(ax, rows: list[dict], metric: str, param: str | None, x_label: str | None,
          y_label: str) -> None:
    ys = [_number(r[metric]) for r in rows]
    if param is None:
        ax.hist([y for y in ys if y is not None and math.isfinite(y)], bins="auto")
        ax.set_xlabel(y_label)
        ax.set_ylabel("runs")
        return
    labels = sorted({r[param] for r in rows}, key=lambda v: (_number(v) is None, _number(v)
                                                              or 0.0, v))
    position = {v: i for i, v in enumerate(labels)}
    numeric = all(_number(v) is not None for v in labels)
    xs = [(_number(r[param]) if numeric else position[r[param]]) for r in rows]
    ax.plot(xs, ys, "o", alpha=0.5)
    means = [np.nanmean([y for r, y in zip(rows, ys, strict=True) if r[param] == v
                         and y is not None]) for v in labels]
    ax.plot([_number(v) if numeric else position[v] for v in labels], means, "-", color="k")
    if not numeric:
        ax.set_xticks(range(len(labels)), labels)
    ax.set_xlabel(x_label)
    ax.set_ylabel(y_label)


def write(out: Path, study: Study, rows: list[dict], name: str = "",
          units: dict[str, str] | None = None, user: dict | None = None) -> None:
    """summary.md and the plots (`plot`'s `name`, `units` and `user`)."""
    with writing(out / "summary.md"):
        (out / "summary.md").write_text(summary_markdown(rows, study))
    plot(out, rows, study, name, units, user)
