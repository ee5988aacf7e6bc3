"""What --rosbag and --ros2 cost (run: python tools/bench_ros2.py).

Headless: runs of the default scene (IR and camera on, driving a circle), plain, writing a
rosbag2, publishing on the live node, and both (`lab.bench_ros2`),
interleaved (`--repeats` rounds) so a shared machine's load falls on all alike: the median
wall and CPU times and their ratios to the plain run's. Real time: the scene as `--ros2` runs
it, camera at 30 Hz, with a subscriber to the images and /odom, against the same without the
node: the real-time factor held and the slips over `--realtime-seconds` of wall clock.
"""

import os
import statistics
import sys
import tempfile

try:  # without the [study] extra: one line naming it, not a traceback
    from tqdm import tqdm
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/bench_ros2.py", "study")

from corobot_drake.arguments import (
    BENCH_SECONDS,
    REPEATS,
    ToolParser,
    bounded,
    one_line_errors,
)
from lab.bench_ros2 import KINDS, dds_network, headless_run, realtime_run


@one_line_errors
def main(argv=None) -> int:
    parser = ToolParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=bounded(BENCH_SECONDS), default=10.0,
                        help="simulated seconds per headless run")
    parser.add_argument("--repeats", type=bounded(REPEATS, int), default=3,
                        help="runs of each kind, the median kept")
    parser.add_argument("--realtime-seconds", type=bounded(BENCH_SECONDS), default=20.0,
                        help="wall-clock seconds of each real-time run")
    args = parser.parse_args(argv)
    times: dict[str, list[tuple[float, float]]] = {k: [] for k in KINDS}
    load = [os.getloadavg()[0]]
    with dds_network(), tempfile.TemporaryDirectory() as out:
        for _ in tqdm(range(args.repeats), desc="rounds", unit="round"):
            for kind in KINDS:
                times[kind].append(headless_run(kind, args.seconds, out))
                load.append(os.getloadavg()[0])
        live = {name: realtime_run(args.realtime_seconds, ros2=name == "--ros2")
                for name in ("plain", "--ros2")}
        load.append(os.getloadavg()[0])
    wall = {k: statistics.median(w for w, _ in v) for k, v in times.items()}
    cpu = {k: statistics.median(c for _, c in v) for k, v in times.items()}
    print(f"load average {min(load):.1f}-{max(load):.1f}")
    print(f"| {args.seconds:g} s headless, default scene, camera 30 Hz | wall s (median of "
          f"{args.repeats}) | to plain | CPU s (median) | to plain |")
    print("|---|---|---|---|---|")
    for kind in KINDS:
        print(f"| {kind} | {wall[kind]:.2f} | {wall[kind] / wall['plain']:.2f}x | "
              f"{cpu[kind]:.2f} | {cpu[kind] / cpu['plain']:.2f}x |")
    print()
    print(f"| real time, {args.realtime_seconds:g} s wall, camera 30 Hz | real-time factor | "
          "slips | messages received |")
    print("|---|---|---|---|")
    for name, stats in live.items():
        print(f"| {name} | {stats['realtime_factor']:.2f} | {stats['slips']} | "
              f"{stats['received'] if name == '--ros2' else '-'} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
