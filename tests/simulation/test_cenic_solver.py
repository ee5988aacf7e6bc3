"""CENIC's solver parameters (`cenic_solver`): they reach the integrator, the default's short
line search saves iterations and moves the robot by nanometres, and a solver that gives up on a
step is one line that keeps the run so far."""

import pytest

from conftest import make_sim
from corobot_drake.config.scenario import LINESEARCH_TOLERANCE
from corobot_drake.simulation import PhysicsError

ROBOT = "corobot"
DRIVE = ("robots: {corobot: {commands: [!SetPower {left: 0.8, right: 0.5}, !Wait {seconds: 1.0}, "
         "!SetPower {left: -0.3, right: 0.9}]}}")
"""A curve, then a spin the other way: the tyres roll and scrub."""
DRAKE_DEFAULT = "{cenic_solver: {linesearch_tolerance: 1.0e-8}}"
"""Drake's own `IcfSolverParameters` (the default scenario's differ in this one)."""


def _drive(*overrides: str) -> tuple[list[float], float, float]:
    """([x, y, yaw] after 2 s of `DRIVE`, Newton iterations per step, line-search iterations
    per step)."""
    sim = make_sim(DRIVE, *overrides)
    sim.advance(2.0)
    integrator = sim.simulator.get_integrator()
    stats, steps = dict(integrator.GetStatisticsSummary()), integrator.get_num_steps_taken()
    pose = sim.robot(ROBOT).pose()
    return ([pose.x, pose.y, pose.yaw], stats["cenic_total_solver_iterations"] / steps,
            stats["cenic_total_ls_iterations"] / steps)


def test_the_parameters_reach_cenic():
    parameters = make_sim().simulator.get_integrator().get_solver_parameters()
    assert parameters.linesearch_tolerance == LINESEARCH_TOLERANCE
    assert parameters.min_tolerance == 1e-8  # Drake's
    parameters = make_sim("{cenic_solver: {min_tolerance: 1.0e-6}}").simulator.get_integrator(
        ).get_solver_parameters()
    assert (parameters.min_tolerance, parameters.linesearch_tolerance) == (
        1e-6, LINESEARCH_TOLERANCE)  # a layer changes only what it writes


def test_the_short_line_search_saves_iterations_and_moves_the_robot_by_nanometres():
    """Measured: 3.3 against 4.4 line-search iterations a step, 3.0 Newton iterations either
    way, and the pose 0.01 nm and 0.01 nrad off after 2 s. The bound, 0.1 um and 0.1 urad,
    is ten thousand times that and far below the docs' figures (mm, 0.01 deg)."""
    ours, newton, line_search = _drive()
    drake, drake_newton, drake_line_search = _drive(DRAKE_DEFAULT)
    assert ours != drake  # the parameters change the steps
    assert ours == pytest.approx(drake, abs=1e-7)
    assert newton == pytest.approx(drake_newton, rel=0.02)
    assert line_search < 0.85 * drake_line_search  # measured 0.75


@pytest.mark.parametrize("fields, words", [
    # Drake: "CenicIntegrator: optimization failed."
    ({"max_iterations": 1}, "max_iterations 1 "),
    # Drake: "NewtonWithBisectionFallback did not converge." (a line search)
    ({"max_linesearch_iterations": 1, "linesearch_tolerance": 1e-300},
     "max_linesearch_iterations 1)"),
])
def test_a_solver_that_gives_up_is_one_line_and_keeps_the_run(fields, words):
    """Past the loader's bounds (set on the integrator, as nothing a scenario holds can): each
    of Drake's two ways of giving up is one line naming the limit."""
    sim = make_sim(DRIVE)
    sim.advance(0.5)
    parameters = sim.simulator.get_integrator().get_solver_parameters()
    for field, value in fields.items():
        setattr(sim.scenario.cenic_solver, field, value)  # what the message reads
        setattr(parameters, field, value)
    sim.simulator.get_mutable_integrator().SetSolverParameters(parameters)
    with pytest.raises(PhysicsError) as raised:
        sim.advance(0.5)
    message, t = str(raised.value), sim.time  # the step that gave up starts at t
    assert "\n" not in message
    assert message.startswith(f"cenic_solver: CENIC's step from t = {t:.6g} s did not converge")
    assert words in message
    assert 0.5 <= t < 1.0
    assert len(sim.robot(ROBOT).run_log()) == round(t / 0.01) + 1  # the run so far, every row


def test_a_live_run_writes_the_run_so_far_when_the_solver_gives_up():
    """The --ros2 front's loop (`run_live`, here with a front that attaches nothing: no DDS):
    the simulation's thread stops on the PhysicsError, the outputs are written from the
    caller's, then the error is raised (the CLI prints its line)."""
    from corobot_drake.config.scenario import load_scenario
    from corobot_drake.resources import DEFAULT_SCENARIO
    from corobot_drake.ros2.run import run_live
    from corobot_drake.simulation import Simulation

    scenario = load_scenario(DEFAULT_SCENARIO, overrides=[DRIVE])
    scenario.cenic_solver.max_iterations = 1  # past the bound: the first step gives up

    class NoFront:
        def attach(self, runner):
            pass

    finished = []
    with pytest.raises(PhysicsError):
        run_live(NoFront(), lambda meshcat: Simulation(scenario, check=False), meshcat=False,
                 duration=1.0, run_log_window=None,
                 finish=lambda sim: finished.append(sim.time) or 0)
    assert finished == [0.0]
