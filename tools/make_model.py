"""Writes the Corobot's SDFormat model from its CAD (corobot_drake/model/dimensions.py) into
--out, and with --robot-file brings the robot file's CAD figures in step.

Usage: python tools/make_model.py [--out FILE] [--robot-file FILE] [--check]

    python tools/make_model.py --out models/corobot.sdf   # regenerate the shipped model
    python tools/make_model.py --robot-file models/corobot/robot.yaml   # and its robot file
    python tools/make_model.py --check                    # are the shipped files current?
"""

import argparse
import sys
from pathlib import Path

from corobot_drake.model.robot_file import robot_file_text
from corobot_drake.model.sdf import corobot_sdf
from corobot_drake.resources import MODELS_DIR
from corobot_drake.robots.corobot import FILE as ROBOT_FILE


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--out", type=Path, default=None,
                        help="file to write (None: ./corobot.sdf; with --check, the shipped "
                        "models/corobot.sdf)")
    parser.add_argument("--robot-file", type=Path, default=None,
                        help="robot file whose wheels' and sensor mounts' figures to write "
                        "from the CAD (with --check: default the shipped one)")
    parser.add_argument("--check", action="store_true", help="exit 1 if a file is stale")
    args = parser.parse_args()
    path = args.out or (MODELS_DIR / "corobot.sdf" if args.check else Path("corobot.sdf"))
    files = [(path, corobot_sdf())]
    robot_file = args.robot_file or (ROBOT_FILE if args.check else None)
    if robot_file is not None:
        files.append((robot_file, robot_file_text(robot_file)))
    stale = False
    for target, text in files:
        if args.check:
            current = target.exists() and target.read_text() == text
            stale = stale or not current
            print(f"{target}: {'up to date' if current else 'stale'}")
        else:
            target.write_text(text)
            print(f"wrote {target}")
    return 1 if stale else 0


if __name__ == "__main__":
    sys.exit(main())
