"""Writes the robot's SDFormat model from corobot_drake/model/dimensions.py into --out.

Usage: python tools/make_model.py [--out FILE] [--check]

    python tools/make_model.py --out models/corobot.sdf   # regenerate the shipped model
    python tools/make_model.py --check                    # is the shipped model current?
"""

import argparse
import sys
from pathlib import Path

from corobot_drake.model.sdf import corobot_sdf
from corobot_drake.resources import MODELS_DIR


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--out", type=Path, default=None,
                        help="file to write (None: ./corobot.sdf; with --check, the shipped "
                        "models/corobot.sdf)")
    parser.add_argument("--check", action="store_true", help="exit 1 if the file is stale")
    args = parser.parse_args()
    path = args.out or (MODELS_DIR / "corobot.sdf" if args.check else Path("corobot.sdf"))
    text = corobot_sdf()
    if args.check:
        stale = not path.exists() or path.read_text() != text
        print(f"{path}: {'stale' if stale else 'up to date'}")
        return 1 if stale else 0
    path.write_text(text)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
