#!/usr/bin/env python3
"""The book's drive test: random legs out and back, and the drift they accumulate.

Each loop: rotate a random angle in [-45, 45] deg, drive a random 0.5-1.5 m, rotate 180 deg,
drive the same distance back, rotate 180 deg - angle (all at `--power`, default 0.2). The drift
is the distance from the start position after each loop. Same seed, same numbers
(`lab.drive_test`).

    python tools/drive_test.py --loops 3 --seed 1 [--profile seed] [--plot path.png]
    python tools/drive_test.py --loops 3 --seeds 20 --workers 2 [--profile seed]  # on Ray
    python tools/drive_test.py ... --override "{plant_config: ...}"   # another physics
"""

import sys
from pathlib import Path

import numpy as np

from corobot_drake.arguments import (
    WORKERS,
    ToolParser,
    bounded,
    one_line_errors,
    output_directory,
    output_file,
)
from corobot_drake.config import scenario as sc
from corobot_drake.limits import DRAKE_INT, DRIVE_POWER, Range
from corobot_drake.study.programs import LOOPS

try:  # without the [study] extra: one line naming it, not a traceback
    from lab import drive_test
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/drive_test.py", "study")

SEEDS = Range(1, 10_000, why="runs of the study")


def _one_seed(args) -> None:
    result = drive_test.run(args.seed, args.loops, args.profile, args.power,
                            overrides=args.override)
    for failure in result["failures"]:
        print(f"failed: {failure}")
    drift = result["drift"][-1]
    print(f"summary: profile {args.profile}, seed {args.seed}, {args.loops} loops: "
          f"drift {drift * 1000:.2f} mm ({drift * 1000 / args.loops:.2f} mm per loop), "
          f"heading error {result['heading_error'][-1]:+.3f} deg, "
          f"{len(result['failures'])} failed commands, {result['sim_time']:.1f} s simulated")
    if args.plot:
        drive_test.plot(result, args.plot)
        print(f"path plot: {args.plot}")


def _many_seeds(args) -> None:
    """The seeds as a study on Ray (`scenarios/studies/drive_test.yaml` is the same study for
    both profiles): its files in --out, then the tool's table."""
    seeds = list(range(args.seed, args.seed + args.seeds))
    out = Path(args.out or f"studies/drive_test_{args.profile}")
    table = drive_test.run_study_of_seeds(seeds, args.loops, args.profile, args.power, out,
                                          args.workers, args.override)
    for r in table:
        print(f"seed {r['seed']:3d}: drift after each loop (mm) "
              + " ".join(f"{v:7.2f}" for v in r["drift_mm"])
              + (f"  failures: {r['failures']}" if r["failures"] else ""))
    drift = np.array([r["drift_mm"] for r in table])  # seeds x loops
    per_loop = drift[:, -1] / args.loops
    print(f"summary: profile {args.profile}, seeds {seeds[0]}..{seeds[-1]}, "
          f"{args.loops} loops: mean drift after each loop (mm) "
          + " ".join(f"{v:.2f}" for v in drift.mean(axis=0))
          + f"; drift per loop {per_loop.mean():.2f} mm mean, {per_loop.max():.2f} max; "
          f"{sum(len(r['failures']) for r in table)} failed commands; study files in {out}")
    plot = args.plot or out / "drift.png"
    drive_test.plot_drift(table, args.profile, plot)
    print(f"drift plot: {plot}")


@one_line_errors
def main(argv=None) -> int:
    p = ToolParser(description=__doc__.splitlines()[0])
    p.add_argument("--loops", type=bounded(LOOPS, int), default=3, help="loops of the test")
    p.add_argument("--seed", type=bounded(DRAKE_INT, int), default=0,
                   help="the legs' seed (the first, with --seeds)")
    p.add_argument("--profile", choices=sc.PROFILES, default="closed_loop",
                   help="landing profile")
    p.add_argument("--power", type=bounded(DRIVE_POWER), default=0.2, help="power of every command")
    p.add_argument("--plot", type=output_file, default=None,
                   help="PNG: the path (one seed) or the drift per loop over seeds (None: "
                   "drive_test.png, or OUT/drift.png with --seeds)")
    p.add_argument("--seeds", type=bounded(SEEDS, int), default=1,
                   help="run seeds SEED .. SEED+N-1 as a study and report the mean drift")
    p.add_argument("--workers", "--jobs", type=bounded(WORKERS, int), default=None,
                   help="Ray workers for --seeds (None: the machine's cores)")
    p.add_argument("--out", type=output_directory, help="study output directory for --seeds "
                   "(None: studies/drive_test_<profile>)")
    p.add_argument("--override", action="append", default=[], metavar="YAML",
                   help="scenario YAML merged on the default scene (repeatable), e.g. SAP: "
                   f"\"{sc.SAP_PLANT % 0.01}\"")
    args = p.parse_args(argv)
    if args.seeds == 1:
        args.plot = args.plot or "drive_test.png"
        _one_seed(args)
    else:
        _many_seeds(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
