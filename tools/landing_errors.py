#!/usr/bin/env python3
"""Landing errors of DriveDistance and RotateDegrees, both profiles: markdown tables and a plot.

Runs `scenarios/studies/landing_drive.yaml` (distance {0.25, 0.5, 1, 2} m) and
`landing_rotate.yaml` (angle {15, 45, 90, 180} deg), each at power {0.2, 0.5, 1} in both
profiles, on the study engine (Ray); or, with `--from DIR`, reads their finished runs.csv.
Each run starts at the origin facing +x (the giant box behind), runs the command, rests 1 s
and measures from the run log: distance error = straight-line distance from the start - target
(mm), angle error = heading change - target (deg, wrapped); also the command's duration (s)
(`lab.landing`). Prints the tables; plots error against target and power.

    python tools/landing_errors.py [--workers N] [--out out/landing] [--plot out/landing.png]
    python tools/landing_errors.py --from out/landing     # the tables and plot, no simulation
"""

import sys
from pathlib import Path

from corobot_drake.arguments import (
    WORKERS,
    ToolParser,
    bounded,
    one_line_errors,
    output_directory,
    output_file,
)

try:  # without the [study] extra: one line naming it, not a traceback
    from lab import landing
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/landing_errors.py", "study")


@one_line_errors
def main(argv=None) -> int:
    p = ToolParser(description=__doc__.splitlines()[0])
    p.add_argument("--workers", type=bounded(WORKERS, int), default=None,
                   help="Ray workers (None: the machine's cores)")
    p.add_argument("--out", type=output_directory, default=Path("out/landing"),
                   help="the studies' output directory (OUT/drive, OUT/rotate)")
    p.add_argument("--from", dest="source", type=Path, default=None,
                   help="read finished studies from this directory instead of simulating")
    p.add_argument("--plot", type=output_file, default=Path("out/landing.png"),
                   help="PNG of the landing errors against target and power")
    p.add_argument("--table", type=output_file, default=None,
                   help="also write the tables to this file")
    args = p.parse_args(argv)
    if args.source:
        rows = landing.read_studies(args.source)
    else:
        rows = landing.run_studies(args.out, args.workers)
    results = landing.results(rows)
    text = landing.table(results)
    print(text)
    landing.plot(results, args.plot)
    print(f"plot: {args.plot}", file=sys.stderr)
    if args.table:
        args.table.write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
