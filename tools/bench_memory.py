"""Benchmark: the resident memory of `python -m corobot_drake --serve` over a long run.

Run: ``.venv/bin/python tools/bench_memory.py [--sim-minutes 60] [--warmup-minutes 2]``.
Serves the default scenario headless as fast as the machine goes, with one client polling the
state at 10 Hz and one driving (set_power every 0.2 s, now and then drive_distance and
set_pose, a camera frame), and samples the resident memory of the server's processes against
simulated time. Prints a table of the samples and the growth over the run, the slope over its
second half (MB per simulated hour) and the growth over one simulated hour (measured, or with
a shorter run the growth so far plus the slope for the rest of the hour). The measurement is
`lab.bench_memory`.
"""

import shlex
import sys

try:  # without the [study] extra: one line naming it, not a traceback
    from tqdm import tqdm
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/bench_memory.py", "study")

from corobot_drake.arguments import ToolParser, bounded, one_line_errors
from corobot_drake.limits import Range
from lab import bench_memory

SIM_MINUTES = Range(0.0, 10_000.0, low_open=True, unit="min")
WARMUP_MINUTES = Range(0.0, 10_000.0, unit="min", why="less than --sim-minutes")
POLL_HZ = Range(0.0, 1000.0, low_open=True, unit="Hz")
SAMPLE_EVERY = Range(0.0, 3600.0, low_open=True, unit="s")


@one_line_errors
def main(argv=None) -> int:
    p = ToolParser(description=__doc__.splitlines()[0])
    p.add_argument("--sim-minutes", type=bounded(SIM_MINUTES), default=60.0,
                   help="simulated minutes to serve")
    p.add_argument("--warmup-minutes", type=bounded(WARMUP_MINUTES), default=2.0,
                   help="simulated minutes before the growth is counted")
    p.add_argument("--poll-hz", type=bounded(POLL_HZ), default=10.0,
                   help="the poller's rate, wall clock")
    p.add_argument("--sample-every", type=bounded(SAMPLE_EVERY), default=30.0,
                   help="simulated s between memory samples")
    args = p.parse_args(argv)
    if args.warmup_minutes >= args.sim_minutes:
        p.error(f"argument --warmup-minutes: must be less than --sim-minutes "
                f"({args.sim_minutes:g}); got {args.warmup_minutes:g}")
    bar = tqdm(total=round(args.sim_minutes * 60), unit="sim s", file=sys.stderr)

    print("sim_min  rss_MB", flush=True)

    def progress(sample: bench_memory.Sample) -> None:
        bar.update(max(0, round(sample.sim_time) - bar.n))
        bar.write(f"{sample.sim_time / 60:7.1f}  {sample.rss / 1e6:6.1f}", file=sys.stdout)
        sys.stdout.flush()

    result = bench_memory.measure(args.sim_minutes, args.warmup_minutes, args.poll_hz,
                                  sample_every=args.sample_every, progress=progress)
    bar.close()
    command = "python tools/bench_memory.py" + (
        " " + shlex.join(argv if argv is not None else sys.argv[1:])
        if (argv if argv is not None else sys.argv[1:]) else "")
    print(bench_memory.summary(result, f"`{command}`"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
