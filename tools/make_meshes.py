"""Writes the Corobot's visual meshes (OBJ + MTL + PNG) into --out (default: ./meshes).

Usage: python tools/make_meshes.py [--out DIR] [--check]

    python tools/make_meshes.py --out models/meshes   # regenerate the shipped meshes
    python tools/make_meshes.py --check               # are the shipped meshes current?

Prints each mesh's triangle count and the whole robot's total against the budget. With --check
nothing is written: it exits 1 if a file in --out (default: the shipped models/meshes) differs
from what would be written (or the robot is over its triangle budget).
"""

import argparse
import sys
from pathlib import Path

from corobot_drake.model import meshes


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--out", type=Path, default=None,
                        help="output directory (None: ./meshes; with --check, the shipped "
                        "models/meshes)")
    parser.add_argument("--check", action="store_true",
                        help="write nothing; exit 1 if the files in --out are stale")
    args = parser.parse_args()

    built = meshes.build_meshes()
    counts = meshes.triangle_counts(built)
    for name, count in counts.items():
        k = meshes.ROBOT_MESH_COUNTS[name]
        note = f"  (x{k} per robot)" if k > 1 else ""
        print(f"{name + '.obj':16s} {count:6d} triangles{note}")
    total = meshes.robot_triangle_total(counts)
    over = total > meshes.TRIANGLE_BUDGET
    print(f"{'robot total':16s} {total:6d} triangles (budget {meshes.TRIANGLE_BUDGET})"
          + ("  OVER BUDGET" if over else ""))

    files = meshes.generate_files(built)
    if args.check:
        args.out = args.out or meshes.MESH_DIR
        stale = meshes.stale_files(args.out, files)
        for name in stale:
            print(f"stale: {args.out / name}")
        if not stale:
            print(f"{args.out}: up to date ({len(files)} files)")
        return 1 if stale or over else 0
    for path in meshes.write_files(args.out or Path("meshes"), files):
        print(f"wrote {path}")
    return 1 if over else 0


if __name__ == "__main__":
    sys.exit(main())
