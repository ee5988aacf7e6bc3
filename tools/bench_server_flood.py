"""Benchmark: a server's real-time factor under a flood (run: python tools/bench_server_flood.py).

The default scenario served headless in real time, the robot spinning in place; its real-time
factor with no load, then while 20 clients poll its state every 0.1 s and 2 clients send 1000
malformed requests (`lab.server_load`: the flood test's load, whose answers the test checks).
"""

import sys

from corobot_drake.arguments import BENCH_SECONDS, ToolParser, bounded, one_line_errors

try:  # without the [serve] extra: one line naming it, not a traceback
    from lab import server_load
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/bench_server_flood.py", "serve")


@one_line_errors
def main(argv=None) -> int:
    parser = ToolParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quiet-seconds", type=bounded(BENCH_SECONDS), default=10.0,
                        help="wall s measured with no load")
    args = parser.parse_args(argv)
    rates = server_load.measure(args.quiet_seconds)
    answers = rates.answers
    print(f"real-time factor {rates.loaded:.2f} (without the load: {rates.quiet:.2f}) over "
          f"{answers.wall_seconds:.1f} s of load: {len(answers.flood_codes)} malformed requests "
          f"({sum(400 <= c < 500 for c in answers.flood_codes)} answered 4xx), "
          f"{answers.polls_ok + answers.polls_bad} polls ({answers.polls_ok} answered 200)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
