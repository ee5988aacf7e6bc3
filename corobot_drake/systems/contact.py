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

A discrete plant's contact results are the forces its solver applied over the last step. A
continuous plant's (CENIC's) are its compliant law evaluated at the current state, not what the
integrator applied (CENIC's solve is not exposed), and while driving they read low (a third low
at full speed). There the loads are the robot's momentum balance over the last physics step:
the vertical contact force on the whole robot is m (g + a_z) of its centre of mass, from the
chassis' velocity change since the last step before now (`add_chassis_velocities`), shared
among the wheels (and whatever else of the robot touches something) as the law shares it at
the state.
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.common.value import AbstractValue, Value
from pydrake.math import RigidTransform
from pydrake.multibody.math import SpatialVelocity
from pydrake.multibody.plant import ContactResults
from pydrake.systems.framework import LeafSystem, ValueProducer
from pydrake.systems.primitives import MatrixGain, ZeroOrderHold

from corobot_drake.robots import corobot

SLIP_SPEED_FLOOR = 0.01
"""m/s: the least denominator of the slip ratio and angle. Below 1 cm/s (the slowest a
completing command drives, `motion` creep speed; 1.6% of top speed) neither speed says much
about grip; with the floor a robot at rest, creeping by ~1e-5 m/s, reads ~0 (not NaN, nor its
noise blown up to +-100%)."""


@dc.dataclass(frozen=True)
class RobotMomentum:
    """What a robot's momentum balance on a continuous plant needs (`of_robot`)."""

    mass: float
    """kg: all the robot's bodies."""
    com_in_chassis: tuple[float, float, float]
    """m: the robot's centre of mass in its chassis frame C (the wheels turn about axes
    through their own centres of mass, so it is fixed in C)."""
    gravity: float
    """m/s^2: the plant's gravity, downwards."""
    chassis: int
    """BodyIndex of the chassis."""
    bodies: frozenset[int]
    """BodyIndex of each of the robot's bodies."""
    geometries: frozenset
    """GeometryId of each collision geometry of the robot's bodies."""
    step: float
    """s: the physics step (`add_chassis_velocities` holds the chassis' velocity at each)."""

    @classmethod
    def of_robot(cls, plant, model_instance, chassis, step: float) -> "RobotMomentum":
        """The robot `model_instance` (chassis body `chassis`) of the finalized `plant`."""
        context = plant.CreateDefaultContext()
        plant.SetFreeBodyPose(context, chassis, RigidTransform())
        bodies = [plant.get_body(i) for i in plant.GetBodyIndices(model_instance)]
        return cls(mass=float(plant.CalcTotalMass(context, [model_instance])),
                   com_in_chassis=tuple(float(x) for x in plant.CalcCenterOfMassPositionInWorld(
                       context, [model_instance])),
                   gravity=float(-plant.gravity_field().gravity_vector()[2]),
                   chassis=int(chassis.index()),
                   bodies=frozenset(int(b.index()) for b in bodies),
                   geometries=frozenset(g for b in bodies
                                        for g in plant.GetCollisionGeometriesForBody(b)),
                   step=step)

    def last_step(self, t: float) -> float:
        """s: the last physics step's time before `t` (the grid k `step` from 0, where Drake
        puts a periodic event's times; `t` on it within a millionth of a step is on it)."""
        return (math.ceil(t / self.step - 1e-6) - 1) * self.step

    def vertical_force(self, R_WC: np.ndarray, velocity, held, seconds: float) -> float:
        """N: the vertical (world +z) force on the robot besides gravity, m (g + a_z) of its
        centre of mass over the last `seconds`, from the chassis' rotation R_WC and its
        `velocity` now and `held` then ([angular; of its origin], world)."""
        # Plain floats, z only: numpy's per-call cost on 3-vectors is 20x the arithmetic.
        wx, wy, wz, _, _, vz = (float(x) for x in velocity)
        hx, hy, _, _, _, hz = (float(x) for x in held)
        ax, ay, az = (wx - hx) / seconds, (wy - hy) / seconds, (vz - hz) / seconds
        c = self.com_in_chassis
        rx, ry, rz = (float(R_WC[i][0]) * c[0] + float(R_WC[i][1]) * c[1]
                      + float(R_WC[i][2]) * c[2] for i in range(3))
        ux, uy = wy * rz - wz * ry, wz * rx - wx * rz  # w x r
        a_com_z = az + (ax * ry - ay * rx) + (wx * uy - wy * ux)  # a + alpha x r + w x (w x r)
        return self.mass * (a_com_z + self.gravity)


def momentum_shares(law: list[float], law_total: float, total: float) -> list[float]:
    """The wheels' loads, N: `total` (the robot's vertical contact force from its momentum)
    shared as the contact law shares `law_total` among the wheels (`law`); the law's own
    loads where it carries nothing (no contact: nothing to share)."""
    if law_total <= LAW_FLOOR:
        return law
    return [x * (total / law_total) for x in law]


