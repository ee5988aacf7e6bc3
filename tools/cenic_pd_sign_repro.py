"""Drake's CENIC integrator turns a PD servo's desired velocity around: a minimal reproduction.

Standalone (pydrake only), for an upstream report. One body on a revolute joint, no gravity,
no contact, 1 kg m^2 about the axle; its actuator has PD gains kp = 0, kd = 1 N m s/rad and the
plant's desired-state input asks for v_d = +1 rad/s from rest. The same model steps 10 ms at a
time with a discrete plant (SAP) and with a continuous plant under CENIC
(`SimulatorConfig(integration_scheme="cenic", use_error_control=False)`). The implicit PD step
gives v = h kd v_d / (I + h kd) = +0.0099 rad/s after one step, and v -> +1 rad/s after a few
seconds; CENIC gives the same magnitudes with the sign flipped.

Cause (Drake 1.51.1 and 1.58.0): multibody/contact_solvers/icf/icf_external_systems_linearizer.cc
writes the PD torque -Kp (q - qd) - Kd (v - vd) into its linearization as
`bu += -Kp * (q0 - qd) - Kd * vd`, where the derivation in the comment above it ends with
`(-Kp (q0 - qd) + Kd vd)`: the Kd vd term's sign.

    python tools/cenic_pd_sign_repro.py        # exit status 1 while the defect is present
"""

import argparse
import sys
from importlib.metadata import version

import numpy as np
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.multibody.tree import PdControllerGains, RevoluteJoint, SpatialInertia
from pydrake.systems.analysis import ApplySimulatorConfig, Simulator, SimulatorConfig
from pydrake.systems.framework import DiagramBuilder

STEP = 0.01
"""s: the discrete plant's time step and CENIC's fixed step."""
KD = 1.0
"""N m s/rad (kp = 0)."""
VD = 1.0
"""rad/s: the desired velocity."""


def joint_speed(continuous: bool, seconds: float) -> float:
    """rad/s: the joint's speed after `seconds`, CENIC (continuous) or SAP (discrete)."""
    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlant(MultibodyPlantConfig(
        time_step=0.0 if continuous else STEP, discrete_contact_approximation="sap"), builder)
    plant.mutable_gravity_field().set_gravity_vector([0.0, 0.0, 0.0])
    # A solid cylinder of 1 kg, radius sqrt(2) m: 1 kg m^2 about its axis (z).
    body = plant.AddRigidBody("body", SpatialInertia.SolidCylinderWithMass(
        1.0, np.sqrt(2.0), 0.1, [0.0, 0.0, 1.0]))
    joint = plant.AddJoint(RevoluteJoint("joint", plant.world_frame(), body.body_frame(),
                                         [0.0, 0.0, 1.0]))
    plant.AddJointActuator("actuator", joint).set_controller_gains(
        PdControllerGains(p=0.0, d=KD))
    plant.Finalize()
    simulator = Simulator(builder.Build())
    if continuous:
        ApplySimulatorConfig(SimulatorConfig(integration_scheme="cenic", max_step_size=STEP,
                                             use_error_control=False), simulator)
    plant_context = plant.GetMyMutableContextFromRoot(simulator.get_mutable_context())
    plant.get_desired_state_input_port(body.model_instance()).FixValue(
        plant_context, [0.0, VD])  # [qd, vd]
    simulator.AdvanceTo(seconds)
    return float(joint.get_angular_rate(plant_context))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.parse_args()
    print(f"drake {version('drake')}; kp 0, kd {KD:g} N m s/rad, desired velocity "
          f"{VD:+g} rad/s, 1 kg m^2, step {STEP:g} s")
    expected = STEP * KD * VD / (1.0 + STEP * KD)
    print(f"implicit PD, one step: {expected:+.6f} rad/s")
    for label, continuous in (("SAP (discrete plant)", False), ("CENIC (continuous plant)", True)):
        print(f"{label:26s} after one step {joint_speed(continuous, STEP):+.6f} rad/s, "
              f"after 5 s {joint_speed(continuous, 5.0):+.6f} rad/s")
    if joint_speed(True, STEP) < 0.0:
        print("defect present: CENIC drives the joint towards -vd")
        return 1
    print("no defect: CENIC drives the joint towards +vd")
    return 0


if __name__ == "__main__":
    sys.exit(main())
