"""Renders a scenario to PNG with Drake's VTK renderer, headless (no display needed).

Usage:
    python tools/snapshot.py [--scenario YAML] [--output PNG] [--view chase|overview|robot-camera]
                             [--eye X,Y,Z [--target X,Y,Z]] [--pose X,Y,YAW_DEG]
                             [--drive LEFT,RIGHT] [--time S]
                             [--width W] [--height H] [--visual meshes|boxes] [--override YAML]

The scene is lit by the scenario's sun (a directional light in the world frame) with the sky
colour behind it. `--time` simulates that many seconds first (the scenario's commands, or
`--drive` power), so the wheels, the robot and anything it pushed are where the drive put them.
Views: `chase` (behind and above the robot), `overview` (the robot and the world's bodies from
the side), `robot-camera` (the robot's own camera: SPEC mount, 320x240, 30 deg vertical fov).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from corobot_drake.config.scenario import ScenarioError, load_scenario
from corobot_drake.model import dimensions as dim
from corobot_drake.sensors import render
from corobot_drake.simulation import Simulation, quiet_drake_warnings

DEFAULT_SCENARIO = Path(__file__).resolve().parent.parent / "scenarios" / "corobot.yaml"
VIEWS = ("chase", "overview", "robot-camera")


def overview_view(sim, fov_y_deg: float, aspect: float):
    """From the front-left, high, framing every robot and every world body near them."""
    points, radii = [], []
    for name in sim.robots:
        points.append(render.chassis_pose(sim, name).translation() + np.array([0, 0, 0.1]))
        radii.append(0.2)
    plant = sim.station.plant
    plant_context = plant.GetMyContextFromRoot(sim.context)
    for name, body in sim.station.bodies.items():
        p = plant.EvalBodyPoseInWorld(plant_context, body).translation()
        size = sim.scenario.world.bodies[name].shape
        half = 0.5 * max(getattr(size, "size", [2 * getattr(size, "radius", 0.5)]))
        if np.linalg.norm(p[:2] - points[0][:2]) < 6.0:
            points.append(p)
            radii.append(half * math.sqrt(3))
    points = np.array(points)
    lo = np.min(points - np.array(radii)[:, None], axis=0)
    hi = np.max(points + np.array(radii)[:, None], axis=0)
    center = (lo + hi) / 2
    center[2] = min(center[2], 0.5)
    radius = 0.5 * np.linalg.norm(hi - lo)
    half_fov = math.radians(min(fov_y_deg, fov_y_deg * aspect)) / 2
    distance = 0.7 * radius / math.sin(half_fov)
    direction = np.array([0.5, -1.0, 0.45])
    direction /= np.linalg.norm(direction)
    return render.look_at(center + distance * direction, center)


def take(sim, view: str, width: int, height: int, robot: str | None = None,
         eye=None, target=None) -> np.ndarray:
    """Renders `sim` now from `view` (or from `eye` looking at `target`, world metres);
    returns an H x W x 3 uint8 image."""
    X_WB = render.chassis_pose(sim, robot)
    if view == "robot-camera":
        # The fill light would cast the robot's own shadow ahead of it: no shadows here.
        name = render.add_renderer(sim, shadows=False, name="robot_camera_vtk")
        return render.render(sim, render.robot_camera_view(X_WB), width, height,
                             dim.CAMERA_FOV_Y_DEG, near=0.001, name=name)
    render.add_renderer(sim)
    fov = 40.0
    if eye is not None:
        X_WC = render.look_at(eye, target if target is not None else X_WB.translation())
    elif view == "chase":
        X_WC = render.chase_view(X_WB)
    elif view == "overview":
        X_WC = overview_view(sim, fov, width / height)
    else:
        raise ValueError(f"view must be one of {VIEWS}, got {view!r}")
    return render.render(sim, X_WC, width, height, fov)


def _pair(text: str, n: int, what: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != n:
        raise argparse.ArgumentTypeError(f"{what}: expected {n} comma-separated numbers")
    return values


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", type=Path, default=DEFAULT_SCENARIO)
    parser.add_argument("--output", type=Path, default=Path("snapshot.png"))
    parser.add_argument("--view", choices=VIEWS, default="chase")
    parser.add_argument("--robot", help="which robot (default: the only one)")
    parser.add_argument("--pose", type=lambda s: _pair(s, 3, "--pose"),
                        help="start pose X,Y,YAW_DEG of the robot (m, m, degrees)")
    parser.add_argument("--drive", type=lambda s: _pair(s, 2, "--drive"),
                        help="LEFT,RIGHT power in [-1, 1] from t = 0 (replaces its commands)")
    parser.add_argument("--eye", type=lambda s: _pair(s, 3, "--eye"),
                        help="X,Y,Z: a free camera here instead of --view (world, m)")
    parser.add_argument("--target", type=lambda s: _pair(s, 3, "--target"),
                        help="X,Y,Z the free camera looks at (default: the robot)")
    parser.add_argument("--time", type=float, default=0.0, help="simulate S seconds first")
    parser.add_argument("--width", type=int)
    parser.add_argument("--height", type=int)
    parser.add_argument("--visual", choices=("meshes", "boxes"),
                        help="how the robot looks (default: the scenario's)")
    parser.add_argument("--override", action="append", default=[],
                        help="YAML merged over the scenario (repeatable)")
    args = parser.parse_args(argv)
    quiet_drake_warnings()

    try:
        scenario = load_scenario(args.scenario, overrides=args.override)
        name = args.robot or (next(iter(scenario.robots)) if len(scenario.robots) == 1 else None)
        if name not in scenario.robots:
            parser.error(f"--robot: name one of {', '.join(scenario.robots)}")
        robot = scenario.robots[name]
        if args.pose:
            from corobot_drake.config.poses import ground_pose
            robot.pose = ground_pose(*args.pose)
        if args.visual:
            robot.visual = args.visual
        if args.drive:
            from corobot_drake.config.scenario import SetPower
            robot.commands = [SetPower(*args.drive)]
    except ScenarioError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2

    sim = Simulation(scenario)
    if args.time > 0:
        sim.advance(args.time)
    small = args.view == "robot-camera"
    width = args.width or (dim.CAMERA_WIDTH if small else 960)
    height = args.height or (dim.CAMERA_HEIGHT if small else 600)
    image = take(sim, args.view, width, height, name, args.eye, args.target)

    import matplotlib.image

    args.output.parent.mkdir(parents=True, exist_ok=True)
    matplotlib.image.imsave(args.output, image)
    X = render.chassis_pose(sim, name)
    x, y, _ = X.translation()
    yaw = math.degrees(render.RollPitchYaw(X.rotation()).yaw_angle())
    view = "free (--eye)" if args.eye else args.view
    print(f"{args.output}: {width}x{height} {view} view at t = {sim.time:.2f} s, "
          f"{name} at x = {x:.3f} m, y = {y:.3f} m, yaw = {yaw:.1f} deg")
    return 0


if __name__ == "__main__":
    sys.exit(main())
