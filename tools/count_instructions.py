#!/usr/bin/env python3
"""Instructions per simulated second of physics only, layer by layer (valgrind's callgrind).

    python tools/count_instructions.py [--seconds 1] [--override YAML ...] [--cache-sim]

The rows of `tools/bench.py --layers` (the plant alone, then the robot's systems added one
layer at a time, then the station, then the plant alone with Python updates that change
nothing), each counted over `--seconds` of the figure of eight's
first segment (`lab.instructions`): a count that is the same run after run,
where time on this shared machine is not, split into the plant's step and the rest, and of
the rest what the Simulator's handlers of the systems' events (their updates and publishes,
`instructions.EVENT_HANDLERS`) take. Each
`--override` adds a station row with that scenario override (e.g. a Drake setting to try).
`--cache-sim` adds callgrind's count of first-level instruction-cache misses (its cache model:
what code the rows keep evicting), at about twice the run time. Rows run two at a time, ~20 s
each. `--repeatability --seconds 0.02` checks the measure itself: two counts of the same run
agree within 1%.
"""

import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

try:  # without the [study] extra: one line naming it, not a traceback
    from tqdm import tqdm
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/count_instructions.py", "study")

from corobot_drake.arguments import ToolParser, bounded, one_line_errors
from corobot_drake.limits import Range
from lab import bench_layers, instructions

SECONDS = Range(0.0, instructions.LONGEST, low_open=True, unit="s")


def _counted(jobs: list, seconds: float, cache: bool) -> list[instructions.Count] | str:
    """Each job's `Count`, two rows at a time; or the one-line error of the first that failed
    (the rows still queued are dropped)."""
    with ThreadPoolExecutor(2) as pool, tqdm(total=len(jobs), unit="row") as bar:
        def counted(job):
            n = instructions.count(job[0], seconds, job[1], cache)
            bar.update()
            return n

        futures = [pool.submit(counted, job) for job in jobs]
        try:
            return [f.result() for f in futures]
        except (RuntimeError, subprocess.CalledProcessError) as e:
            pool.shutdown(cancel_futures=True)
            return str(e).splitlines()[0]


def _print_table(jobs: list, counts: list[instructions.Count], seconds: float) -> None:
    def per_second(n):
        return None if n is None else n / seconds / 1e6

    millions = [(per_second(c.instructions), per_second(c.plant_step),
                 per_second(c.event_handlers), per_second(c.i1_misses),
                 per_second(c.event_i1_misses)) for c in counts]
    cache = millions[0][3] is not None
    station = millions[instructions.rows().index(instructions.STATION)][0]
    print(f"{seconds:g} simulated s per row, from {instructions.WARM_UP:g} s of the figure "
          "of eight\n\n| layers (cumulative) | million instructions per simulated s | added | "
          "of the station's | in the plant's step | in the rest (framework and systems) | "
          "of the rest, in the systems' events |"
          + (" million first-level instruction-cache misses per simulated s | of them, in "
             "the systems' events |" if cache else "")
          + "\n|---|---|---|---|---|---|---|" + ("---|---|" if cache else ""))
    for k, ((row, override), (value, step, events, misses, event_misses)) in enumerate(
            zip(jobs, millions, strict=True)):
        name = f"the station, `{override}`" if override else (
            "the station (Simulation, physics only)" if row == instructions.STATION else row)
        added = (f"{value - millions[k - 1][0]:+.1f}" if row in bench_layers.LAYERS[1:]
                 else f"{value - millions[0][0]:+.1f} over the plant alone"
                 if row in bench_layers.FLOORS else "")
        print(f"| {name} | {value:.1f} | {added} | {value / station:.2f} | {step:.1f} | "
              f"{value - step:.1f} | {events:.1f} |"
              + (f" {misses:.2f} | {event_misses:.2f} |" if cache else ""))


REPEATABLE = 0.01
"""The most two counts of the same station run may differ, relative: they differ only by
what lands in the window besides the steps (Python's garbage collector, the toggling itself),
0.05-0.15% over 20 ms; 1% still tells a count from a time, which moves 10-30% between
identical runs on a shared machine."""


def _repeatability(seconds: float) -> int:
    """Counts the station twice: prints both counts, their relative difference and the
    plant's step's share; 1 if they differ by more than REPEATABLE."""
    jobs = [(instructions.STATION, None)] * 2
    counts = _counted(jobs, seconds, False)
    if isinstance(counts, str):
        print(f"error: {counts}", file=sys.stderr)
        return 2
    first, second = counts
    spread = abs(second.instructions - first.instructions) / first.instructions
    print(f"the station over {seconds:g} simulated s, counted twice: {first.instructions:,} "
          f"and {second.instructions:,} instructions ({spread:.3%} apart); the plant's step "
          f"{first.plant_step / first.instructions:.0%} of them")
    return 0 if spread <= REPEATABLE else 1


@one_line_errors
def main(argv=None) -> int:
    p = ToolParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=bounded(SECONDS), default=1.0,
                   help="simulated s counted per row (after a 0.05 s warm-up)")
    p.add_argument("--override", action="append", default=[],
                   help="scenario YAML: adds a station row with it (repeatable; default: none)")
    p.add_argument("--cache-sim", action="store_true",
                   help="also count first-level instruction-cache misses (~2x slower)")
    p.add_argument("--repeatability", action="store_true",
                   help="instead of the table: count the station twice and print how far "
                   "the counts differ (exit 1 beyond REPEATABLE)")
    args = p.parse_args(argv)
    try:
        instructions.require_valgrind()
    except instructions.ValgrindMissingError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    if args.repeatability:
        return _repeatability(args.seconds)
    for override in args.override:  # a bad one is its one line now, not a failed row later
        bench_layers._scenario(override)
    jobs = [(row, None) for row in instructions.rows()]
    jobs += [(instructions.STATION, override) for override in args.override]
    counts = _counted(jobs, args.seconds, args.cache_sim)
    if isinstance(counts, str):
        print(f"error: {counts}", file=sys.stderr)
        return 2
    _print_table(jobs, counts, args.seconds)
    return 0


if __name__ == "__main__":
    sys.exit(main())
