"""A shipped robot's figures (`tools/robot_figures.py`), each measured on open ground (the
scenario's world bodies and directives left out, the robot's sensors off) from its scenario:

- top speed: power 1 on both sides for `SECONDS`, the mean speed over the last second (as the
  study's `steady_speed`), against the robot file's top speed (axle speed at power 1 x radius);
- spin rate: power -1 left, +1 right, the mean yaw rate over the last second, at CENIC steps 1, 2, 5
  and 10 ms, against the analytic rates: the wheels' speed difference over the track,
  2 u / track (rolling without slip), and a skid steer's `spec.spin_yaw_per_rim_speed` u
  (every wheel slipping as isotropic friction has it, from each wheel's lever arm: b u /
  (a^2 + b^2) for four wheels at half wheelbase a, half track b; the same as the first for
  a differential drive, a = 0);
- DriveDistance 1 m and RotateDegrees 90 deg at power 0.5 and 1, in both motion profiles: the
  landing error 1 s after the command ends (the robot at rest), as `lab.landing` measures it;
- the physics-only real-time factor (`realtime_factor`): lab.bench's figure of eight, 8 s,
  building excluded (a timing: the machine's load changes it).
"""

from __future__ import annotations

import math
import time

import numpy as np

from corobot_drake.commands import DriveDistance, RotateDegrees, SetPower, Wait
from corobot_drake.config.scenario import CENIC_PLANT, PROFILES, load_scenario
from corobot_drake.resources import SCENARIOS_DIR
from corobot_drake.robots import robot_spec
from corobot_drake.sensors.registry import KINDS
from corobot_drake.simulation import Simulation

SCENARIOS = {"corobot": "corobot.yaml", "burger": "burger.yaml", "pioneer": "pioneer.yaml"}
"""Each shipped robot's scenario (its robot is the scenario's only one)."""
SPIN_STEPS = (0.001, 0.002, 0.005, 0.01)
"""s: the CENIC steps the spin is measured at."""
SECONDS = 3.0
"""s driven before the steady figures' last `WINDOW` s (every robot is steady by 2 s)."""
WINDOW = 1.0
"""s: the steady figures' averaging window (the study's `metrics.WINDOW`)."""
SAMPLE = 0.01
"""s between the poses the steady figures are read from."""
SETTLE = 1.0
"""s at rest after a DriveDistance or RotateDegrees before its landing is measured."""
DISTANCE, DEGREES = 1.0, 90.0
POWERS = (0.5, 1.0)
"""The powers DriveDistance and RotateDegrees are measured at."""
EIGHT = (SetPower(1.0, 0.6), Wait(3.0), SetPower(0.6, 1.0), Wait(3.0), SetPower(-1.0, 1.0))
"""lab.bench's figure of eight."""
RTF_SECONDS = 8.0


def simulation(robot: str, commands=(), step: float | None = None,
               overrides: tuple[str, ...] = ()) -> Simulation:
    """`robot`'s scenario on open ground, its sensors off, running `commands`; at CENIC
    `step` s (None: the scenario's own plant)."""
    plant = [CENIC_PLANT % step] if step else []
    scenario = load_scenario(SCENARIOS_DIR / SCENARIOS[robot], overrides=[*plant, *overrides])
    scenario.world.bodies = {}
    scenario.directives = []
    (config,) = scenario.robots.values()
    config.commands = list(commands)
    for kind in KINDS:
        setattr(config, kind.field, {})
    return Simulation(scenario)


def steady(robot: str, left: float, step: float | None = None) -> tuple[float, float]:
    """(m/s, rad/s): the mean forward speed and yaw rate over the last `WINDOW` s of
    `SECONDS` at power (`left`, 1), from the pose every `SAMPLE` s (as the study's
    steady_speed and steady_yaw_rate: the displacement along the mean heading, the heading
    unwrapped sample to sample)."""
    sim = simulation(robot, [SetPower(left, 1.0)], step)
    r = sim.robot()
    poses = []
    for k in range(round(WINDOW / SAMPLE) + 1):
        sim.advance_to(SECONDS - WINDOW + k * SAMPLE)
        poses.append(r.pose())
    yaw = np.unwrap([p.yaw for p in poses])
    heading = 0.5 * (yaw[0] + yaw[-1])
    dx, dy = poses[-1].x - poses[0].x, poses[-1].y - poses[0].y
    return ((dx * math.cos(heading) + dy * math.sin(heading)) / WINDOW,
            float(yaw[-1] - yaw[0]) / WINDOW)


