"""`python -m corobot_drake.study STUDY.yaml [--workers N] [--address ADDR] [--out DIR]
[--resume]`: run a study on Ray and write its runs, summary and plots.

Exit status: 0 when every run is ok, 1 when some runs are error rows, an output file could
not be written (a full disk: the line names the file) or Ray's local instance did not start (a
loaded machine), 2 for a bad study file
or arguments (an --address where no Ray cluster answers, an OUT/runs.csv that --resume cannot
continue), 130 when stopped with Ctrl-C (the finished rows are kept: `--resume`).
"""

import argparse
import sys
from pathlib import Path

from corobot_drake.arguments import (
    WORKERS,
    ToolParser,
    bounded,
    output_directory,
)
from corobot_drake.config.scenario import ScenarioError
from corobot_drake.extras import MissingExtraError, require


def _parser() -> argparse.ArgumentParser:
    p = ToolParser(formatter_class=argparse.HelpFormatter,  # its help states the defaults
                   prog="python -m corobot_drake.study", description=__doc__.split("\n\n")[0])
    p.add_argument("study", help="study YAML file, or a shipped study's name (tiny.yaml)")
    p.add_argument("--workers", type=bounded(WORKERS, int), default=None,
                   help="Ray workers (default: this machine's cores, or the cluster's CPUs)")
    p.add_argument("--address", help="join this Ray cluster (e.g. 10.0.0.1:6379) instead of "
                   "starting a local instance")
    p.add_argument("--out", type=output_directory,
                   help="output directory (default: studies/<study name>)")
    p.add_argument("--resume", action="store_true",
                   help="simulate only the runs not yet in OUT/runs.csv")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        require("study", "python -m corobot_drake.study")
    except MissingExtraError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    from corobot_drake.study.engine import (
        AddressError,
        RayStartError,
        ResumeError,
        read_rows,
        run_study,
    )
    from corobot_drake.study.report import OutputError

    out = args.out or Path("studies") / Path(args.study).stem
    try:
        runs_csv = run_study(args.study, out, workers=args.workers, address=args.address,
                             resume=args.resume, progress=not args.quiet)
    except ScenarioError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except AddressError as e:  # before the OSError below: no Ray cluster there is no --out's
        print(f"error: --{e}", file=sys.stderr)
        return 2
    except ResumeError as e:
        print(f"error: --resume: {e}", file=sys.stderr)
        return 2
    except RayStartError as e:  # not the study's fault: the same command may work later
        print(f"error: {e}", file=sys.stderr)
        return 1
    except OutputError as e:  # a full disk: the file named is not (wholly) written
        print(f"error: {e.filename}: cannot write ({e.strerror}); the study did not finish",
              file=sys.stderr)
        return 1
    except OSError as e:  # the output directory cannot be made or written after all
        print(f"error: --out: {e.filename or out}: cannot write ({e.strerror})", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        from corobot_drake.cli import stopped_status

        print(f"stopped: the finished runs are in {out / 'runs.csv'} (--resume runs the rest)",
              file=sys.stderr)
        return stopped_status()  # 130 for Ctrl-C, 143 for SIGTERM
    rows = read_rows(runs_csv)
    errors = [r for r in rows if r["status"] != "ok"]
    print(f"{len(rows)} runs ({len(errors)} errors): {runs_csv}, {out / 'summary.md'}")
    for row in errors[:5]:
        print(f"  run {row['run']}: {row['error']}", file=sys.stderr)
    return 1 if errors else 0


if __name__ == "__main__":
    from corobot_drake.cli import ctrl_c_stops

    ctrl_c_stops()
    sys.exit(main())
