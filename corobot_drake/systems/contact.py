"""Contact telemetry: each wheel's load and slip, from the plant's contact results and
velocities.

- load: the vertical (world +z) component of the total contact force on the wheel, N: what
  the ground carries on that wheel (at rest the four sum to the robot's weight);
- slip ratio (longitudinal, dimensionless): (rim speed omega R - ground speed) / max(|rim|,
  |ground|, `SLIP_SPEED_FLOOR`), with the ground speed the wheel centre's speed along the
  chassis heading and R the nominal radius, signed so that driving forwards and backwards read
  alike (times the sign of the faster of the two speeds): positive while a wheel turns faster
  than it travels (traction: +1 spinning on the spot), negative while it is dragged faster
  than it turns (braking, skidding: -1 locked), beyond +-1 (up to +-2) only while it turns
  against its travel; free rolling on the compliant tyre reads about +0.8% (it rolls on a
  smaller effective radius, `tools/calibrate_odometry.py`);
- slip angle (lateral, deg): atan2(lateral speed, max(|ground speed along the heading|,
  `SLIP_SPEED_FLOOR`)), the lateral speed being the wheel centre's speed across the heading
  (+ to the left): the angle between where the wheel points and where it goes; a skid-steer
  turn scrubs every wheel sideways (a spin in place: atan(half wheelbase / half track) = 39.5
  deg, front wheels + one way, rear - the other).

Hydroelastic contacts (the tyres' compliant patches) and point contacts (the fallback, e.g. a
rigid body against a tyre) both count for the loads. The slip is kinematic: it needs the body
velocities only, not the contact results.
"""

import math

import numpy as np
from pydrake.common.value import AbstractValue, Value
from pydrake.math import RigidTransform
from pydrake.multibody.math import SpatialVelocity
from pydrake.multibody.plant import ContactResults
from pydrake.systems.framework import LeafSystem, ValueProducer

from corobot_drake.model import dimensions as dim

SLIP_SPEED_FLOOR = 0.01
"""m/s: the least denominator of the slip ratio and angle. Below 1 cm/s (the slowest a
completing command drives, `motion` creep speed; 1.6% of top speed) neither speed says much
about grip; with the floor a robot at rest, creeping by ~1e-5 m/s, reads ~0 (not NaN, nor its
noise blown up to +-100%)."""


