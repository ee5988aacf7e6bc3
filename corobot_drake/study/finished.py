"""The rows of finished studies, read back and checked (a tool's `--from DIR`).

`read_studies(out, {kind: study file})` reads `out/<kind>/runs.csv` of each study and checks
it is that study's table before a tool computes from it: the file is a readable regular file
of UTF-8 CSV, its header has the study's columns (`run`, `seed`, its grid and random
parameters, `status`, `error`, and the metric columns the tool `needs`), and every row has
as many fields as the header and numbers where the study put numbers. Anything else is one
ScenarioError line naming the file, the line and the column:

    out/landing/drive/runs.csv:1: columns: lacks robots.corobot.commands.0.distance, ...:
    not the runs of landing_drive.yaml (python -m corobot_drake.study ... --out ...)
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

from corobot_drake.config.scenario import ScenarioError, read_text
from corobot_drake.study.spec import Choice, Study, load_study

MAX_RUNS_BYTES = 256 << 20
"""The largest runs.csv read (256 MiB: `spec.MAX_RUNS` rows of 2.5 kB); larger is refused unread."""
STATUSES = ("ok", "error")


def read_studies(out: Path, studies: dict[str, Path], needs: dict[str, tuple] | None = None
                 ) -> dict[str, list[dict]]:
    """{kind: rows} of `out/<kind>/runs.csv`, each checked against its study file
    (`studies[kind]`) and the metric columns `needs[kind]` (numbers in every ok row)."""
    out = Path(out)
    if not out.is_dir():
        raise ScenarioError(str(out), "", f"{'not' if out.exists() else 'no such'} "
                            "directory; --from reads a directory of "
                            f"finished studies ({', '.join(f'{k}/runs.csv' for k in studies)})")
    return {kind: read_runs(out / kind / "runs.csv", Path(study),
                            tuple((needs or {}).get(kind, ())))
            for kind, study in studies.items()}


def _rerun(path: Path, study_file: Path) -> str:
    return f"python -m corobot_drake.study {study_file} --out {path.parent}"


def read_runs(path: Path, study_file: Path, needs: tuple[str, ...] = ()) -> list[dict]:
    """The rows of one study's runs.csv (see the module docstring); ScenarioError else."""
    source = str(path)
    if not path.exists():
        raise ScenarioError(source, "", "no such file: run the study first ("
                            + _rerun(path, study_file) + ")")
    text = read_text(path, kind="runs.csv is a study's CSV table", max_bytes=MAX_RUNS_BYTES)
    study = load_study(study_file)
    reader = csv.reader(io.StringIO(text, newline=""))
    try:
        header = next(reader, None)
        if not header:
            raise ScenarioError(source, "", "empty: no header and no runs ("
                                + _rerun(path, study_file) + ")", 1)
        numeric = _numeric_columns(study, needs)
        missing = [c for c in ("run", "seed", *study.grid, *study.random, "status", "error",
                               *needs) if c not in header]
        if missing:
            raise ScenarioError(source, "columns", f"lacks {', '.join(missing)}: not the runs "
                                f"of {study_file.name} ({_rerun(path, study_file)})", 1)
        rows = [_row(source, reader.line_num, header, fields, numeric, needs)
                for fields in reader if fields]
    except csv.Error as e:
        raise ScenarioError(source, "", f"not a CSV table ({e})", reader.line_num) from None
    if not rows:
        raise ScenarioError(source, "", f"no runs, only the header ({_rerun(path, study_file)})",
                            1)
    return rows


def _numeric_columns(study: Study, needs: tuple[str, ...]) -> set[str]:
    """The columns whose values the study makes numbers."""
    columns = {"run", "seed", *needs}
    for key, values in study.grid.items():
        if all(isinstance(v, int | float) and not isinstance(v, bool) for v in values):
            columns.add(key)
    columns.update(k for k, dist in study.random.items() if not isinstance(dist, Choice))
    return columns


def _row(source: str, line: int, header: list[str], fields: list[str], numeric: set[str],
         needs: tuple[str, ...]) -> dict:
    if len(fields) != len(header):
        raise ScenarioError(source, "", f"{len(fields)} fields; the header has {len(header)}",
                            line)
    row = dict(zip(header, fields, strict=True))
    if row["status"] not in STATUSES:
        raise ScenarioError(source, "status", f"{row['status']!r} is not one of "
                            f"{', '.join(STATUSES)}", line)
    for column in numeric:
        if column in needs and row["status"] != "ok":
            continue  # an error row has no metrics
        try:
            float(row[column])
        except ValueError:
            raise ScenarioError(source, column, f"{row[column]!r} is not a number",
                                line) from None
    return row
