"""Real-time factors of the default scene driving a figure of eight (`tools/bench.py`).

Stacks (physics only; + 2 IR at 20 Hz; + camera at 30 Hz; both) times plant settings
(CENIC at 10, 5 and 2 ms; SAP at 10 and 2 ms; SAP with point contact at 10 ms):
:func:`realtime_factor` of
`sensor_overrides(**STACKS[stack])` with `PLANTS[plant]`. Fleets of robots, each driving
the figure of eight: :func:`robot_seconds_per_second`.
"""

import os
import platform
import time
from importlib.metadata import version
from pathlib import Path

from corobot_drake.config import scenario as sc
from corobot_drake.config.presets import (  # noqa: F401 (the lab's names for them)
    CAMERA_FPS,
    IR_RATE_HZ,
    physics_only_overrides,
    sensor_overrides,
)
from corobot_drake.config.scenario import load_scenario
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.simulation import Simulation

ROBOT = "corobot"
DRIVING = (f"robots: {{{ROBOT}: {{commands: [!SetPower {{left: 1.0, right: 0.6}}, "
           "!Wait {seconds: 3}, !SetPower {left: 0.6, right: 1.0}, !Wait {seconds: 3}, "
           "!SetPower {left: -1.0, right: 1.0}]}}")
"""The figure of eight the benchmarks drive (a scenario override)."""
NO_CAMERA = f"robots: {{{ROBOT}: {{cameras: {{front: {{rgb: false}}}}}}}}"
"""The override that turns the robot's camera off (its IR sensors as the scenario has them)."""


def realtime_factor(overrides: list[str], seconds: float,
                    scenario: Path = DEFAULT_SCENARIO) -> tuple[float, float]:
    """(wall, CPU) simulated seconds per second of the figure of eight, building excluded."""
    sim = Simulation(load_scenario(scenario, overrides=[DRIVING, *overrides]))
    wall, cpu = time.perf_counter(), time.process_time()
    sim.advance(seconds)
    return seconds / (time.perf_counter() - wall), seconds / (time.process_time() - cpu)


ROBOT_SPACING = 4.0
"""m between the robots of a fleet (on a 4-wide grid): their figures of eight stay apart."""


def fleet_overrides(count: int) -> list[str]:
    """`count` robots (`corobot` and `robot_1`...) on a grid, each driving the figure of eight,
    physics only."""
    overrides = [DRIVING, *physics_only_overrides()]
    commands = DRIVING[DRIVING.index("commands:"):-2]
    for i in range(1, count):
        name = f"robot_{i}"
        x, y = ROBOT_SPACING * (i % 4), ROBOT_SPACING * (i // 4)
        overrides += [f"robots: {{{name}: {{pose: {{translation: [{x}, {y}, 0.0]}}, "
                      f"{commands}}}}}", *physics_only_overrides(name)]
    return overrides


def robot_seconds_per_second(count: int, seconds: float) -> tuple[float, float]:
    """(wall, CPU) simulated robot-seconds per second of `count` robots driving, physics only
    (`fleet_overrides`), building excluded."""
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=fleet_overrides(count)))
    wall, cpu = time.perf_counter(), time.process_time()
    sim.advance(seconds)
    return (count * seconds / (time.perf_counter() - wall),
            count * seconds / (time.process_time() - cpu))


STACKS = {
    "physics only": dict(ir=False, camera=False),
    f"+ 2 IR at {IR_RATE_HZ:g} Hz": dict(ir=True, camera=False),
    f"+ camera at {CAMERA_FPS:g} Hz": dict(ir=False, camera=True),
    "full stack (IR + camera)": dict(ir=True, camera=True),
}
"""Stack name -> `sensor_overrides` flags."""
PLANTS = {
    "CENIC 10 ms (default)": sc.CENIC_PLANT % 0.01,
    "CENIC 5 ms": sc.CENIC_PLANT % 0.005,
    "CENIC 2 ms": sc.CENIC_PLANT % 0.002,
    "SAP 10 ms": sc.SAP_PLANT % 0.01,
    "SAP 2 ms": sc.SAP_PLANT % 0.002,
    "SAP point 10 ms": ("{plant_config: {time_step: 0.01, contact_model: point}, "
                        "simulator_config: {integration_scheme: runge_kutta3}}"),
}
"""Plant setting name -> scenario override (hydroelastic unless named point)."""
DEFAULT_PLANT = "CENIC 10 ms (default)"
IN_PLACE = ((f"+ 2 IR at {IR_RATE_HZ:g} Hz", IR_RATE_HZ, "scan (2 sensors)"),
            (f"+ camera at {CAMERA_FPS:g} Hz", CAMERA_FPS, "frame"))
"""(stack, events per simulated second, what one event is) of each sensor's in-place cost."""


def in_place_ms(rtf: tuple[float, float], base: tuple[float, float],
                per_second: float) -> tuple[float, float]:
    """(wall, CPU) ms per sensor event: the extra time per simulated second of a stack with
    real-time factors `rtf` over `base` (physics only), per event."""
    wall, cpu = ((1 / rtf[i] - 1 / base[i]) / per_second * 1000 for i in (0, 1))
    return wall, cpu


def machine() -> str:
    """One line: cores, CPU model, OS, Python and drake versions."""
    cpu = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (f"{os.cpu_count()} cores ({cpu}), no GPU, {platform.system()} {platform.release()}, "
            f"Python {platform.python_version()}, drake {version('drake')}")