LAW_FLOOR = 1e-9
"""N: a contact law's vertical force on the robot at or below which nothing touches."""


class WheelContacts(LeafSystem):
    """Per-wheel load and slip of one robot (module docstring).

    .. pydrake_system::

        name: WheelContacts
        input_ports:
        - contact_results
        - chassis_pose
        - body_spatial_velocities
        - wheel_state
        - chassis_velocity (continuous plant)
        - held_chassis_velocity (continuous plant)
        output_ports:
        - wheel_loads
        - wheel_slip_ratio
        - wheel_slip_angle

    Inputs: `contact_results` (abstract ContactResults of the plant), `chassis_pose` (abstract
    RigidTransform X_WC, from `odometry.ChassisPoses`), `body_spatial_velocities` (the
    plant's, indexed by BodyIndex), `wheel_state` [q, v] of the n axles (rad, rad/s); with
    `momentum` (a continuous plant), `chassis_velocity` (6: the chassis' angular velocity,
    rad/s, and its origin's, m/s, world) now and `held_chassis_velocity` at the last physics
    step before now.
    Outputs (n each, the robot's wheel order, `RobotSpec.wheels`; the Corobot's front left,
    front right, rear left, rear right): `wheel_loads` (N), `wheel_slip_ratio` (longitudinal,
    dimensionless, + traction),
    `wheel_slip_angle` (deg, + moving to the left of the heading). Only `wheel_loads` reads
    the contact results; the slip's two ports share one computation (a cache entry). No state
    on a discrete plant: the outputs are functions of the plant's latest step. With
    `momentum`, one number set when the Simulator initializes: the time after which the held
    velocity is a step's (until then, the contact law's loads).
    """

    def __init__(self, plant, wheels, momentum: RobotMomentum | None = None,
                 wheel_radius: float = corobot.wheels("radius")):
        super().__init__()
        self._wheels = [int(w.index()) for w in wheels]
        n = self._n = len(wheels)
        self._radius = wheel_radius
        self._wheel_of_body = {i: k for k, i in enumerate(self._wheels)}
        self._wheel_of_geometry = {g: k for k, w in enumerate(wheels)
                                   for g in plant.GetCollisionGeometriesForBody(w)}
        self._momentum = momentum
        self._contacts = self.DeclareAbstractInputPort("contact_results",
                                                       AbstractValue.Make(ContactResults()))
        self._pose = self.DeclareAbstractInputPort("chassis_pose",
                                                   AbstractValue.Make(RigidTransform()))
        self._velocities = self.DeclareAbstractInputPort(
            "body_spatial_velocities", AbstractValue.Make([SpatialVelocity()]))
        self._wheel_state = self.DeclareVectorInputPort("wheel_state", 2 * n)
        loads_depend_on = {self.input_port_ticket(self._contacts.get_index())}
        if momentum is not None:
            self._velocity = self.DeclareVectorInputPort("chassis_velocity", 6)
            self._held = self.DeclareVectorInputPort("held_chassis_velocity", 6)
            self._momentum_from = self.DeclareDiscreteState(1)
            self.DeclareInitializationDiscreteUpdateEvent(self._start_momentum)
            loads_depend_on = {self.all_input_ports_ticket(), self.xd_ticket()}
        self.DeclareVectorOutputPort("wheel_loads", n, self._calc_loads, loads_depend_on)
        self._slip = self.DeclareCacheEntry(
            "slip", ValueProducer(allocate=lambda: Value([0.0] * (2 * n)),
                                  calc=lambda c, v: v.set_value(self._calc_slip(c))),
            {self.input_port_ticket(port.get_index())
             for port in (self._pose, self._velocities, self._wheel_state)})
        self.DeclareVectorOutputPort("wheel_slip_ratio", n, lambda c, o: o.SetFromVector(
            self._slip.Eval(c)[:n]), {self._slip.ticket()})
        self.DeclareVectorOutputPort("wheel_slip_angle", n, lambda c, o: o.SetFromVector(
            self._slip.Eval(c)[n:]), {self._slip.ticket()})

    def _start_momentum(self, context, discrete_state):
        # The hold samples at the grid's times: the first at or after the start.
        first = self._momentum.last_step(context.get_time()) + self._momentum.step
        discrete_state.set_value(self._momentum_from, [first])

    def loads(self, context) -> list[float]:
        """Each wheel's load: the vertical (world +z) component of the total contact force on
        it, N (module docstring)."""
        law, law_total = self._law_loads(context)
        momentum = self._momentum
        t = context.get_time()
        if momentum is None or t <= context.get_discrete_state(
                self._momentum_from).GetAtIndex(0) + 1e-6 * momentum.step:
            return law
        total = momentum.vertical_force(self._pose.Eval(context).rotation().matrix(),
                                        self._velocity.Eval(context), self._held.Eval(context),
                                        t - momentum.last_step(t))
        return momentum_shares(law, law_total, total)

    def _law_loads(self, context) -> tuple[list[float], float]:
        """(each wheel's vertical contact force, the robot's (every body's; only with
        `momentum`)), N, from the contact results. Plain floats: a vector sum per contact in
        numpy costs more than the sum."""
        results = self._contacts.Eval(context)
        robot_geometries = self._momentum.geometries if self._momentum else frozenset()
        robot_bodies = self._momentum.bodies if self._momentum else frozenset()
        loads, total = [0.0] * self._n, 0.0
        for i in range(results.num_hydroelastic_contacts()):
            info = results.hydroelastic_contact_info(i)
            surface = info.contact_surface()
            force_z = float(info.F_Ac_W().translational()[2])  # on the body of geometry M
            for geometry, sign in ((surface.id_M(), 1.0), (surface.id_N(), -1.0)):
                k = self._wheel_of_geometry.get(geometry)
                if k is not None:
                    loads[k] += sign * force_z
                if geometry in robot_geometries:
                    total += sign * force_z
        for i in range(results.num_point_pair_contacts()):
            info = results.point_pair_contact_info(i)
            force_z = float(info.contact_force()[2])  # on body B
            for body, sign in ((info.bodyA_index(), -1.0), (info.bodyB_index(), 1.0)):
                k = self._wheel_of_body.get(int(body))
                if k is not None:
                    loads[k] += sign * force_z
                if int(body) in robot_bodies:
                    total += sign * force_z
        return loads, total

    def _calc_loads(self, context, output):
        output.SetFromVector(np.array(self.loads(context)))

    def _calc_slip(self, context) -> list[float]:
        """[slip ratios (n), slip angles (n), deg] from the wheels' speeds. Plain floats: on
        four wheels numpy's per-call overhead costs more than the sums, every step."""
        R = self._pose.Eval(context).rotation().matrix().tolist()
        (fx, lx), (fy, ly), (fz, lz) = (row[:2] for row in R)  # heading and left, world
        velocities = self._velocities.Eval(context)
        axles = self._wheel_state.Eval(context)[self._n:].tolist()
        ratios, angles = [], []
        for i, omega in zip(self._wheels, axles, strict=True):
            vx, vy, vz = velocities[i].translational().tolist()
            ground, lateral = fx * vx + fy * vy + fz * vz, lx * vx + ly * vy + lz * vz  # m/s
            ratios.append(slip_ratio(omega * self._radius, ground))
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


