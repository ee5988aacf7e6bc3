#!/usr/bin/env python3
"""Trains the GoToGoal policy: the cross-entropy method over its parameters, on Ray.

Saves the policy (`policy.json`) and plots the learning curve (`gym_learning_curve.png`) in
`--out` (default: the current directory); `--ship` puts them where the package and the docs
take them from instead (`corobot_drake/gym/policy.json`, `docs/images/`). `--evaluate` plays
a saved policy (`--policy`, default the shipped one), the hand-written goal seeker and random
actions on the held-out seeds.

    python tools/train_policy.py [--generations 4] [--population 8] [--episodes 16] ...
    python tools/train_policy.py --ship          # train and ship
    python tools/train_policy.py --evaluate      # the held-out seeds' table
"""

import dataclasses as dc
import sys
from pathlib import Path

from corobot_drake.arguments import (
    WORKERS,
    ToolParser,
    bounded,
    one_line_errors,
    output_directory,
)
from corobot_drake.cli import ctrl_c_stops, stopped_status
from corobot_drake.limits import OneOf, bound_of
from corobot_drake.simulation import quiet_drake_warnings

try:  # without the [gym] extra: one line naming it, not a traceback
    from corobot_drake.gym.policy import SHIPPED, LinearPolicy, load
    from corobot_drake.gym.rollouts import episode_pool
    from corobot_drake.gym.train import HELD_OUT, CemSettings, evaluate, plot_curve, train
    from corobot_drake.study.engine import AddressError
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/train_policy.py", "gym")

REPO = Path(__file__).resolve().parent.parent
POLICY_FILE = "policy.json"
CURVE_FILE = "gym_learning_curve.png"
SHIPPED_CURVE = REPO / "docs" / "images" / CURVE_FILE


RANDOM_SEEDS = HELD_OUT[:10]
"""Random actions are played on these only: they reach no goal, and each of their episodes
runs to the time limit."""


def _print_evaluation(policy: dict, start: dict, random: dict) -> None:
    print(f"Held-out seeds {HELD_OUT[0]}-{HELD_OUT[-1]}:")
    print("| policy | success rate | mean return | mean steps | collision steps | "
          "stall steps |")
    print("|---|---|---|---|---|---|")
    for name, s in ((f"trained ({policy['kind']}, CEM)", policy),
                    ("hand-written goal seeker (LinearPolicy.goal_seeker)", start),
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
    p.add_argument("--out", type=output_directory, default=Path("."),
                   help=f"the directory {POLICY_FILE} and {CURVE_FILE} are written to "
                        f"(default: the current one)")
    p.add_argument("--ship", action="store_true",
                   help=f"write the policy into the package ({SHIPPED}) and the curve into the "
                        f"docs ({SHIPPED_CURVE}) instead of --out")
    p.add_argument("--evaluate", action="store_true",
                   help="only evaluate --policy, the hand-written goal seeker and random "
                        "actions on the held-out seeds")
    p.add_argument("--policy", type=Path, default=SHIPPED,
                   help="the saved policy --evaluate plays (default: the shipped one)")
    return p


def outputs(args) -> tuple[Path, Path]:
    """Where training writes the policy and its learning curve: under --out, or with --ship
    into the package and the docs."""
    if args.ship:
        return SHIPPED, SHIPPED_CURVE
    return args.out / POLICY_FILE, args.out / CURVE_FILE


@one_line_errors
def main(argv=None) -> int:
    p = _parser()
    args = p.parse_args(argv)
    if args.elite > args.population:
        p.error(f"argument --elite: must be at most --population ({args.population}); "
                f"got {args.elite}")
    if args.evaluate and not args.policy.is_file():
        p.error(f"argument --policy: {args.policy}: no such file (--evaluate reads a saved "
                f"policy)")
    saved = None
    if args.evaluate:  # read before any worker starts: a bad file is its one line
        try:
            saved = load(args.policy)
        except ValueError as e:
            p.error(f"argument --policy: not a saved policy: {e}")
    policy_file, curve_file = outputs(args)
    if not args.evaluate:  # before training: an unwritable place fails now, not after it
        policy_file.parent.mkdir(parents=True, exist_ok=True)
        curve_file.parent.mkdir(parents=True, exist_ok=True)
    quiet_drake_warnings()
    settings = CemSettings(**{f.name: getattr(args, f.name) for f in dc.fields(CemSettings)})
    try:
        with episode_pool(args.workers, args.address) as pool:
            if args.evaluate:
                held_out = {**evaluate(pool, saved), "kind": type(saved).__name__}
                start = evaluate(pool, LinearPolicy.goal_seeker())
                random = evaluate(pool, None, RANDOM_SEEDS)
                _print_evaluation(held_out, start, random)
                return 0
            policy, curve = train(settings, pool)
    except AddressError as e:  # no Ray cluster there: the flag's one line
        print(f"error: --{e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # Ctrl-C or SIGTERM (ctrl_c_stops): Ray is shut down on the way
        print("stopped: nothing written (a policy is saved when its training ends)",
              file=sys.stderr)
        return stopped_status()
    policy.save(policy_file, trained_by="tools/train_policy.py", settings=dc.asdict(settings))
    plot_curve(curve, curve_file)
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
          f"{sum(c.seconds for c in curve):.0f} s; saved {policy_file.name}, plotted "
          f"{curve_file.name}; `--evaluate` plays it on the held-out seeds.")
    return 0


if __name__ == "__main__":
    ctrl_c_stops()
    sys.exit(main())
