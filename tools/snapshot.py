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
the side), `robot-camera` (the robot's own camera: its mount, 320x240, 30 deg vertical fov).
The rendering is `lab.snapshot`.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from pydrake.systems.sensors import CameraConfig

from corobot_drake.arguments import (
    ToolParser,
    bounded,
    one_line_errors,
    output_file,
    scenario_file,
)
from corobot_drake.config.bounds import DRAKE_BOUNDS
from corobot_drake.config.poses import ground_pose
from corobot_drake.config.scenario import SetPower, load_scenario
from corobot_drake.limits import DURATION
from corobot_drake.names import unknown_robot
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.robots import corobot
from corobot_drake.sensors import render
from corobot_drake.simulation import Simulation, quiet_drake_warnings
from lab.snapshot import VIEWS, take

PIXELS = DRAKE_BOUNDS[CameraConfig]["width"]
CAMERA = corobot.sensor("cameras", "front")
"""The Corobot's camera (its robot file's): the robot-camera view's default size."""


def _pair(text: str, n: int, what: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != n:
        raise argparse.ArgumentTypeError(f"{what}: expected {n} comma-separated numbers")
    return values


def _parser() -> argparse.ArgumentParser:
    parser = ToolParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", type=scenario_file, default=str(DEFAULT_SCENARIO),
                        help="scenario file, or a shipped scenario's name (maze.yaml) from "
                        "any folder")
    parser.add_argument("--output", type=output_file, default=Path("snapshot.png"),
                        help="PNG to write")
    parser.add_argument("--view", choices=VIEWS, default="chase", help="camera to render")
    parser.add_argument("--robot", help="which robot (None: the only one)")
    parser.add_argument("--pose", type=lambda s: _pair(s, 3, "--pose"),
                        help="start pose X,Y,YAW_DEG of the robot (m, m, degrees; "
                        "None: the scenario's)")
    parser.add_argument("--drive", type=lambda s: _pair(s, 2, "--drive"),
                        help="LEFT,RIGHT power in [-1, 1] from t = 0 (replaces its commands; "
                        "None: its commands)")
    parser.add_argument("--eye", type=lambda s: _pair(s, 3, "--eye"),
                        help="X,Y,Z: a free camera here instead of --view (world, m; None: --view)")
    parser.add_argument("--target", type=lambda s: _pair(s, 3, "--target"),
                        help="X,Y,Z the free camera looks at (None: the robot)")
    parser.add_argument("--time", type=bounded(DURATION), default=0.0,
                        help="simulate S seconds first")
    parser.add_argument("--width", type=bounded(PIXELS, int),
                        help="image width, px (None: the camera's)")
    parser.add_argument("--height", type=bounded(PIXELS, int),
                        help="image height, px (None: the camera's)")
    parser.add_argument("--visual", choices=("meshes", "boxes"),
                        help="how the robot looks (None: the scenario's)")
    parser.add_argument("--override", action="append", default=[],
                        help="YAML merged over the scenario (repeatable)")
    return parser


def _scenario(args, parser: argparse.ArgumentParser):
    """(scenario, robot name) with the command line's changes; raises ScenarioError."""
    scenario = load_scenario(args.scenario, overrides=args.override)
    name = args.robot or (next(iter(scenario.robots)) if len(scenario.robots) == 1 else None)
    if name is None:
        parser.error(f"--robot: name one of {', '.join(scenario.robots)}")
    if name not in scenario.robots:
        parser.error(f"--robot: {unknown_robot(name, scenario.robots)}")
    robot = scenario.robots[name]
    if args.pose:
        robot.pose = ground_pose(*args.pose)
    if args.visual:
        robot.visual = args.visual
    if args.drive:
        robot.commands = [SetPower(*args.drive)]
    return scenario, name


@one_line_errors
def main(argv: list[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    quiet_drake_warnings()
    scenario, name = _scenario(args, parser)
    sim = Simulation(scenario)  # checks the command line's changes (--pose, --drive)
    if args.time > 0:
        sim.advance(args.time)
    small = args.view == "robot-camera"
    width = args.width or (CAMERA["width"] if small else 960)
    height = args.height or (CAMERA["height"] if small else 600)
    image = take(sim, args.view, width, height, name, args.eye, args.target)

    from PIL import Image  # the core's (Matplotlib is the [study] extra's)

    args.output.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(image).save(args.output)
    X = render.chassis_pose(sim, name)
    x, y, _ = X.translation()
    yaw = math.degrees(render.RollPitchYaw(X.rotation()).yaw_angle())
    view = "free (--eye)" if args.eye else args.view
    print(f"{args.output}: {width}x{height} {view} view at t = {sim.time:.2f} s, "
          f"{name} at x = {x:.3f} m, y = {y:.3f} m, yaw = {yaw:.1f} deg")
    return 0


if __name__ == "__main__":
    sys.exit(main())
