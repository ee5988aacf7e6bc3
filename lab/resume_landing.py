"""How far a command resumed from a saved scene lands from the uninterrupted one
(`tools/resume_landing.py`; docs/commands.md).

For each landing profile, command and power (`CASES`): `saved_run` runs the command in the
default scene (camera off) uninterrupted, saving the scene every `step` s while it runs
(through the YAML a saved file holds); `landing_gaps` runs each saved scene on to the time the
uninterrupted run ended plus `settle` s and keeps the largest distance and heading gap between
the two landings; `table` is the Markdown the docs show.
"""

import dataclasses as dc
import math

from pydrake.common.yaml import yaml_dump_typed

from corobot_drake.config import scenario as sc
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.simulation import Simulation

COMMANDS = {"DriveDistance 0.3 m": "!DriveDistance {distance: 0.3, power: %g}",
            "RotateDegrees -60 deg": "!RotateDegrees {degrees: -60, power: %g}"}
"""Table name -> the command's YAML (`%g`: its power)."""
PROFILES = ("closed_loop", "seed")
POWERS = (0.5, 1.0)
CASES = [(profile, name, power) for profile in PROFILES for name in COMMANDS
         for power in POWERS]
"""(profile, command name, power) of each table row, in order."""


@dc.dataclass(frozen=True)
class Gaps:
    """One case's largest gaps between a resumed and the uninterrupted landing: (gap, the save
    time that gave it) in mm and in deg."""

    saves: int
    end: float
    """s: when the uninterrupted command ended."""
    mm: tuple[float, float | None]
    deg: tuple[float, float | None]


def scenario(profile: str, command: str) -> sc.Scenario:
    """The default scene without the camera, running `command` (its YAML) with `profile`."""
    return sc.load_scenario(DEFAULT_SCENARIO, overrides=[
        f"robots: {{corobot: {{cameras: {{front: {{rgb: false}}}}, motion: {{profile: {profile}}}, "
        f"commands: [{command}]}}}}"])


def landing(sim: Simulation) -> tuple[float, float, float]:
    """The robot's x, y (m) and heading (rad) in the world."""
    robot = sim.robot()
    return (*robot.position()[:2], robot.heading())


def saved_run(profile: str, command: str, step: float):
    """(end time of the command, the saved scenes' YAML by save time, the simulation)."""
    sim = Simulation(scenario(profile, command))
    saves, k = {}, 0
    while True:
        k += 1
        sim.advance_to(k * step)
        if sim.robot().summary()["commands"][0]["status"] != "running":
            return sim.time, saves, sim
        saves[sim.time] = yaml_dump_typed(sim.saved_scenario(), schema=sc.Scenario)


def landing_gaps(end: float, saves: dict, sim: Simulation, settle: float,
                 progress=None) -> Gaps:
    """Runs `sim` (the uninterrupted run, at `end`) and each of `saves` to `end + settle`;
    the largest gaps between their landings. `progress()` after each saved scene."""
    sim.advance_to(end + settle)
    x0, y0, h0 = landing(sim)
    again, worst = None, {"mm": (0.0, None), "deg": (0.0, None)}
    for t, text in saves.items():
        loaded = sc.load_scenario(data=text, defaults=sc.Scenario())
        if again is None:
            again = Simulation(loaded)
        else:
            again.reset(loaded)  # bit for bit a fresh simulation's run
        again.advance_to(end + settle)
        x, y, h = landing(again)
        gaps = {"mm": 1e3 * math.hypot(x - x0, y - y0),
                "deg": abs(math.degrees(math.remainder(h - h0, 2 * math.pi)))}
        for key, gap in gaps.items():
            if gap >= worst[key][0]:
                worst[key] = (gap, t)
        if progress is not None:
            progress()
    return Gaps(len(saves), end, **worst)


def _gap(gap: float, t: float, decimals: int) -> str:
    """The gap to `decimals` places, and the save time that gave it unless it shows as 0
    (then the largest is float rounding, ~1e-13, and where it falls is noise)."""
    text = f"{gap:.{decimals}f}"
    return text if float(text) == 0.0 else f"{text} (saved at {t:.2f} s)"


def table(gaps: list[Gaps], step: float, settle: float) -> str:
    """The Markdown table of `gaps` (one per `CASES` row) with its opening sentence."""
    rows = [f"| {profile} | {name} | {power:g} | {g.saves} (ends at {g.end:.2f} s) | "
            f"{_gap(*g.mm, 3)} | {_gap(*g.deg, 4)} |"
            for (profile, name, power), g in zip(CASES, gaps, strict=True)]
    return "\n".join([
        f"Saved every {step * 1e3:g} ms while the command runs; landings compared "
        f"{settle:g} s after it ends.\n",
        "| profile | command | power | saves (command ends) | largest gap, mm "
        "| largest gap, deg |",
        "|---|---|---|---|---|---|",
        *rows])
