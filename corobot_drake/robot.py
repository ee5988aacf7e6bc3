"""Checks a robot file: `python -m corobot_drake.robot check FILE [--urdf OUT]`.

Loads the robot file and its model as the simulation will (`robots.load`), prints what it
understood (the wheels per side, radius, track, wheelbase, mass, the drive's kind and top
speed, the casters, the sensors) and writes the robot's URDF for RViz and
robot_state_publisher (`--urdf`, default `<robot>.urdf` in the current folder; never over the
robot's own model or robot file), saying where. A bad robot file is one line naming
file:line:field, exit status 2. `FILE` may also name a shipped robot (`corobot`).
"""

import sys
from pathlib import Path

from corobot_drake.arguments import ToolParser, one_line_errors
from corobot_drake.robots import ROBOTS, RobotSpec, robot_spec
from corobot_drake.robots.spec import LEFT, RIGHT


def drive_kind(spec: RobotSpec) -> str:
    """`differential drive` (one wheel a side) or `skid steer` (more)."""
    per_side = max(spec.sides.count(LEFT), spec.sides.count(RIGHT))
    return "differential drive" if per_side == 1 else "skid steer"


def describe(spec: RobotSpec) -> list[str]:
    """What the robot file says, line by line, as `check` prints it."""
    side = {LEFT: "left", RIGHT: "right"}
    lines = [f"robot {spec.kind}: {spec.file}",
             f"  model: {spec.model_file} (base link {spec.base!r})",
             f"  {drive_kind(spec)}: {spec.sides.count(LEFT)} left, {spec.sides.count(RIGHT)} "
             f"right wheel(s)"]
    for w in spec.wheels:
        x, y, z = w.center
        lines.append(f"    {side[w.side]:5s} {w.joint} (link {w.link}): radius {w.radius:.4f} m, "
                     f"centre ({x:+.4f}, {y:+.4f}, {z:.4f}) m")
    lines += [
        f"  wheel radius {spec.wheel_radius:.4f} m, track {spec.track:.4f} m, wheelbase "
        f"{spec.wheelbase:.4f} m",
        f"  mass {spec.mass:.3f} kg, centre of mass ({spec.com[0]:+.4f}, {spec.com[1]:+.4f}, "
        f"{spec.com[2]:.4f}) m",
        "  casters: " + (", ".join(spec.casters) + f" (friction {spec.caster_friction:g})"
                         if spec.casters else "none"),
        f"  drive: {spec.drive.motor_torque_scaling:.4g} rad/s at power 1, top speed "
        f"{spec.top_speed():.3f} m/s; slew {spec.drive.slew_rate:g} rad/s^2, torque limit "
        f"{spec.contact.effort_limit:.3g} N m, {spec.encoder_ticks_per_revolution} ticks/rev",
        f"  spin: {spec.spin_yaw_per_rim_speed:.4f} rad/s of yaw per m/s at the rims",
        f"  tyres: friction {spec.contact.friction:g}, modulus "
        f"{spec.contact.hydroelastic_modulus:.3g} Pa, mesh "
        f"{spec.contact.resolution_hint * 1000:.3g} mm",
    ]
    sensors = [f"{field}.{name} on {config.X_PB.base_frame}"
               for field, configs in spec.sensors.items() for name, config in configs.items()]
    lines.append("  sensors: " + (", ".join(sensors) if sensors else "none"))
    lines.append(f"  links: {', '.join(spec.links)}")
    return lines


def _parser() -> ToolParser:
    parser = ToolParser(prog="python -m corobot_drake.robot", description=__doc__.splitlines()[0])
    commands = parser.add_subparsers(dest="command", required=True)
    check = commands.add_parser("check", help="load a robot file, say what it holds, write its "
                                "URDF", formatter_class=parser.formatter_class)
    check.error = parser.error
    check.add_argument("file", help="a robot file (YAML), or a shipped robot "
                       f"({', '.join(ROBOTS)})")
    check.add_argument("--urdf", type=Path, default=None,
                       help="where to write the robot's URDF (default: ./<robot>.urdf)")
    check.add_argument("--no-urdf", action="store_true", help="write no URDF")
    return parser


@one_line_errors
def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    if args.file not in ROBOTS and not Path(args.file).is_file():
        print(f"error: {args.file}: no such robot file (shipped robots: {', '.join(ROBOTS)})",
              file=sys.stderr)
        return 2
    spec = robot_spec(args.file if args.file in ROBOTS else str(Path(args.file).resolve()))
    print("\n".join(describe(spec)))
    if not args.no_urdf:
        from corobot_drake.ros2.urdf import robot_urdf

        out = (args.urdf or Path(f"{spec.kind}.urdf")).resolve()
        own = {Path(spec.model_file).resolve(): "model", Path(spec.file).resolve(): "robot file"}
        if out in own:  # run beside its my_robot.urdf, the default would replace the model
            print(f"error: {out} is the robot's own {own[out]}: not written over (--urdf FILE "
                  "names another, --no-urdf writes none)", file=sys.stderr)
            return 2
        out.write_text(robot_urdf(spec))
        print(f"wrote {out} (the robot's URDF, for RViz and robot_state_publisher)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
