#!/usr/bin/env python3
"""What CENIC's solver tolerances (`cenic_solver`) cost and move: iterations, the robot's pose
against Drake's own parameters', and gym steps per second (`lab/cenic_solver.py`): a markdown
table.

    python tools/cenic_solver.py [--repeats 3]
"""

import sys

try:  # without the [study] extra: one line naming it, not a traceback
    from tqdm import tqdm
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/cenic_solver.py", "study")

from corobot_drake.arguments import REPEATS, ToolParser, bounded, one_line_errors
from corobot_drake.simulation import quiet_drake_warnings
from lab import cenic_solver
from lab.bench import machine


@one_line_errors
def main(argv=None) -> int:
    parser = ToolParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=bounded(REPEATS, int), default=3,
                        help="gym runs per setting, interleaved (the median is shown)")
    args = parser.parse_args(argv)
    quiet_drake_warnings()
    settings = cenic_solver.SETTINGS
    drives = {s: cenic_solver.drive(s)
              for s in tqdm(settings, desc="drives", unit="setting", file=sys.stderr)}
    rates = {s: [] for s in settings}
    for _ in tqdm(range(args.repeats), desc="gym rounds", unit="round", file=sys.stderr):
        for s in settings:
            if "failed" not in drives[s]:
                rates[s].append(cenic_solver.gym_rate(s))
    print(f"machine: {machine()}; {cenic_solver.SECONDS:g} s of driving, "
          f"{cenic_solver.GYM_STEPS} gym steps x {args.repeats} rounds\n")
    print(cenic_solver.table(drives, rates))
    return 0


if __name__ == "__main__":
    sys.exit(main())
