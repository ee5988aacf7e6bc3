"""What --mcap and --record cost on a headless run (run: python tools/bench_recording.py).

Runs of the default scene (IR and camera on, driving a circle), plain and with each output
(`lab.bench_recording`), interleaved (plain, mcap, record, both; again
`--repeats` times) so a shared machine's load falls on all alike. Prints a markdown table: the
median wall time (run and file writing), its ratio to the plain run's, and the file sizes.
"""

import os
import statistics
import sys
import tempfile

try:  # without the [study] and [record] extras: one line naming it, not a traceback
    from tqdm import tqdm
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/bench_recording.py", "study", "record")

from corobot_drake.arguments import (
    BENCH_SECONDS,
    REPEATS,
    ToolParser,
    bounded,
    one_line_errors,
)
from lab.bench_recording import KINDS, recording_run


@one_line_errors
def main(argv=None) -> int:
    parser = ToolParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=bounded(BENCH_SECONDS), default=10.0,
                        help="simulated seconds per run")
    parser.add_argument("--repeats", type=bounded(REPEATS, int), default=3,
                        help="runs of each kind, the median kept")
    args = parser.parse_args(argv)
    times: dict[str, list[float]] = {k: [] for k in KINDS}
    sizes: dict[str, int] = {}
    load = [os.getloadavg()[0]]
    with tempfile.TemporaryDirectory() as out:
        for _ in tqdm(range(args.repeats), desc="rounds", unit="round"):
            for kind in KINDS:
                seconds, sizes[kind] = recording_run(kind, args.seconds, out)
                times[kind].append(seconds)
                load.append(os.getloadavg()[0])
    plain = statistics.median(times["plain"])
    print(f"load average {min(load):.1f}-{max(load):.1f}")
    print(f"| {args.seconds:g} s headless, default scene | wall s (median of {args.repeats}) "
          "| to plain | file |")
    print("|---|---|---|---|")
    for kind in KINDS:
        t = statistics.median(times[kind])
        size = f"{sizes[kind] / 1e6:.1f} MB" if sizes[kind] else "-"
        print(f"| {kind} | {t:.2f} | {t / plain:.2f}x | {size} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