def spec_and_rim_speed(robot: str):
    """(RobotSpec, m/s of the rims at power 1 as the scenario's drive gives it)."""
    (config,) = load_scenario(SCENARIOS_DIR / SCENARIOS[robot]).robots.values()
    spec = robot_spec(config.robot)
    return spec, config.drive.motor_torque_scaling * spec.wheel_radius


def spin(robot: str) -> dict:
    """The steady spin at each of `SPIN_STEPS`: rad/s and its ratios to both analytic
    rates (rad/s, for rims at +-u)."""
    spec, u = spec_and_rim_speed(robot)
    rolling = 2.0 * u / spec.track
    slipping = u * spec.spin_yaw_per_rim_speed
    out = {}
    for step in SPIN_STEPS:
        rate = abs(steady(robot, -1.0, step)[1])
        out[f"{step:g}"] = {"rad_s": rate, "rolling": rate / rolling,
                            "slipping": rate / slipping}
    return {"rolling_rad_s": rolling, "slipping_rad_s": slipping, "steps": out}


def landing(robot: str, profile: str, command) -> float:
    """The landing error of one `command` in `profile`: mm (DriveDistance) or deg
    (RotateDegrees), measured `SETTLE` s after it ends."""
    sim = simulation(robot, overrides=(
        f"robots: {{{robot}: {{motion: {{profile: {profile}}}}}}}",))
    r = sim.robot()
    start, heading = r.pose(), r.heading()
    if isinstance(command, DriveDistance):
        r.drive_distance(command.distance, command.power)
    else:
        r.rotate_degrees(command.degrees, command.power)
    sim.advance(SETTLE)
    end = r.pose()
    if isinstance(command, DriveDistance):
        return 1000.0 * (math.hypot(end.x - start.x, end.y - start.y) - command.distance)
    turned = r.heading() - heading - math.radians(command.degrees)
    return math.degrees(math.remainder(turned, 2 * math.pi))


def figures(robot: str) -> dict:
    """Every deterministic figure of `robot` (JSON-ready)."""
    return {
        "top_speed_spec": spec_and_rim_speed(robot)[1],
        "top_speed": steady(robot, 1.0)[0],
        "spin": spin(robot),
        "landing": {profile: {f"{power:g}": {
            "drive_mm": landing(robot, profile, DriveDistance(distance=DISTANCE, power=power)),
            "rotate_deg": landing(robot, profile, RotateDegrees(degrees=DEGREES, power=power)),
        } for power in POWERS} for profile in PROFILES},
    }


def realtime_factor(robot: str, seconds: float = RTF_SECONDS) -> float:
    """Simulated seconds per wall second of the figure of eight, physics only, building
    excluded."""
    sim = simulation(robot, EIGHT)
    wall = time.perf_counter()
    sim.advance(seconds)
    return seconds / (time.perf_counter() - wall)


def table(results: dict[str, dict]) -> str:
    """The figures of several robots as one Markdown table, a column per robot."""
    names = list(results)
    rows = [("top speed, power 1 (m/s)", lambda f: f"{f['top_speed']:.4f}"),
            ("top speed, robot file (m/s)", lambda f: f"{f['top_speed_spec']:.4f}"),
            ("top speed / robot file", lambda f: f"{f['top_speed'] / f['top_speed_spec']:.3f}")]
    rows += [(f"spin {float(s) * 1000:g} ms / 2u/track", lambda f, s=s:
              f"{f['spin']['steps'][s]['rolling']:.3f}") for s in (f"{x:g}" for x in SPIN_STEPS)]
    rows += [(f"spin {float(s) * 1000:g} ms / bu/(a^2+b^2)", lambda f, s=s:
              f"{f['spin']['steps'][s]['slipping']:.3f}")
             for s in (f"{x:g}" for x in SPIN_STEPS)]
    for profile in PROFILES:
        for power in (f"{x:g}" for x in POWERS):
            rows += [(f"DriveDistance {DISTANCE:g} m at {power}, {profile} (mm)",
                      lambda f, p=profile, w=power: f"{f['landing'][p][w]['drive_mm']:+.1f}"),
                     (f"RotateDegrees {DEGREES:g} at {power}, {profile} (deg)",
                      lambda f, p=profile, w=power: f"{f['landing'][p][w]['rotate_deg']:+.2f}")]
    lines = ["| figure | " + " | ".join(names) + " |", "|---" * (len(names) + 1) + "|"]
    lines += [f"| {label} | " + " | ".join(cell(results[n]) for n in names) + " |"
              for label, cell in rows]
    return "\n".join(lines)

