"""Real-time factor of the default scene, headless (run: python tools/bench.py).

Prints a markdown table: each configuration is simulated for `--seconds` with the robot
driving a figure of eight, three times; the median real-time factor is reported.
"""

import argparse
import statistics
import time
from pathlib import Path

from corobot_drake.scenario import load_scenario
from corobot_drake.simulation import Simulation, quiet_drake_warnings

DEFAULT_SCENARIO = Path(__file__).resolve().parent.parent / "scenarios" / "corobot.yaml"
DRIVING = ("robots: {corobot: {commands: [!SetPower {left: 1.0, right: 0.6}, !Wait {seconds: 3},"
           " !SetPower {left: 0.6, right: 1.0}, !Wait {seconds: 3}, !SetPower {left: -1.0,"
           " right: 1.0}]}}")


def realtime_factor(overrides: list[str], seconds: float) -> float:
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[DRIVING, *overrides]))
    start = time.perf_counter()
    sim.advance(seconds)
    return seconds / (time.perf_counter() - start)


CONFIGURATIONS = {
    "physics only, default (5 ms, hydroelastic)": [],
    "physics only, 2 ms": ["plant_config: {time_step: 0.002}"],
    "physics only, 1 ms": ["plant_config: {time_step: 0.001}"],
    "physics only, point contact": ["plant_config: {contact_model: point}"],
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="simulated s per run")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--only", help="run only configurations containing this text")
    args = parser.parse_args()
    quiet_drake_warnings()
    print("| configuration | real-time factor (median) |")
    print("|---|---|")
    for name, overrides in CONFIGURATIONS.items():
        if args.only and args.only not in name:
            continue
        rtfs = [realtime_factor(overrides, args.seconds) for _ in range(args.repeats)]
        print(f"| {name} | {statistics.median(rtfs):.2f}x |", flush=True)


if __name__ == "__main__":
    main()
