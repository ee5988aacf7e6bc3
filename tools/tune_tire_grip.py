#!/usr/bin/env python3
"""Picks the motor's effort limit by the worst case of the box flip.

Runs `scenarios/studies/tire_grip.yaml` (per effort limit: into the giant box at half and full
power, backwards and forwards, square and at 30 deg, CENIC steps 1-10 ms) and
`tire_grip_drive.yaml` (straight speed and spin rate at full power) on the study engine, or
reads them with `--from DIR`; prints a table per limit and the pick: no flip in the worst case
(largest tilt below 20 deg), not slower on open ground, then the most margin
(`corobot_drake.tuning.tire_grip`). Exit status 1 when no limit passes.

    python tools/tune_tire_grip.py [--quick] [--workers N] [--out out/tire_grip]
"""

import sys
import time
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
    from corobot_drake.tuning import tire_grip
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/tune_tire_grip.py", "study")


@one_line_errors
def main(argv=None) -> int:
    p = ToolParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true",
                   help="tire_grip_quick.yaml: the unlimited motor's flip case at 5 and 10 ms, "
                   "two limits (a smoke run, ~1 minute)")
    p.add_argument("--workers", type=bounded(WORKERS, int), default=None,
                   help="Ray workers (None: the machine's cores)")
    p.add_argument("--out", type=output_directory, default=Path("out/tire_grip"),
                   help="the studies' output directory (OUT/box, OUT/drive)")
    p.add_argument("--from", dest="source", type=Path, default=None,
                   help="read finished studies from this directory instead of simulating")
    p.add_argument("--plot", type=output_file, default=Path("out/tire_grip.png"),
                   help="PNG of the largest tilt against the step, per limit")
    args = p.parse_args(argv)
    start = time.perf_counter()
    if args.source:
        rows = tire_grip.read_studies(args.source)
    else:
        rows = tire_grip.run_studies(args.out, args.quick, args.workers)
    took = time.perf_counter() - start
    table = tire_grip.limits(rows)
    picked = tire_grip.pick(table)
    runs = sum(len(r) for r in rows.values())
    how = f"read from {args.source}" if args.source else f"simulated in {took:.0f} s"
    print(f"tire grip: {runs} runs {how}; flip threshold {tire_grip.FLIP_DEG:g} deg\n")
    print(tire_grip.markdown(table, picked))
    tire_grip.plot(rows, args.plot)
    print(f"plot: {args.plot}")
    if picked is None:
        print("picked: none (every limit flips, fails or slows the robot)")
        return 1
    print(f"picked: effort_limit {picked.effort_limit:g} N m (worst-case tilt "
          f"{picked.worst_tilt_deg:.1f} deg: {picked.worst_case})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
