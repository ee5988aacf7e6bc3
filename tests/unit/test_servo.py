"""The wheels' velocity servo under CENIC: the sign probe, its compensation, and the defect
itself (a test that fails the day Drake fixes it, so the compensation's note can go)."""

import numpy as np
import pytest
from pydrake.systems.analysis import SimulatorConfig

from conftest import make_sim
from corobot_drake.config.scenario import SAP_PLANT
from corobot_drake.systems.servo import (
    PROBE_DAMPING,
    PROBE_SPEED,
    add_servo_sign,
    probe_servo_speed,
    servo_velocity_sign,
)

STEP = 0.01
CENIC = SimulatorConfig(integration_scheme="cenic", max_step_size=STEP, use_error_control=False)
CENIC_SCENE = ("{plant_config: {time_step: 0}, simulator_config: {integration_scheme: cenic, "
               f"max_step_size: {STEP}, use_error_control: false}}}}")
SAP_SCENE = SAP_PLANT % STEP
IMPLICIT_ONE_STEP = STEP * PROBE_DAMPING * PROBE_SPEED / (1.0 + STEP * PROBE_DAMPING)
"""rad/s: one implicit PD step of the probe's 1 kg m^2 wheel from rest."""


def test_drake_cenic_still_turns_the_pd_servo_backwards():
    """Fails the day Drake fixes the sign of Kd vd in icf_external_systems_linearizer.cc:
    then the probe returns +1 and nothing is compensated (the station needs no change), but
    systems/servo.py's docstring, docs/performance.md and this test describe a defect that is
    gone: update them (tools/cenic_pd_sign_repro.py then exits 0)."""
    speed = probe_servo_speed(CENIC)
    assert speed == pytest.approx(-IMPLICIT_ONE_STEP, rel=1e-6), (
        f"CENIC's PD servo now gives {speed:+.6g} rad/s for +{IMPLICIT_ONE_STEP:.6g}: Drake "
        "fixed (or changed) the desired-velocity sign; revisit corobot_drake/systems/servo.py")
    assert servo_velocity_sign(CENIC) == -1.0


def test_other_integrators_are_not_compensated():
    """The probe on an integrator without the defect gives the implicit step's sign (+)."""
    rk3 = SimulatorConfig(integration_scheme="runge_kutta3", max_step_size=STEP,
                          use_error_control=False)
    assert probe_servo_speed(rk3) > 0.0
    assert servo_velocity_sign(rk3) == 1.0
    assert servo_velocity_sign(SimulatorConfig()) == 1.0


def test_servo_sign_gain_negates_only_the_desired_velocities():
    from pydrake.systems.framework import DiagramBuilder

    builder = DiagramBuilder()
    gain = add_servo_sign(builder, "servo_sign", -1.0, 8)
    context = gain.CreateDefaultContext()
    x = np.arange(1.0, 9.0)
    gain.get_input_port().FixValue(context, x)
    np.testing.assert_array_equal(gain.get_output_port().Eval(context),
                                  np.concatenate([x[:4], -x[4:]]))


@pytest.mark.parametrize("left,right", [(1.0, 0.6), (-0.6, 1.0)])
def test_wheels_turn_as_commanded_under_cenic(left, right):
    """With the compensation the robot's axles reach the commanded speeds' signs and sizes
    under CENIC as under SAP (power x motor_torque_scaling, 10.16 rad/s at power 1; the
    servo, kd 10 N m s/rad against the tyres' turning load, holds them within 0.5%; SAP and
    CENIC agree within 0.2%)."""
    speeds = {}
    for name, overrides in (("sap", (SAP_SCENE,)), ("cenic", (CENIC_SCENE,))):
        sim = make_sim(*overrides)
        bot = sim.robot()
        bot.set_power(left, right)
        sim.advance(1.5)
        speeds[name] = bot.axle_speeds()
    scaling = make_sim().scenario.robots["corobot"].drive.motor_torque_scaling
    for wheel, speed in speeds["cenic"].items():
        power = left if wheel.endswith("left") else right
        assert speed == pytest.approx(power * scaling, rel=5e-3), (wheel, speed)
        assert speed == pytest.approx(speeds["sap"][wheel], rel=2e-3)
    names = make_sim(CENIC_SCENE).station.diagram.GetSystems()
    assert "corobot.servo_sign" in [s.get_name() for s in names]
    assert "corobot.servo_sign" not in [s.get_name() for s in
                                        make_sim(SAP_SCENE).station.diagram.GetSystems()]
