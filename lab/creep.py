"""A robot at rest: how far it creeps and why (`tools/creep.py`; docs/tuning.md, "At rest").

The tyres are Drake's compliant-hydroelastic cylinders. Drake meshes a cylinder as a prism over
a regular polygon of `tyre_facets` sides (`MakeCylinderVolumeMeshWithMa`: ceil(2 pi R / the
resolution hint), 76 at the shipped 5 mm), so the pressure under a wheel at rest depends a
little on its angle: over each facet there are angles where the contact's moment about the axle
is zero and stable, others where it is zero and unstable, and between them a moment of up to
~3e-4 N m (0.1% of the motor's effort limit) that rolls the wheel towards the stable angle.
The wheel servo has kp = 0: it only damps, so it slows that roll (to at most ~2 um/s at 10
N m s/rad) but never stops it, and the robot rolls with its wheels (no slip: the chassis moves
the effective radius x the wheel rotation) until the wheels reach their stable angle, up to ~2
mm. The drive's hold (`drive.hold_gain`, `systems.drive.DriveController`) stops it.

`rate_map` measures the roll's rate against the wheels' starting angle over half a facet (the
other half mirrors it); `predict` integrates that rate over time from any start; `rest_run`
measures a resting robot directly. All physics only (camera and IR off), no commands.
"""

import dataclasses as dc
import math

import numpy as np

from corobot_drake.config.scenario import SAP_PLANT
from corobot_drake.model.sdf import WheelContact
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.robots import robot_spec

SETTLE = 1.0
"""s: the robot settles on its tyres (they take its weight in ~0.1 s) before a measurement."""
MAP_SECONDS = 2.0
"""s: each `rate_map` run's measurement (the roll moves the wheel < 0.1 mrad in it)."""


def tyre_facets(contact: WheelContact | None = None) -> int:
    """The sides of the polygon Drake's tyre mesh is a prism over (Drake's rule for a
    compliant cylinder, `make_cylinder_mesh.cc`: ceil(2 pi R / resolution_hint), at least 3)."""
    contact = contact or WheelContact()
    return max(3, math.ceil(2 * math.pi * robot_spec().wheel_radius / contact.resolution_hint))


def facet_angle(contact: WheelContact | None = None) -> float:
    """rad: the wheel angle over which the tyre mesh repeats."""
    return 2 * math.pi / tyre_facets(contact)


@dc.dataclass
class RestRun:
    """A robot left at rest with all four wheels at `start_angle` (rad)."""

    start_angle: float
    hold: bool
    seconds: float
    """s measured, after `SETTLE`."""
    displacement: float
    """m: the chassis origin's planar displacement over `seconds`."""
    yaw: float
    """rad: the heading's change over `seconds`."""
    wheel_rotation: float
    """rad: the four wheels' mean rotation over `seconds` (forward positive)."""

    @property
    def rate(self) -> float:
        """m/s: the mean creep speed."""
        return self.displacement / self.seconds


def rest_run(start_angle: float = 0.0, seconds: float = 30.0, hold: bool = True,
             scenario=DEFAULT_SCENARIO, overrides=()) -> RestRun:
    """Leaves the robot of `scenario` (its first) at rest, wheels at `start_angle`, with the
    drive's hold on or off (`drive.hold_gain` 0), and measures it over `seconds` after
    `SETTLE`."""
    from corobot_drake.config.scenario import load_scenario
    from corobot_drake.simulation import Simulation, quiet_drake_warnings
    from lab.bench import physics_only_overrides

    quiet_drake_warnings()
    loaded = load_scenario(scenario)
    name = next(iter(loaded.robots))
    angles = ", ".join([repr(float(start_angle))] * 4)
    robot_override = f"robots: {{{name}: {{wheel_angles: [{angles}], commands: []"
    robot_override += "}}" if hold else ", drive: {hold_gain: 0.0}}}"
    sim = Simulation(load_scenario(scenario, overrides=[*physics_only_overrides(name), *overrides,
                                                         robot_override]))
    robot = sim.robot(name)
    plant = sim.station.plant
    joints = sim.station.robots[name].wheel_joints

    def state():
        pose = robot.pose()
        context = plant.GetMyContextFromRoot(sim.context)
        return pose.x, pose.y, pose.yaw, np.mean([j.get_angle(context) for j in joints])

    sim.advance_to(SETTLE)
    x0, y0, yaw0, q0 = state()
    sim.advance_to(SETTLE + seconds)
    x1, y1, yaw1, q1 = state()
    return RestRun(float(start_angle), hold, seconds, math.hypot(x1 - x0, y1 - y0),
                   math.remainder(yaw1 - yaw0, 2 * math.pi), q1 - q0)


def map_angles(points: int, contact: WheelContact | None = None) -> np.ndarray:
    """`points` wheel angles (rad) from 0 to half a facet, both ends included."""
    return np.linspace(0.0, 0.5 * facet_angle(contact), points)


def rate_map(points: int = 13, progress=None, **kwargs) -> tuple[np.ndarray, np.ndarray]:
    """(angles rad, wheel rates rad/s): the unheld roll's rate from each of `map_angles`,
    each over `MAP_SECONDS`. `progress(angle)` after each."""
    angles = map_angles(points)
    rates = []
    for angle in angles:
        run = rest_run(angle, MAP_SECONDS, hold=False, **kwargs)
        rates.append(run.wheel_rotation / run.seconds)
        if progress is not None:
            progress(angle)
    return angles, np.array(rates)


