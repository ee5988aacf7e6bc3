"""Refreshes the measured figures in README.md and docs/*.md (run: python tools/refresh_docs.py).

Every measured figure in the documentation sits in a generated block,

    <!-- BEGIN generated: NAME (COMMAND) -->
    ...
    <!-- END generated: NAME -->

and COMMAND is what produces it: a tool of tools/ (or examples/, or a test run with -s), or
`python tools/refresh_docs.py --measure NAME` for a few simple measurements this tool makes
itself through the Python API. This tool runs each block's command(s), renders the output as
Markdown and replaces the block's content (and writes the pictures the commands write).
Text outside the markers is never touched. The blocks, their commands and renderers live in
lab/refresh/ (lab/docs_blocks.py reads the markers).

    python tools/refresh_docs.py                 # every block: deterministic ones first,
                                                 # pictures, timings last (--list: each cost)
    python tools/refresh_docs.py --only NAME ...  # some blocks (a NAME may be a pattern:
                                                 # --only 'gallery-*')
    python tools/refresh_docs.py --list          # the blocks, their commands and costs
    python tools/refresh_docs.py --check         # the cheap deterministic blocks: exit 1 on drift
    python tools/refresh_docs.py --date-from-git --only NAME  # date an undated block, no run

Simulation results are deterministic (same numbers on every run), so `--check` can hold them to
the text; timings (real-time factors, per-frame and per-scan costs) are not: their blocks note
the machine's load average while they were measured, and only a refresh rewrites them. Every
block says the day it was made: a timing in its "Measured" line, any other block in a last line
"Produced DAY by COMMAND" that `--check` leaves out of its comparison. `--date-from-git` dates an
undated block without running its command: the day of the last commit that changed its lines
(or its picture), which its date line says.
"""

import argparse
import fnmatch
import json
import sys

from lab.refresh.measures import MEASUREMENTS
from lab.refresh.rewrite import check_markers, list_blocks, refresh, stamp_from_git
from lab.refresh.runner import DETERMINISTIC
from lab.refresh.specs import blocks


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--only", nargs="+", metavar="NAME",
                   help="these blocks only, by name or shell pattern (None: all)")
    p.add_argument("--list", action="store_true", help="list the blocks, their commands, costs")
    p.add_argument("--check", action="store_true",
                   help="re-render deterministic blocks (without --only: the cheap ones) and "
                        "exit 1 if any differs from the file; writes nothing")
    p.add_argument("--date-from-git", action="store_true",
                   help="date the undated blocks (of --only) by git's last change to their "
                        "lines, without running their commands")
    p.add_argument("--measure", choices=sorted(MEASUREMENTS),
                   help="make one of this tool's own measurements and print it (JSON; None: "
                   "refresh instead)")
    args = p.parse_args(argv)
    if args.measure:
        print(json.dumps(MEASUREMENTS[args.measure](), indent=1))
        return 0
    specs = blocks()
    problems = check_markers(specs)
    for problem in problems:
        print(f"error: {problem}", file=sys.stderr)
    if problems:
        return 2
    if args.only:
        unknown = {p for p in args.only if not any(fnmatch.fnmatchcase(s.name, p) for s in specs)}
        if unknown:
            print(f"error: no block {', '.join(sorted(unknown))} (see --list)", file=sys.stderr)
            return 2
        specs = [s for s in specs if any(fnmatch.fnmatchcase(s.name, p) for p in args.only)]
    if args.list:
        list_blocks(specs)
        return 0
    if args.date_from_git:
        return stamp_from_git(specs)
    if args.check:
        chosen = [s for s in specs if s.kind == DETERMINISTIC and (args.only or s.cheap)]
        skipped = [s.name for s in specs if s not in chosen]
        if args.only and skipped:
            print(f"note: not checked (their figures vary run to run): {', '.join(skipped)}",
                  file=sys.stderr)
        return refresh(chosen, check=True)
    return refresh(specs, check=False)


if __name__ == "__main__":
    sys.exit(main())
