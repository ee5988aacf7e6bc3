#!/usr/bin/env python3
"""How far a command resumed from a saved scene lands from the uninterrupted one
(`lab/resume_landing.py`).

For each landing profile, command (DriveDistance 0.3 m, RotateDegrees -60 deg) and power, runs
the command in the default scene (camera off) uninterrupted, saving the scene every `--step`
s while it runs (through the YAML a saved file holds); then runs each saved scene on to the
time the uninterrupted run ended plus `--settle` s and prints a Markdown table of the largest
distance and heading gap between the two landings (docs/commands.md).

    python tools/resume_landing.py [--step 0.02] [--settle 1.0]
"""

import sys

try:  # without the [study] extra: one line naming it, not a traceback
    from tqdm import tqdm
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/resume_landing.py", "study")

from corobot_drake.arguments import ToolParser, bounded, one_line_errors
from corobot_drake.limits import Range
from corobot_drake.simulation import quiet_drake_warnings
from lab import resume_landing as rl

STEP = Range(0.01, 10.0, unit="s", why="a multiple of the 10 ms control period")
SETTLE = Range(0.0, 100.0, unit="s")


@one_line_errors
def main(argv=None) -> int:
    p = ToolParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--step", type=bounded(STEP), default=0.02,
                   help="s between saves (a multiple of the 10 ms control period)")
    p.add_argument("--settle", type=bounded(SETTLE), default=1.0,
                   help="s after the command ends when the landings are compared")
    args = p.parse_args(argv)
    quiet_drake_warnings()
    gaps = []
    with tqdm(total=0, unit="save", file=sys.stderr) as bar:
        for profile, name, power in rl.CASES:
            end, saves, sim = rl.saved_run(profile, rl.COMMANDS[name] % power, args.step)
            bar.total += len(saves)
            gaps.append(rl.landing_gaps(end, saves, sim, args.settle, progress=bar.update))
    print(rl.table(gaps, args.step, args.settle))
    return 0


if __name__ == "__main__":
    sys.exit(main())