def _rate_at(angles: np.ndarray, rates: np.ndarray, facet: float):
    """The rate (rad/s) at any wheel angle: the map, mirrored (odd about half a facet: the
    measured map is, within 1%) and repeated every facet."""
    full_angles = np.concatenate([angles, facet - angles[::-1][1:]])
    full_rates = np.concatenate([rates, -rates[::-1][1:]])
    return lambda q: np.interp(np.mod(q, facet), full_angles, full_rates)


def stable_angles(angles: np.ndarray, rates: np.ndarray) -> list[float]:
    """Where the roll stops and stays (rad): the map's falling zero crossings, interpolated."""
    out = []
    for a0, a1, r0, r1 in zip(angles[:-1], angles[1:], rates[:-1], rates[1:], strict=True):
        if r0 > 0 >= r1:
            out.append(float(a0 + (a1 - a0) * r0 / (r0 - r1)))
    return out


def predict(angles: np.ndarray, rates: np.ndarray, start: float, seconds: float,
            step: float = 1.0) -> float:
    """rad: the wheel rotation after `seconds` at rest from `start`, integrating the mapped
    rate (RK4 at `step` s; the rate changes over hundreds of seconds)."""
    rate = _rate_at(angles, rates, 2 * angles[-1])
    q = float(start)
    for _ in range(math.ceil(seconds / step)):
        k1 = rate(q)
        k2 = rate(q + 0.5 * step * k1)
        k3 = rate(q + 0.5 * step * k2)
        k4 = rate(q + step * k3)
        q += step * (k1 + 2 * k2 + 2 * k3 + k4) / 6
    return q - start


def worst_prediction(angles: np.ndarray, rates: np.ndarray, seconds: float,
                     starts: int = 200) -> tuple[float, float]:
    """(start angle rad, rotation rad): the start over a facet whose predicted rotation in
    `seconds` is largest."""
    facet = 2 * angles[-1]
    candidates = np.linspace(0.0, facet, starts, endpoint=False)
    rotations = [abs(predict(angles, rates, s, seconds, step=5.0)) for s in candidates]
    best = int(np.argmax(rotations))
    return float(candidates[best]), float(rotations[best])


SAP = SAP_PLANT % 0.01
"""SAP's discrete plant at 10 ms (`scenario.SAP_PLANT`)."""
ISOLATION = (
    ("shipped (CENIC, 10 ms, hydroelastic, servo damping 10 N m s/rad)", ()),
    ("servo damping 1 N m s/rad", ("robots: {{robot}: {contact: {servo_damping: 1}}}",)),
    ("servo damping 100 N m s/rad",
     ("robots: {{robot}: {contact: {servo_damping: 100}}}",)),
    ("servo damping 1000 N m s/rad",
     ("robots: {{robot}: {contact: {servo_damping: 1000}}}",)),
    ("CENIC step 1 ms", ("simulator_config: {max_step_size: 0.001}",)),
    ("CENIC step 5 ms", ("simulator_config: {max_step_size: 0.005}",)),
    ("SAP (lagged, 10 ms)", (SAP,)),
    ("SAP, approximation similar",
     (SAP, "plant_config: {discrete_contact_approximation: similar}")),
    ("SAP, approximation sap", (SAP, "plant_config: {discrete_contact_approximation: sap}")),
    ("SAP, stiction tolerance 1e-6 m/s (Drake's default 1e-4)",
     (SAP, "plant_config: {stiction_tolerance: 1.0e-6}")),
    ("SAP, stiction tolerance 1e-2 m/s", (SAP, "plant_config: {stiction_tolerance: 1.0e-2}")),
    ("Hunt-Crossley dissipation 0.5 s/m", ("robots: {{robot}: {contact: "
     "{hunt_crossley_dissipation: 0.5}}}",)),
    ("Hunt-Crossley dissipation 50 s/m", ("robots: {{robot}: {contact: "
     "{hunt_crossley_dissipation: 50}}}",)),
    ("tyre mesh 2.5 mm (152 facets)", ("robots: {{robot}: {contact: "
     "{resolution_hint: 0.0025}}}",)),
    ("point contact (an exact cylinder, no mesh)", ("plant_config: {contact_model: point}",)),
)
"""(change, override texts, `{robot}` standing for the robot's name): one change each from
the shipped scenario (SAP's own settings under SAP)."""
ISOLATION_SECONDS = 5.0


def isolate(progress=None, scenario=DEFAULT_SCENARIO) -> list[tuple[str, float, float]]:
    """(change, start angle rad, unheld creep rate m/s) per `ISOLATION` row: the wheels start
    a quarter of their own mesh's facet past a facet's edge (near the fastest roll)."""
    from corobot_drake.config.scenario import load_scenario

    name = next(iter(load_scenario(scenario).robots))
    rows = []
    for label, templates in ISOLATION:
        overrides = [t.replace("{robot}", name) for t in templates]
        contact = next(iter(load_scenario(scenario, overrides=overrides).robots.values())).contact
        start = 0.25 * facet_angle(contact)
        run = rest_run(start, ISOLATION_SECONDS, hold=False, scenario=scenario,
                       overrides=overrides)
        rows.append((label, start, run.rate))
        if progress is not None:
            progress(label)
    return rows
