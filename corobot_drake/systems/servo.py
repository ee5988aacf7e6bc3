"""The wheels' velocity servo under Drake's CENIC integrator: a probe for a sign defect.

The wheels are driven by Drake's implicit PD on the plant's desired-state input (kp = 0, kd =
`WheelContact.servo_damping`). Under CENIC (a continuous plant, `time_step: 0`) Drake 1.51 and
1.58 linearize that PD with the desired velocity's term negated: in
`multibody/contact_solvers/icf/icf_external_systems_linearizer.cc` the PD torque
-Kp (q - qd) - Kd (v - vd) is written into `bu` as `-Kp (q0 - qd) - Kd vd`, where its own
derivation in the comment above it ends in `+ Kd vd`. A servo asked for +vd turns at -vd.

`servo_velocity_sign` measures it, once per process and integrator settings, on a one-joint
plant: one CENIC step of a wheel at rest asked to turn forward. It returns -1 while the defect
is present and +1 once Drake is fixed (or for any other integrator), and the station feeds the
servo `sign * vd` (`add_servo_sign`): the wheels turn as commanded either way, and nothing is
compensated on a Drake that does not need it. `tools/cenic_pd_sign_repro.py` is the same probe
as a standalone script for an upstream report.
"""

import functools

import numpy as np
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.multibody.tree import PdControllerGains, RevoluteJoint, SpatialInertia
from pydrake.systems.analysis import ApplySimulatorConfig, Simulator, SimulatorConfig
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import MatrixGain

from corobot_drake.config.scenario import CENIC

PROBE_SPEED = 1.0
"""rad/s: the probe's desired joint speed."""
PROBE_DAMPING = 1.0
"""N m s/rad: the probe's servo gain kd (kp = 0)."""


def uses_cenic(simulator_config: SimulatorConfig) -> bool:
    return simulator_config.integration_scheme == CENIC


def probe_servo_speed(simulator_config: SimulatorConfig) -> float:
    """rad/s: the speed after one step (`max_step_size`) of a free-spinning wheel (1 kg m^2
    about its axle, no gravity, no contact) whose servo (kp 0, kd `PROBE_DAMPING`) is asked
    for `PROBE_SPEED` from rest, on a continuous plant with `simulator_config`. A correct
    implicit step gives h kd / (1 + h kd) of `PROBE_SPEED`: positive."""
    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlant(MultibodyPlantConfig(time_step=0.0), builder)
    plant.mutable_gravity_field().set_gravity_vector([0.0, 0.0, 0.0])
    wheel = plant.AddRigidBody("wheel", SpatialInertia.SolidCylinderWithMass(
        1.0, np.sqrt(2.0), 0.1, [0.0, 0.0, 1.0]))  # 1 kg m^2 about its axis
    joint = plant.AddJoint(RevoluteJoint("axle", plant.world_frame(), wheel.body_frame(),
                                         [0.0, 0.0, 1.0]))
    actuator = plant.AddJointActuator("motor", joint)
    actuator.set_controller_gains(PdControllerGains(p=0.0, d=PROBE_DAMPING))
    plant.Finalize()
    diagram = builder.Build()
    simulator = Simulator(diagram)
    ApplySimulatorConfig(simulator_config, simulator)
    context = simulator.get_mutable_context()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    plant.get_desired_state_input_port(wheel.model_instance()).FixValue(
        plant_context, [0.0, PROBE_SPEED])
    simulator.Initialize()
    simulator.AdvanceTo(simulator_config.max_step_size)
    return float(joint.get_angular_rate(plant_context))


@functools.cache
def _sign(scheme: str, max_step_size: float, use_error_control: bool, accuracy: float) -> float:
    config = SimulatorConfig(integration_scheme=scheme, max_step_size=max_step_size,
                             use_error_control=use_error_control, accuracy=accuracy)
    return -1.0 if probe_servo_speed(config) < 0.0 else 1.0


def servo_velocity_sign(simulator_config: SimulatorConfig) -> float:
    """+1, or -1 when the integrator turns a PD servo's desired velocity around (CENIC on
    Drake 1.51-1.58: the module's docstring); probed once per integrator settings."""
    if not uses_cenic(simulator_config):
        return 1.0
    c = simulator_config
    return _sign(c.integration_scheme, c.max_step_size, c.use_error_control, c.accuracy)


def add_servo_sign(builder, name: str, sign: float, size: int):
    """A gain on the desired state [q_d (size/2), v_d (size/2)] that multiplies v_d by
    `sign` (q_d unchanged: the wheels' servo has kp = 0); returns the system."""
    half = size // 2
    gain = np.diag([1.0] * half + [sign] * half)
    return builder.AddNamedSystem(name, MatrixGain(gain))
