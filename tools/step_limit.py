#!/usr/bin/env python3
"""How the robot stands on the ground at each plant step: the measurement behind the loader's
largest `plant_config.time_step` (`lab/step_limit.py`): a markdown table.

    python tools/step_limit.py [--steps 0.005 0.01 ...]
"""

import argparse
import sys

try:  # without the [study] extra: one line naming it, not a traceback
    from tqdm import tqdm
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/step_limit.py", "study")

from corobot_drake.limits import MAX_TIME_STEP
from corobot_drake.simulation import quiet_drake_warnings
from lab import step_limit

STEPS = (0.005, 0.01, 0.02, 0.025, 0.03, 0.05, 0.1, 1.0)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--steps", type=float, nargs="+", default=list(STEPS),
                   help="plant steps to try, s")
    args = p.parse_args(argv)
    quiet_drake_warnings()
    rows = [step_limit.measure(s) for s in tqdm(args.steps, unit="step", file=sys.stderr)]
    print(step_limit.table(rows, MAX_TIME_STEP))
    return 0


if __name__ == "__main__":
    sys.exit(main())
