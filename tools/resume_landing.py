#!/usr/bin/env python3
"""How far a command resumed from a saved scene lands from the uninterrupted one.

For each landing profile, command (DriveDistance 0.3 m, RotateDegrees -60 deg) and power, runs
the command in the default scene (camera off) uninterrupted, saving the scene every `--step`
s while it runs (through the YAML a saved file holds); then runs each saved scene on to the
time the uninterrupted run ended plus `--settle` s and prints a Markdown table of the largest
distance and heading gap between the two landings (docs/commands.md, issue 14).

    python tools/resume_landing.py [--step 0.02] [--settle 1.0]
"""

import math
import sys

from pydrake.common.yaml import yaml_dump_typed
from tqdm import tqdm

from corobot_drake.analysis.arguments import ToolParser, bounded, one_line_errors
from corobot_drake.config import scenario as sc
from corobot_drake.config.bounds import Range
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.simulation import Simulation, quiet_drake_warnings

COMMANDS = {"DriveDistance 0.3 m": "!DriveDistance {distance: 0.3, power: %g}",
            "RotateDegrees -60 deg": "!RotateDegrees {degrees: -60, power: %g}"}
PROFILES = ("closed_loop", "seed")
POWERS = (0.5, 1.0)


def _scenario(profile: str, command: str) -> sc.Scenario:
    return sc.load_scenario(DEFAULT_SCENARIO, overrides=[
        f"robots: {{corobot: {{camera: {{rgb: false}}, motion: {{profile: {profile}}}, "
        f"commands: [{command}]}}}}"])


def _landing(sim: Simulation) -> tuple[float, float, float]:
    robot = sim.robot()
    return (*robot.position()[:2], robot.heading())


def _saved_run(profile: str, command: str, step: float):
    """(end time of the command, the saved scenes' YAML by save time, the simulation)."""
    sim = Simulation(_scenario(profile, command))
    saves, k = {}, 0
    while True:
        k += 1
        sim.advance_to(k * step)
        if sim.robot().summary()["commands"][0]["status"] != "running":
            return sim.time, saves, sim
        saves[sim.time] = yaml_dump_typed(sim.saved_scenario(), schema=sc.Scenario)


def measure(profile: str, command: str, step: float, settle: float, bar) -> dict:
    end, saves, sim = _saved_run(profile, command, step)
    sim.advance_to(end + settle)
    x0, y0, h0 = _landing(sim)
    again, worst = None, {"mm": (0.0, None), "deg": (0.0, None)}
    bar.total += len(saves)
    for t, text in saves.items():
        scenario = sc.load_scenario(data=text, defaults=sc.Scenario())
        if again is None:
            again = Simulation(scenario)
        else:
            again.reset(scenario)  # bit for bit a fresh simulation's run
        again.advance_to(end + settle)
        x, y, h = _landing(again)
        gaps = {"mm": 1e3 * math.hypot(x - x0, y - y0),
                "deg": abs(math.degrees(math.remainder(h - h0, 2 * math.pi)))}
        for key, gap in gaps.items():
            if gap >= worst[key][0]:
                worst[key] = (gap, t)
        bar.update()
    return {"saves": len(saves), "end": end, **worst}


def _gap(gap: float, t: float, decimals: int) -> str:
    """The gap to `decimals` places, and the save time that gave it unless it shows as 0
    (then the largest is float rounding, ~1e-13, and where it falls is noise)."""
    text = f"{gap:.{decimals}f}"
    return text if float(text) == 0.0 else f"{text} (saved at {t:.2f} s)"


STEP = Range(0.01, 10.0, unit="s", why="a multiple of the 10 ms control period")
SETTLE = Range(0.0, 100.0, unit="s")


@one_line_errors
def main(argv=None) -> int:
    p = ToolParser(description=__doc__.splitlines()[0])
    p.add_argument("--step", type=bounded(STEP), default=0.02,
                   help="s between saves (a multiple of the 10 ms control period)")
    p.add_argument("--settle", type=bounded(SETTLE), default=1.0,
                   help="s after the command ends when the landings are compared")
    args = p.parse_args(argv)
    quiet_drake_warnings()
    rows = []
    with tqdm(total=0, unit="save", file=sys.stderr) as bar:
        for profile in PROFILES:
            for name, command in COMMANDS.items():
                for power in POWERS:
                    r = measure(profile, command % power, args.step, args.settle, bar)
                    rows.append(f"| {profile} | {name} | {power:g} | {r['saves']} "
                                f"(ends at {r['end']:.2f} s) | {_gap(*r['mm'], 3)} "
                                f"| {_gap(*r['deg'], 4)} |")
    print(f"Saved every {args.step * 1e3:g} ms while the command runs; landings compared "
          f"{args.settle:g} s after it ends.\n")
    print("| profile | command | power | saves (command ends) | largest gap, mm "
          "| largest gap, deg |")
    print("|---|---|---|---|---|---|")
    print("\n".join(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
