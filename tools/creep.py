#!/usr/bin/env python3
"""How far a robot left at rest creeps, with the drive's hold and without it, and why
(`lab/creep.py`; docs/physics.md, "At rest").

    python tools/creep.py [--seconds 30] [--points 13] [--minutes 30]
    python tools/creep.py --isolate

Maps the unheld roll's rate against the wheels' angle over half a facet of the tyres' mesh,
predicts from it the creep over `--minutes` (from the default start and from the worst one),
then measures a resting robot `--seconds` from the default start and from the map's fastest
angle, unheld and held. `--isolate` instead measures the unheld roll with one thing changed at
a time (servo, contact approximation, step, friction regularization, dissipation, mesh, point
contact): the experiments that found the cause.
"""

import math
import sys

try:  # without the [study] extra: one line naming it, not a traceback
    from tqdm import tqdm
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/creep.py", "study")

from corobot_drake.arguments import ToolParser, bounded, one_line_errors
from corobot_drake.config.scenario import load_scenario
from corobot_drake.limits import Range
from corobot_drake.resources import DEFAULT_SCENARIO
from lab import creep


def _um(metres: float) -> str:
    return f"{metres * 1e6:.3g}"


SECONDS = Range(0.0, 3600.0, low_open=True, unit="s")
POINTS = Range(2, 1000, why="wheel angles over half a facet")
MINUTES = Range(0.0, 1e4, low_open=True, unit="min")


@one_line_errors
def main(argv=None) -> int:
    p = ToolParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seconds", type=bounded(SECONDS), default=30.0,
                   help="simulated seconds each resting robot is measured")
    p.add_argument("--points", type=bounded(POINTS, int), default=13,
                   help="wheel angles the rate map samples over half a facet")
    p.add_argument("--minutes", type=bounded(MINUTES), default=30.0,
                   help="simulated minutes the creep is predicted over")
    p.add_argument("--isolate", action="store_true",
                   help="the one-change-at-a-time table instead (unheld, 5 s each)")
    args = p.parse_args(argv)
    if args.isolate:
        return isolate()
    robot = next(iter(load_scenario(DEFAULT_SCENARIO).robots.values()))
    radius = robot.drive.effective_wheel_radius
    facets, facet = creep.tyre_facets(robot.contact), creep.facet_angle(robot.contact)
    with tqdm(total=args.points + 4, unit="run", file=sys.stderr) as bar:
        angles, rates = creep.rate_map(args.points, progress=lambda _: bar.update())
        worst = float(angles[abs(rates).argmax()])
        runs = []
        for start in (0.0, worst):
            for hold in (False, True):
                runs.append(creep.rest_run(start, args.seconds, hold))
                bar.update()
    seconds = 60 * args.minutes
    print(f"tyre mesh: {facets} facets of {math.degrees(facet):.2f} deg "
          f"(resolution hint {robot.contact.resolution_hint * 1000:g} mm)")
    damping = robot.contact.servo_damping
    print("\n| wheel angle (deg) | unheld roll (urad/s) | at the rim (um/s) | "
          "moment rolling each wheel (N m: servo damping x roll) |")
    print("|---|---|---|---|")
    for a, r in zip(angles, rates, strict=True):
        print(f"| {math.degrees(a):.2f} | {r * 1e6:+.2f} | {r * radius * 1e6:+.3f} | "
              f"{r * damping:+.2g} |")
    stable = creep.stable_angles(angles, rates)
    if stable:
        farthest = max(max(s, angles[-1] - s) for s in stable)
        print(f"\nstable wheel angles: {', '.join(f'{math.degrees(s):.2f}' for s in stable)} "
              f"deg (and mirrored about half a facet); unheld, a resting robot rolls at most "
              f"{farthest * radius * 1000:.2f} mm in all")
    else:  # the roll turns back over a fraction of a facet: a coarse map steps over it
        print(f"\nstable wheel angles: none among the {args.points} mapped angles, "
              f"{math.degrees(angles[1] - angles[0]):.2f} deg apart (one between two of them "
              f"goes unseen: more --points map it finer)")
    from_zero = creep.predict(angles, rates, 0.0, seconds)
    start, rotation = creep.worst_prediction(angles, rates, seconds)
    print(f"\npredicted unheld over {args.minutes:g} min: {abs(from_zero) * radius * 1e6:.3g} um "
          f"from the default start (wheels at 0); at most {rotation * radius * 1000:.2f} mm "
          f"(wheels starting at {math.degrees(start):.2f} deg)")
    print(f"\n| start (wheel angle, deg) | hold | creep in {args.seconds:g} s (um) | "
          f"rate (um/s) | yaw (urad) |")
    print("|---|---|---|---|---|")
    for run in runs:
        print(f"| {math.degrees(run.start_angle):.2f} | {'on' if run.hold else 'off'} | "
              f"{_um(run.displacement)} | {_um(run.rate)} | {run.yaw * 1e6:+.3g} |")
    return 0


def isolate() -> int:
    with tqdm(total=len(creep.ISOLATION), unit="run", file=sys.stderr) as bar:
        rows = creep.isolate(progress=lambda _: bar.update())
    shipped = rows[0][2]
    print(f"| change (one at a time) | start (wheel angle, deg) | unheld creep "
          f"(um/s, over {creep.ISOLATION_SECONDS:g} s) | against shipped |")
    print("|---|---|---|---|")
    for label, start, rate in rows:
        print(f"| {label} | {math.degrees(start):.2f} | {rate * 1e6:.3g} | "
              f"{rate / shipped:.3g} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