class WheelContacts(LeafSystem):
    """Per-wheel load and slip of one robot (module docstring).

    .. pydrake_system::

        name: WheelContacts
        input_ports:
        - contact_results
        - chassis_pose
        - body_spatial_velocities
        - wheel_state
        output_ports:
        - wheel_loads
        - wheel_slip_ratio
        - wheel_slip_angle

    Inputs: `contact_results` (abstract ContactResults of the plant), `chassis_pose` (abstract
    RigidTransform X_WC, from `odometry.ChassisPoses`), `body_spatial_velocities` (the
    plant's, indexed by BodyIndex), `wheel_state` [q, v] of the four axles (rad, rad/s).
    Outputs (4 each, `dimensions.WHEEL_NAMES` order: front left, front right, rear left, rear
    right): `wheel_loads` (N), `wheel_slip_ratio` (longitudinal, dimensionless, + traction),
    `wheel_slip_angle` (deg, + moving to the left of the heading). No state: the outputs are
    functions of the plant's latest step. Only `wheel_loads` reads the contact results; the
    slip's two ports share one computation (a cache entry).
    """

    def __init__(self, plant, wheels):
        super().__init__()
        self._wheels = [int(w.index()) for w in wheels]
        self._wheel_of_body = {i: k for k, i in enumerate(self._wheels)}
        self._wheel_of_geometry = {g: k for k, w in enumerate(wheels)
                                   for g in plant.GetCollisionGeometriesForBody(w)}
        self._contacts = self.DeclareAbstractInputPort("contact_results",
                                                       AbstractValue.Make(ContactResults()))
        self._pose = self.DeclareAbstractInputPort("chassis_pose",
                                                   AbstractValue.Make(RigidTransform()))
        self._velocities = self.DeclareAbstractInputPort(
            "body_spatial_velocities", AbstractValue.Make([SpatialVelocity()]))
        self._wheel_state = self.DeclareVectorInputPort("wheel_state", 8)
        self.DeclareVectorOutputPort("wheel_loads", 4, self._calc_loads,
                                     {self.input_port_ticket(self._contacts.get_index())})
        self._slip = self.DeclareCacheEntry(
            "slip", ValueProducer(allocate=lambda: Value([0.0] * 8),
                                  calc=lambda c, v: v.set_value(self._calc_slip(c))),
            {self.input_port_ticket(port.get_index())
             for port in (self._pose, self._velocities, self._wheel_state)})
        self.DeclareVectorOutputPort("wheel_slip_ratio", 4, lambda c, o: o.SetFromVector(
            self._slip.Eval(c)[:4]), {self._slip.ticket()})
        self.DeclareVectorOutputPort("wheel_slip_angle", 4, lambda c, o: o.SetFromVector(
            self._slip.Eval(c)[4:]), {self._slip.ticket()})

    def loads(self, context) -> list[float]:
        """Each wheel's load: the vertical (world +z) component of the total contact force on
        it, N. Plain floats: a vector sum per contact in numpy costs more than the sum."""
        results = self._contacts.Eval(context)
        loads = [0.0] * 4
        for i in range(results.num_hydroelastic_contacts()):
            info = results.hydroelastic_contact_info(i)
            surface = info.contact_surface()
            force_z = float(info.F_Ac_W().translational()[2])  # on the body of geometry M
            for geometry, sign in ((surface.id_M(), 1.0), (surface.id_N(), -1.0)):
                k = self._wheel_of_geometry.get(geometry)
                if k is not None:
                    loads[k] += sign * force_z
        for i in range(results.num_point_pair_contacts()):
            info = results.point_pair_contact_info(i)
            force_z = float(info.contact_force()[2])  # on body B
            for body, sign in ((info.bodyA_index(), -1.0), (info.bodyB_index(), 1.0)):
                k = self._wheel_of_body.get(int(body))
                if k is not None:
                    loads[k] += sign * force_z
        return loads

    def _calc_loads(self, context, output):
        output.SetFromVector(np.array(self.loads(context)))

    def _calc_slip(self, context) -> list[float]:
        """[slip ratios (4), slip angles (4), deg] from the wheels' speeds. Plain floats: on
        four wheels numpy's per-call overhead costs more than the sums, every step."""
        R = self._pose.Eval(context).rotation().matrix().tolist()
        (fx, lx), (fy, ly), (fz, lz) = (row[:2] for row in R)  # heading and left, world
        velocities = self._velocities.Eval(context)
        axles = self._wheel_state.Eval(context)[4:].tolist()
        ratios, angles = [], []
        for i, omega in zip(self._wheels, axles, strict=True):
            vx, vy, vz = velocities[i].translational().tolist()
            ground, lateral = fx * vx + fy * vy + fz * vz, lx * vx + ly * vy + lz * vz  # m/s
            ratios.append(slip_ratio(omega * dim.WHEEL_RADIUS, ground))
            angles.append(slip_angle_deg(ground, lateral))
        return ratios + angles


def slip_ratio(rim: float, ground: float) -> float:
    """Longitudinal slip ratio +-(rim - ground) / max(|rim|, |ground|, floor), signed by the
    faster speed (module docstring): + traction, - braking, either way; speeds in m/s."""
    faster = rim if abs(rim) >= abs(ground) else ground
    return math.copysign(1.0, faster) * (rim - ground) / max(abs(faster), SLIP_SPEED_FLOOR)


def slip_angle_deg(ground: float, lateral: float) -> float:
    """Slip angle, deg in (-90, 90): atan2(lateral, max(|ground along the heading|, floor))."""
    return math.degrees(math.atan2(lateral, max(abs(ground), SLIP_SPEED_FLOOR)))


def add_wheel_contacts(builder, name: str, plant, wheels, chassis_pose_port, wheel_state_port):
    """Adds `<name>.wheel_contacts` fed by the plant, `chassis_pose_port` and
    `wheel_state_port`; returns it."""
    system = builder.AddNamedSystem(f"{name}.wheel_contacts", WheelContacts(plant, wheels))
    for port_name, port in (("contact_results", plant.get_contact_results_output_port()),
                            ("chassis_pose", chassis_pose_port),
                            ("body_spatial_velocities",
                             plant.get_body_spatial_velocities_output_port()),
                            ("wheel_state", wheel_state_port)):
        builder.Connect(port, system.GetInputPort(port_name))
    return system
