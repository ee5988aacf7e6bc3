#!/usr/bin/env python3
"""Landing errors of DriveDistance and RotateDegrees, both profiles: a markdown table.

For each profile, distance {0.25, 0.5, 1, 2} m and angle {15, 45, 90, 180} deg at power
{0.2, 0.5, 1}: SetPose the robot to the origin facing +x (the giant box behind it), run the
command, let the robot come to rest (1 s), and measure from the GPS and compass:
distance error = straight-line distance from the start - target (mm), angle error = heading
change - target (deg, wrapped). Also the command's duration (s). The two profiles run in
parallel processes (`corobot_drake.analysis.landing`).

    python tools/landing_errors.py [--out docs/landing_errors.md]
"""

import argparse
import sys
from pathlib import Path

from corobot_drake.analysis import landing


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", help="also write the table to this file")
    args = p.parse_args(argv)
    text = landing.table(landing.measure_profiles())
    print(text)
    if args.out:
        Path(args.out).write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
