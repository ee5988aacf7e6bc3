#!/usr/bin/env python3
"""Where the station's CPU time goes, against the plant alone's (Linux perf, sampled).

    python tools/profile_step.py [--seconds 20] [--repeats 5]

Runs the plant alone and the station (physics only, the figure of eight), interleaved, each in
a child process that `perf record` samples (`lab.profile_step`). It prints the CPU ms per
simulated second spent in each kind of code (the plant's physics, Drake's dependency tracking,
its systems framework, Python and its bindings, the rest), medians over the rounds, and what
the station adds to each. Needs Linux perf.
"""

import sys

try:  # without the [study] extra: one line naming it, not a traceback
    from tqdm import tqdm
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/profile_step.py", "study")

from corobot_drake.arguments import ToolParser, bounded, one_line_errors
from corobot_drake.limits import Range
from lab import profile_step

SECONDS = Range(1.0, 300.0, unit="s")
REPEATS = Range(1, 101)


def _print_table(medians: dict, seconds: float, repeats: int) -> None:
    plant, station = (medians[row] for row in profile_step.ROWS)
    added = station[profile_step.ALL] - plant[profile_step.ALL]
    print(f"{seconds:g} simulated s per run, {repeats} interleaved runs of each, medians\n\n"
          "| CPU ms per simulated s, by where the samples landed | plant alone | station | "
          "the station adds | of the station's added time |\n|---|---|---|---|---|")
    for kind in (*profile_step.KINDS, profile_step.ALL):
        more = station[kind] - plant[kind]
        share = "" if kind == profile_step.ALL else f"{more / added:.0%}"
        print(f"| {kind} | {plant[kind]:.1f} | {station[kind]:.1f} | {more:+.1f} | {share} |")
    print(f"\nThe robot's systems take {added / station[profile_step.ALL]:.0%} of the station's "
          f"CPU time ({station[profile_step.ALL] / plant[profile_step.ALL] - 1:+.0%} over the "
          "plant alone).")


@one_line_errors
def main(argv=None) -> int:
    p = ToolParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=bounded(SECONDS), default=20.0,
                   help="simulated s sampled per run")
    p.add_argument("--repeats", type=bounded(REPEATS, int), default=5,
                   help="runs of each row, interleaved; the medians")
    args = p.parse_args(argv)
    try:
        profile_step.require_perf()
        with tqdm(total=args.repeats * len(profile_step.ROWS), unit="run") as bar:
            medians = profile_step.profile(args.seconds, args.repeats, bar.update)
    except profile_step.PerfMissingError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    _print_table(medians, args.seconds, args.repeats)
    return 0


if __name__ == "__main__":
    sys.exit(main())
