#!/usr/bin/env python3
"""The shipped robots' figures, each from its scenario on open ground: a Markdown table.

Top speed at power 1 against the robot file's, the spin in place against the analytic rates
at CENIC steps 1, 2, 5 and 10 ms, DriveDistance's and RotateDegrees' landing errors in both
profiles (`lab.robot_figures` says how each is measured); with `--realtime`, the physics-only
real-time factor instead (a timing).

    python tools/robot_figures.py [--robots corobot burger pioneer] [--json FILE]
    python tools/robot_figures.py --realtime [--repeats 3]
"""

import json
import statistics
import sys
from pathlib import Path

from corobot_drake.arguments import REPEATS, ToolParser, bounded, one_line_errors, output_file
from corobot_drake.simulation import quiet_drake_warnings
from lab import robot_figures


@one_line_errors
def main(argv=None) -> int:
    p = ToolParser(description=__doc__.splitlines()[0])
    p.add_argument("--robots", nargs="+", choices=sorted(robot_figures.SCENARIOS),
                   default=list(robot_figures.SCENARIOS), help="the robots to measure")
    p.add_argument("--realtime", action="store_true",
                   help="measure the physics-only real-time factor instead")
    p.add_argument("--repeats", type=bounded(REPEATS, int), default=3,
                   help="with --realtime: runs per robot, taken in turn (the median)")
    p.add_argument("--json", type=output_file, default=None, help="also write the figures here")
    args = p.parse_args(argv)
    quiet_drake_warnings()
    if args.realtime:
        runs = {name: [] for name in args.robots}
        for _ in range(args.repeats):  # interleaved: the machine's load falls on every robot
            for name in args.robots:
                runs[name].append(robot_figures.realtime_factor(name))
        results = {name: statistics.median(values) for name, values in runs.items()}
        print("| robot | physics-only real-time factor (median of "
              f"{args.repeats}, {robot_figures.RTF_SECONDS:g} s figure of eight) |")
        print("|---|---|")
        for name, rtf in results.items():
            print(f"| {name} | {rtf:.1f} |")
    else:
        results = {name: robot_figures.figures(name) for name in args.robots}
        print(robot_figures.table(results))
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
