#!/usr/bin/env python3
"""Trains the GoToGoal policy: the cross-entropy method over a linear policy, on Ray.

Saves the policy and plots the learning curve (`corobot_drake.gym.train`); `--evaluate` plays
the saved policy, its hand-written start and random actions on the held-out seeds.

    python tools/train_policy.py [--generations 10] [--population 10] [--episodes 8] ...
    python tools/train_policy.py --evaluate     # the held-out seeds' table
"""

import dataclasses as dc
import sys
from pathlib import Path

from corobot_drake.arguments import (
    WORKERS,
    ToolParser,
    bounded,
    one_line_errors,
    output_file,
)
from corobot_drake.gym.policy import SHIPPED, LinearPolicy
from corobot_drake.gym.rollouts import episode_pool
from corobot_drake.gym.train import HELD_OUT, CemSettings, evaluate, plot_curve, train
from corobot_drake.limits import OneOf, bound_of
from corobot_drake.simulation import quiet_drake_warnings
from corobot_drake.study.engine import AddressError

REPO = Path(__file__).resolve().parent.parent


RANDOM_SEEDS = HELD_OUT[:10]
"""Random actions are played on these only: they reach no goal, and each of their episodes
runs to the time limit."""


def _print_evaluation(policy: dict, start: dict, random: dict) -> None:
    print(f"Held-out seeds {HELD_OUT[0]}-{HELD_OUT[-1]}:")
    print("| policy | success rate | mean return | mean steps | collision steps | "
          "stall steps |")
    print("|---|---|---|---|---|---|")
    for name, s in (("trained (linear, CEM)", policy),
                    ("hand-written start (LinearPolicy.goal_seeker)", start),
                    (f"random actions (seeds {RANDOM_SEEDS[0]}-{RANDOM_SEEDS[-1]} only)",
                     random)):
        print(f"| {name} | {s['success_rate']:.0%} | {s['mean_return']:.1f} | "
              f"{s['mean_steps']:.1f} | {s['collision_steps']:.1f} | {s['stall_steps']:.1f} |")
    print(f"\nSuccess, trained minus hand-written: "
          f"{100 * (policy['success_rate'] - start['success_rate']):+.0f} points.")
    for name, s in (("trained", policy), ("hand-written", start)):
        print(f"Not reached by the {name} policy: seeds {', '.join(map(str, s['not_reached']))}.")


def _setting(parser: ToolParser, field: dc.Field, default) -> None:
    """A --flag for one CemSettings field, checked against the field's bound."""
    bound = bound_of(field)
    kwargs = ({"choices": bound.names} if isinstance(bound, OneOf)
              else {"type": bounded(bound, type(default))})
    parser.add_argument(f"--{field.name.replace('_', '-')}", default=default,
                        help=f"CEM {field.name}", **kwargs)


def _parser() -> ToolParser:
    p = ToolParser(description=__doc__.splitlines()[0])
    defaults = CemSettings()
    for field in dc.fields(CemSettings):
        _setting(p, field, getattr(defaults, field.name))
    p.add_argument("--workers", type=bounded(WORKERS, int), default=None,
                   help="Ray workers (None: this machine's cores)")
    p.add_argument("--address", default=None,
                   help="a Ray cluster's address (None: a local instance)")
    p.add_argument("--out", type=output_file, default=SHIPPED, help="where the policy is saved")
    p.add_argument("--plot", type=output_file,
                   default=REPO / "docs/images/gym_learning_curve.png",
                   help="the learning curve's picture")
    p.add_argument("--evaluate", action="store_true",
                   help="only evaluate the policy at --out and random actions on the held-out "
                        "seeds")
    return p


@one_line_errors
def main(argv=None) -> int:
    p = _parser()
    args = p.parse_args(argv)
    if args.elite > args.population:
        p.error(f"argument --elite: must be at most --population ({args.population}); "
                f"got {args.elite}")
    if args.evaluate and not args.out.is_file():
        p.error(f"argument --out: {args.out}: no such file (--evaluate reads a saved policy)")
    saved = None
    if args.evaluate:  # read before any worker starts: a bad file is its one line
        try:
            saved = LinearPolicy.load(args.out)
        except (ValueError, KeyError, TypeError) as e:  # JSONDecodeError is a ValueError
            p.error(f"argument --out: {args.out}: not a saved policy ({e})")
    quiet_drake_warnings()
    settings = CemSettings(**{f.name: getattr(args, f.name) for f in dc.fields(CemSettings)})
    try:
        with episode_pool(args.workers, args.address) as pool:
            if args.evaluate:
                held_out = evaluate(pool, saved)
                start = evaluate(pool, LinearPolicy.goal_seeker())
                random = evaluate(pool, None, RANDOM_SEEDS)
                _print_evaluation(held_out, start, random)
                return 0
            policy, curve = train(settings, pool)
    except AddressError as e:  # no Ray cluster there: the flag's one line
        print(f"error: --{e}", file=sys.stderr)
        return 2
    policy.save(args.out, trained_by="tools/train_policy.py", settings=dc.asdict(settings))
    plot_curve(curve, args.plot)
    print("| generation | population mean return | elite mean return | best | "
          "success (population) | success (elite) | s |")
    print("|---|---|---|---|---|---|---|")
    for c in curve:
        print(f"| {c.generation} | {c.mean_return:.1f} | {c.elite_return:.1f} | "
              f"{c.best_return:.1f} | {c.success_rate:.0%} | {c.elite_success_rate:.0%} | "
              f"{c.seconds:.0f} |")
    episodes = settings.generations * settings.population * settings.episodes
    print(f"\nTrained on {episodes} episodes ({settings.generations} generations x "
          f"{settings.population} candidates x {settings.episodes} seeds) in "
          f"{sum(c.seconds for c in curve):.0f} s; saved {args.out.name}, plotted "
          f"{args.plot.name}; `--evaluate` plays it on the held-out seeds.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
