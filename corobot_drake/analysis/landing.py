"""Landing errors of DriveDistance and RotateDegrees, both profiles (`tools/landing_errors.py`).

For each profile, distance {0.25, 0.5, 1, 2} m and angle {15, 45, 90, 180} deg at power
{0.2, 0.5, 1}: SetPose the robot to the origin facing +x (the giant box behind it), run the
command, let the robot come to rest (1 s), and measure from the GPS and compass:
distance error = straight-line distance from the start - target (mm), angle error = heading
change - target (deg, wrapped). Also the command's duration (s).
"""

import math
from concurrent.futures import ProcessPoolExecutor

from corobot_drake.analysis.drive_test import fast_overrides
from corobot_drake.config import scenario as sc
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.simulation import Simulation, quiet_drake_warnings

DISTANCES = (0.25, 0.5, 1.0, 2.0)
ANGLES = (15.0, 45.0, 90.0, 180.0)
POWERS = (0.2, 0.5, 1.0)
REST = 1.0
"""s after the command ends before measuring (a seed-profile command ends while coasting)."""


def measure(profile: str) -> dict:
    """{("drive"|"rotate", target, power): (error in mm or deg, duration s, status)}."""
    quiet_drake_warnings()
    sim = Simulation(sc.load_scenario(DEFAULT_SCENARIO, overrides=fast_overrides(profile)))
    robot = sim.robot()
    results = {}
    for kind, targets in (("drive", DISTANCES), ("rotate", ANGLES)):
        for target in targets:
            for power in POWERS:
                robot.set_pose(0.0, 0.0, 0.0).wait()
                x0, y0, _ = robot.position()
                heading0 = robot.heading()
                if kind == "drive":
                    result = robot.drive_distance(target, power)
                else:
                    result = robot.rotate_degrees(target, power)
                sim.advance(REST)
                x, y, _ = robot.position()
                if kind == "drive":
                    error = (math.hypot(x - x0, y - y0) - target) * 1000.0
                else:
                    error = math.degrees(math.remainder(
                        robot.heading() - heading0 - math.radians(target), 2 * math.pi))
                results[(kind, target, power)] = (error, result.end_time - result.start_time,
                                                  result.status)
    return results


def table(all_results: dict) -> str:
    profiles = list(all_results)
    lines = []
    for kind, targets, unit, label in (("drive", DISTANCES, "mm", "distance (m)"),
                                       ("rotate", ANGLES, "deg", "angle (deg)")):
        head = [label, "power"] + [f"{p} error ({unit})" for p in profiles] + [
            f"{p} time (s)" for p in profiles]
        lines.append("| " + " | ".join(head) + " |")
        lines.append("|" + "---|" * len(head))
        for target in targets:
            for power in POWERS:
                cells = [f"{target:g}", f"{power:g}"]
                rows = [all_results[p][(kind, target, power)] for p in profiles]
                fmt = "{:+.2f}" if kind == "drive" else "{:+.3f}"
                cells += [fmt.format(r[0]) + ("" if r[2] == "succeeded" else f" ({r[2]})")
                          for r in rows]
                cells += [f"{r[1]:.2f}" for r in rows]
                lines.append("| " + " | ".join(cells) + " |")
        for p in profiles:
            worst = max(abs(v[0]) for k, v in all_results[p].items() if k[0] == kind)
            lines.append(f"\nLargest |error|, {p}: {worst:.3f} {unit}.")
        lines.append("")
    return "\n".join(lines)


def measure_profiles() -> dict:
    """{profile: `measure(profile)`} for every motion profile, in parallel processes."""
    with ProcessPoolExecutor(max_workers=len(sc.PROFILES)) as pool:
        return dict(zip(sc.PROFILES, pool.map(measure, sc.PROFILES), strict=True))
