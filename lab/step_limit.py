"""The coarsest plant step the tyres' contact resolves (`limits.py`, MAX_TIME_STEP).

The default scene, cameras and IR sensors off, drives 5 s (1.5 s full power forward, 1.5 s
spinning left, 2 s full power back) at each plant step; every 50 ms the chassis frame's
height (its origin is on the ground when the tyres do not sink) and tilt are sampled. Coarser
steps let the stiff tyre contact overshoot: the robot sinks into the ground and rocks.
The plant step is set on the loaded scenario, past the loader's bound, to measure beyond it,
on a discrete plant stepped by SAP (CENIC's step, `simulator_config.max_step_size`, has the
same bound, but the drive's 10 ms events end each of its steps sooner).
"""

import math

from corobot_drake.config.scenario import load_scenario
from corobot_drake.resources import DEFAULT_SCENARIO

SCRIPT = ("robots: {corobot: {commands: [!SetPower {left: 1, right: 1}, !Wait {seconds: 1.5}, "
          "!SetPower {left: -1, right: 1}, !Wait {seconds: 1.5}, "
          "!SetPower {left: -1, right: -1}]}}")
SECONDS = 5.0
SAMPLE = 0.05


def measure(time_step: float) -> dict:
    """{time_step, sink_mm (deepest the chassis frame went below the ground), rise_mm
    (highest above), tilt_deg (largest)} over the drive."""
    from corobot_drake.simulation import Simulation
    from lab.bench import physics_only_overrides

    scenario = load_scenario(DEFAULT_SCENARIO, overrides=[SCRIPT, *physics_only_overrides()])
    # SAP's discrete step: CENIC's (`max_step_size`) never exceeds the drive's 10 ms control
    # period, whose events end every step; the bound is a discrete plant's.
    scenario.plant_config.time_step = time_step
    scenario.simulator_config.integration_scheme = "runge_kutta3"
    sim = Simulation(scenario, check=False)  # steps beyond the bound: what it measures
    plant, chassis = sim.station.plant, sim.robot()._parts.chassis
    heights, tilts = [], []
    while sim.time < SECONDS - 1e-9:
        sim.advance(SAMPLE)
        X = plant.EvalBodyPoseInWorld(plant.GetMyContextFromRoot(sim.context), chassis)
        heights.append(X.translation()[2])
        tilts.append(math.degrees(math.acos(min(1.0, X.rotation().matrix()[2, 2]))))
    return {"time_step": time_step, "sink_mm": -1000 * min(heights),
            "rise_mm": 1000 * max(heights), "tilt_deg": max(tilts)}


def table(rows: list[dict], limit: float) -> str:
    lines = ["| plant step (ms) | chassis frame height, lowest / highest (mm) | "
             "largest tilt (deg) | loader |", "|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {1000 * r['time_step']:g} | {-r['sink_mm']:.1f} / {r['rise_mm']:.1f} "
                     f"| {r['tilt_deg']:.2f} | "
                     f"{'accepts' if r['time_step'] <= limit else 'refuses'} |")
    return "\n".join(lines)
