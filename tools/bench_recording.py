"""What --mcap and --record cost on a headless run (run: python tools/bench_recording.py).

Runs of the default scene (IR and camera on, driving a circle), plain and with each output
(`corobot_drake.analysis.bench_recording`), interleaved (plain, mcap, record, both; again
`--repeats` times) so a shared machine's load falls on all alike. Prints a markdown table: the
median wall time (run and file writing), its ratio to the plain run's, and the file sizes.
"""

import argparse
import os
import statistics
import tempfile

from tqdm import tqdm

from corobot_drake.analysis.bench_recording import KINDS, recording_run


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--seconds", type=float, default=10.0,
                        help="simulated seconds per run")
    parser.add_argument("--repeats", type=int, default=3,
                        help="runs of each kind, the median kept")
    args = parser.parse_args()
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


if __name__ == "__main__":
    main()
