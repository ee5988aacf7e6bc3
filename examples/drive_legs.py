#!/usr/bin/env python3
"""The book's random legs, driven through the live services with `CorobotClient`.

Each loop: rotate a random angle in [-45, 45] deg, drive a random 0.5-1.5 m, rotate 180 deg,
drive the same distance back, rotate 180 deg - angle (power 0.2); print the drift from the start
after each loop. The legs are the drive test's (`DriveTest.commands`): a seed gives the same
legs as `tools/drive_test.py --seed` and a study's `drive_test`. The orchestration (`legs`) uses
only methods the Python API and the client share, so the same function drives the in-process
simulation (`--local`).

    python -m corobot_drake --serve &                 # then:
    python examples/drive_legs.py --url http://127.0.0.1:50000 --loops 3 --seed 1
    python examples/drive_legs.py --loops 2           # starts a headless server of its own
    python examples/drive_legs.py --rate max          # ... that runs as fast as it can
    python examples/drive_legs.py --local --loops 2   # the same legs, in-process
"""

import argparse
import math
import sys

from corobot_drake.arguments import ToolParser, bounded
from corobot_drake.cli import ArgumentError, run_rate
from corobot_drake.commands import RotateDegrees
from corobot_drake.limits import DRAKE_INT, DRIVE_POWER
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.study.programs import COMMANDS_PER_LOOP, LOOPS, DriveTest

try:  # without the [serve] extra: one line naming it, not a traceback
    from corobot_drake.serving.client import CorobotClient
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("examples/drive_legs.py", "serve")


def legs(robot, loops: int, seed: int, power: float = 0.2, out=print) -> list[float]:
    """Drives the drive test's `loops` legs of `seed` out and back; returns the drift (m)
    after each loop."""
    commands = DriveTest(loops, power).commands(seed)
    x0, y0, _ = robot.position()
    drift = []
    for loop in range(1, loops + 1):
        mine = commands[(loop - 1) * COMMANDS_PER_LOOP:loop * COMMANDS_PER_LOOP]
        for step, command in enumerate(mine):
            if isinstance(command, RotateDegrees):
                name, value = "rotate_degrees", command.degrees
            else:  # DriveDistance
                name, value = "drive_distance", command.distance
            result = getattr(robot, name)(value, command.power)
            if not result.succeeded:
                out(f"  loop {loop} step {step + 1}: {name}({value:.3f}) {result.status}"
                    f" ({result.reason})")
        x, y, _ = robot.position()
        drift.append(math.hypot(x - x0, y - y0))
        out(f"loop {loop}: rotate {mine[0].degrees:+6.1f} deg, drive {mine[1].distance:.3f} m "
            f"-> drift {drift[-1] * 1000:7.1f} mm, heading {math.degrees(robot.heading()):+6.2f}"
            f" deg")
    return drift


def rate(text: str) -> float:
    """An argparse `type`: `python -m corobot_drake --rate`'s value (a number, or max)."""
    try:
        return run_rate(text)
    except ArgumentError as e:
        raise argparse.ArgumentTypeError(str(e).removeprefix("--rate: ")) from None


def main(argv=None) -> int:
    p = ToolParser(description=__doc__.splitlines()[0])
    p.add_argument("--url", help="a running server (default: start a headless one)")
    p.add_argument("--local", action="store_true", help="drive an in-process simulation")
    # The drive test's own bounds, so that a seed's legs are the same as its.
    p.add_argument("--loops", type=bounded(LOOPS, int), default=3, help="loops of the test")
    p.add_argument("--seed", type=bounded(DRAKE_INT, int), default=1, help="the legs' seed")
    p.add_argument("--power", type=bounded(DRIVE_POWER), default=0.2,
                   help="power of every command")
    p.add_argument("--rate", type=rate, default=1.0, metavar="X",
                   help="the started server's pace: simulated s per wall-clock s, or max: as "
                   "fast as it can (the same legs, sooner)")
    args = p.parse_args(argv)
    if args.rate != 1.0 and (args.url or args.local):
        p.error("--rate: only for the server this example starts (not with --url or --local)")
    if args.local:
        from corobot_drake.simulation import Simulation, quiet_drake_warnings

        quiet_drake_warnings()
        sim = Simulation.from_file(DEFAULT_SCENARIO)
        drift = legs(sim.robot(), args.loops, args.seed, args.power)
    elif args.url:
        with CorobotClient(args.url) as sim:
            drift = legs(sim.robot(), args.loops, args.seed, args.power)
    else:
        from corobot_drake.serving.serve import ServerProcess

        pace = "max" if math.isinf(args.rate) else repr(args.rate)
        with ServerProcess(["--headless", "--rate", pace]) as server:
            print(f"started {server.url}")
            with CorobotClient(server.url) as sim:
                drift = legs(sim.robot(), args.loops, args.seed, args.power)
    print(f"{len(drift)} loops: final drift {drift[-1] * 1000:.1f} mm, "
          f"mean {sum(drift) / len(drift) * 1000:.1f} mm")
    return 0


if __name__ == "__main__":
    sys.exit(main())
