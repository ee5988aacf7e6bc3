"""What CENIC's solver tolerances (`cenic_solver`) cost and move (`tools/cenic_solver.py`).

Each row is one setting of Drake's `IcfSolverParameters` (the rest as the default scenario's):
- the default scene, physics only, drives `SCRIPT` (a curve, a spin, full power straight, a
  spin the other way: the tyres roll, scrub and slip) for `SECONDS`: the solver's Newton and
  line-search iterations per step, and how far the robot ends from where Drake's own
  parameters bring it (deterministic);
- the gym (`GoToGoalEnv`, random powers: the tyres slip most) steps `GYM_STEPS` times, the
  rows interleaved over `repeats` rounds: env steps per CPU second, median, against Drake's
  parameters'.
"""

import dataclasses as dc
import math
import statistics
import time

from pydrake.multibody.contact_solvers import IcfSolverParameters

from corobot_drake.config.scenario import LINESEARCH_TOLERANCE, load_scenario
from corobot_drake.resources import DEFAULT_SCENARIO

SCRIPT = ("robots: {corobot: {commands: [!SetPower {left: 0.8, right: 0.5}, !Wait {seconds: 1.0}, "
          "!SetPower {left: -0.3, right: 0.9}, !Wait {seconds: 2.0}, "
          "!SetPower {left: 1.0, right: 1.0}, !Wait {seconds: 2.0}, "
          "!SetPower {left: -1.0, right: 1.0}]}}")
SECONDS = 8.0
GYM_STEPS = 300


@dc.dataclass(frozen=True)
class Setting:
    """A row: a name and the parameters that differ from Drake's."""

    name: str
    min_tolerance: float = 1e-8
    linesearch_tolerance: float = 1e-8

    def parameters(self) -> IcfSolverParameters:
        return IcfSolverParameters(min_tolerance=self.min_tolerance,
                                   linesearch_tolerance=self.linesearch_tolerance)


DRAKE = Setting("Drake's (min_tolerance 1e-8, linesearch_tolerance 1e-8)")
SETTINGS = (
    DRAKE,
    Setting("linesearch_tolerance 1e-6", linesearch_tolerance=1e-6),
    Setting("linesearch_tolerance 1e-4", linesearch_tolerance=1e-4),
    Setting(f"**linesearch_tolerance {LINESEARCH_TOLERANCE:g}** (the default)",
            linesearch_tolerance=LINESEARCH_TOLERANCE),
    Setting("linesearch_tolerance 1e-2 (past the loader's bound)", linesearch_tolerance=1e-2),
    Setting("linesearch_tolerance 5e-2 (past the loader's bound)", linesearch_tolerance=5e-2),
    Setting(f"min_tolerance 1e-6, linesearch_tolerance {LINESEARCH_TOLERANCE:g}",
            min_tolerance=1e-6, linesearch_tolerance=LINESEARCH_TOLERANCE),
    Setting(f"min_tolerance 1e-5, linesearch_tolerance {LINESEARCH_TOLERANCE:g}",
            min_tolerance=1e-5, linesearch_tolerance=LINESEARCH_TOLERANCE),
)


def drive(setting: Setting) -> dict:
    """{newton, line_search: iterations per step; pose: [x, y, yaw] (m, m, rad)} of `SCRIPT`,
    or {failed: the time (s) of the step the solver gave up on}."""
    from corobot_drake.simulation import PhysicsError, Simulation
    from lab.bench import physics_only_overrides

    scenario = load_scenario(DEFAULT_SCENARIO, overrides=[SCRIPT, *physics_only_overrides()])
    scenario.cenic_solver = setting.parameters()
    sim = Simulation(scenario, check=False)  # a setting past the bounds: what it measures
    try:
        sim.advance(SECONDS)
    except PhysicsError:
        return {"failed": sim.time}
    integrator = sim.simulator.get_integrator()
    stats, steps = dict(integrator.GetStatisticsSummary()), integrator.get_num_steps_taken()
    pose = sim.robot().pose()
    return {"newton": stats["cenic_total_solver_iterations"] / steps,
            "line_search": stats["cenic_total_ls_iterations"] / steps,
            "pose": [pose.x, pose.y, pose.yaw]}


def gym_rate(setting: Setting) -> float:
    """Env steps per CPU second of `GYM_STEPS` random actions (seed 0), the env's CENIC
    solver set to `setting` (it keeps it through the resets: one Simulator)."""
    from corobot_drake.gym.env import GoToGoalEnv

    env = GoToGoalEnv()
    env.reset(seed=0)
    env.action_space.seed(0)
    integrator = env.sim.simulator.get_mutable_integrator()
    integrator.SetSolverParameters(setting.parameters())
    start = time.process_time()
    for _ in range(GYM_STEPS):
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if terminated or truncated:
            env.reset()
    rate = GYM_STEPS / (time.process_time() - start)
    used = integrator.get_solver_parameters()
    assert (used.min_tolerance, used.linesearch_tolerance) == (setting.min_tolerance,
                                                               setting.linesearch_tolerance)
    env.close()
    return rate


def table(drives: dict, rates: dict) -> str:
    """Markdown: a row per setting (`drives`, `rates`: {Setting: drive(), [gym_rate()]})."""
    base = drives[DRAKE]["pose"]
    lines = ["| CENIC's solver (`cenic_solver`) | Newton iterations per step | "
             "line-search iterations per step | ends off Drake's: position (nm), heading (nrad) "
             "| gym env steps per CPU s, median (a round's against Drake's, median) |",
             "|---|---|---|---|---|"]
    for setting in SETTINGS:
        d = drives[setting]
        if "failed" in d:
            lines.append(f"| {setting.name} | | | gives up on the step from t = {d['failed']:g} "
                         "s | |")
            continue
        (x, y, yaw), (x0, y0, yaw0) = d["pose"], base
        moved = f"{1e9 * math.hypot(x - x0, y - y0):.3g}, {1e9 * abs(yaw - yaw0):.3g}"
        rate = statistics.median(rates[setting])
        # Each round's rate against Drake's in the same round: the host's swings cancel.
        ratio = statistics.median(r / r0 for r, r0 in zip(rates[setting], rates[DRAKE],
                                                          strict=True))
        lines.append(f"| {setting.name} | {d['newton']:.2f} | {d['line_search']:.2f} | {moved} "
                     f"| {rate:.1f} ({ratio:.2f}) |")
    return "\n".join(lines)