def held_velocity_name(robot: str) -> str:
    """The name of the robot's hold of its chassis velocity (`add_chassis_velocities`)."""
    return f"{robot}.held_chassis_velocity"


def add_chassis_velocities(builder, name: str, plant, chassis, step: float):
    """Adds `<name>.chassis_velocity` (the chassis' velocities, angular and of its origin,
    world, picked out of the plant's state) and `<name>.held_chassis_velocity` (them held at
    each physics step `step`, on the plant's step grid): Drake's MatrixGain and ZeroOrderHold,
    C++. Returns their output ports."""
    pick = np.zeros((6, plant.num_multibody_states()))
    start = plant.num_positions() + chassis.floating_velocities_start_in_v()
    pick[:, start:start + 6] = np.eye(6)
    velocity = builder.AddNamedSystem(f"{name}.chassis_velocity", MatrixGain(pick))
    builder.Connect(plant.get_state_output_port(), velocity.get_input_port())
    held = builder.AddNamedSystem(held_velocity_name(name), ZeroOrderHold(step, 6))
    builder.Connect(velocity.get_output_port(), held.get_input_port())
    return velocity.get_output_port(), held.get_output_port()


def add_wheel_contacts(builder, name: str, plant, wheels, chassis_pose_port, wheel_state_port,
                       chassis, continuous_step: float = 0.0,
                       wheel_radius: float = corobot.wheels("radius")):
    """Adds `<name>.wheel_contacts` fed by the plant, `chassis_pose_port` and
    `wheel_state_port`; on a continuous plant (its step `continuous_step` > 0,
    `scenario.continuous_step`), its loads from the robot's momentum balance (its `chassis`
    body's model instance: `add_chassis_velocities`). Returns it."""
    momentum = (RobotMomentum.of_robot(plant, chassis.model_instance(), chassis,
                                       continuous_step) if continuous_step > 0 else None)
    system = builder.AddNamedSystem(f"{name}.wheel_contacts",
                                    WheelContacts(plant, wheels, momentum, wheel_radius))
    for port_name, port in (("contact_results", plant.get_contact_results_output_port()),
                            ("chassis_pose", chassis_pose_port),
                            ("body_spatial_velocities",
                             plant.get_body_spatial_velocities_output_port()),
                            ("wheel_state", wheel_state_port)):
        builder.Connect(port, system.GetInputPort(port_name))
    if momentum is not None:
        velocity, held = add_chassis_velocities(builder, name, plant, chassis,
                                                continuous_step)
        builder.Connect(velocity, system.GetInputPort("chassis_velocity"))
        builder.Connect(held, system.GetInputPort("held_chassis_velocity"))
    return system
