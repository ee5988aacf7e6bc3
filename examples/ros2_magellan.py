#!/usr/bin/env python3
"""A Robo-Magellan contestant over ROS 2: drives the simulated robot (`python -m corobot_drake
--ros2`) to each cone of a course in turn, the bonus cones first and the goal cone last, from
standard topics only: /odom (nav_msgs/Odometry) to head for a cone's place on the course map,
/camera/image_raw (sensor_msgs/Image, with /camera/camera_info) to find the cone by its orange
and home on it, /ir/front (sensor_msgs/Range) to see an obstacle on the way and to touch the
cone. It publishes geometry_msgs/Twist on /cmd_vel.

    python -m corobot_drake robo_magellan.yaml --ros2 --paused &   # then, in that ROS_DOMAIN_ID:
    python examples/ros2_magellan.py &
    python examples/ros2_referee.py --start      # starts the run, scores it

The course map is the scenario's cones (`world.bodies` named `cone_bonus_*` and `cone_goal`,
`--course FILE`): a contestant is handed the cones' places before the run. The robot starts
at the map's origin facing +x (where `odom` starts). Every step is paced by the simulation's
time (each /odom message), so it drives the same at any `--rate`.

It never waits for ever: with no /odom for `--timeout` s (wall clock) it says so and exits 1,
and it gives up after `--time-limit` s of simulated time. Exit 0 once the goal cone is touched.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

try:  # corobot_drake's one-line check of ROS 2's environment variables
    from corobot_drake.ros2.graph import refuse_unusable
except ImportError:  # a ROS 2 install without corobot_drake: rcl's own errors

    def refuse_unusable(program: str) -> None:
        """(corobot_drake is not installed here)"""


COURSE = Path(__file__).resolve().parent.parent / "scenarios" / "robo_magellan.yaml"
SPEED = 0.5
"""m/s cruising (the Corobot's top speed is 0.61)."""
TURN = 1.2
"""rad/s at most."""
HOME_RANGE = 1.6
"""m (odometry): nearer than this to a cone, home on it by camera once it is in view."""
HOME_GATE = 0.4
"""rad: an orange blob this near the cone's bearing from odometry is that cone."""
OBSTACLE_RANGE = 0.5
"""m (IR): nearer than this, and not the cone, is an obstacle to go round."""
AVOID_TURN = math.radians(70)
AVOID_DRIVE = 0.8
"""rad and m: an obstacle is gone round by turning away, then driving on."""
TOUCH_RANGE = 0.03
"""m (IR): the cone's side this near the robot's front is a touch."""
BACK_OFF = 0.35
"""m driven back from a touched cone before heading for the next."""
LOST = 0.5
"""s (simulated) without the homed cone in view: head for its place again."""
STALE = 0.3
"""s (simulated): a camera frame older than this is not looked at (none has come since)."""
CENTRED = 0.2
"""rad: homing, a cone further off than this is turned to in place (the IR looks straight
ahead: it must see the cone before the wheels touch it)."""
TIMEOUT = 60.0
"""s (wall clock) to wait for /odom (discovery takes a few seconds)."""
MODES = {"head": "heading for it", "turn_away": "an obstacle ahead: turning away",
         "pass_by": "passing the obstacle", "home": "in view: homing on it",
         "back_off": "touched: backing off"}


# --- the course map and the camera, without ROS ---------------------------------------------


class _AnyTag(yaml.SafeLoader):
    """Reads a scenario's tagged values (!Box {...}, !Rpy {...}) as plain mappings."""


_AnyTag.add_multi_constructor("!", lambda loader, suffix, node: (
    loader.construct_mapping(node, deep=True) if isinstance(node, yaml.MappingNode) else None))


def load_course(path: Path) -> list[tuple[str, float, float]]:
    """(name, x m, y m) of each cone of the scenario `path` in the order to visit: the bonus
    cones (`cone_bonus_*`) in the file's order, then `cone_goal`."""
    bodies = (yaml.load(Path(path).read_text(), Loader=_AnyTag) or {}).get(
        "world", {}).get("bodies", {})
    cones = [(name, *map(float, body["pose"]["translation"][:2]))
             for name, body in bodies.items() if name.startswith("cone_")]
    goal = [c for c in cones if c[0] == "cone_goal"]
    if len(goal) != 1:
        raise ValueError(f"{path}: world.bodies: needs one cone_goal (has {len(goal)})")
    return [c for c in cones if c[0].startswith("cone_bonus")] + goal


def orange_blobs(rgb: np.ndarray, min_pixels: int = 20) -> list[tuple[float, int]]:
    """(mean column, pixels) of each orange blob in an RGB image (H x W x 3, uint8): the runs
    of columns that hold a traffic cone's orange (red over twice green, blue near none), lit
    or in shade. Blobs side by side with no column between are one."""
    r, g, b = (rgb[..., i].astype(np.int16) for i in range(3))
    counts = ((r > 60) & (r > 2 * g) & (r > 3 * b)).sum(axis=0)
    on = np.concatenate(([False], counts >= 2, [False]))
    edges = np.flatnonzero(np.diff(on.astype(np.int8)))
    blobs = []
    for first, end in zip(edges[::2], edges[1::2], strict=True):
        pixels = int(counts[first:end].sum())
        if pixels >= min_pixels:
            columns = np.arange(first, end)
            blobs.append((float((columns * counts[first:end]).sum() / pixels), pixels))
    return blobs


def wrap(angle: float) -> float:
    """`angle` in (-pi, pi]."""
    return math.atan2(math.sin(angle), math.cos(angle))


# --- the contestant's behaviour, without ROS -------------------------------------------------


@dataclass
class Sensed:
    """What the driver knows at one step: simulated time (s), the odometry's pose (m, m, rad
    in `odom`), the front IR range (m, +inf: nothing), the orange blobs' bearings (rad, left
    positive) from the camera's latest frame."""


    t: float
    x: float
    y: float
    yaw: float
    ir: float = math.inf
    bearings: list[float] | None = None
    """None: no fresh frame (the camera's last is older than `STALE`)."""


@dataclass
class Driver:
    """Visits `course`'s cones in turn: heads for each by odometry, goes round what the IR
    sees on the way, homes on the cone by camera once near, touches it (IR), backs off.
    `step` is called once per odometry message and returns (linear m/s, angular rad/s)."""

    course: list[tuple[str, float, float]]
    mode: str = "head"
    target: int = 0
    since: float = 0.0
    """s: when the current mode (or the homed cone's last sighting) began."""
    mark: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """(x, y, yaw) where the current manoeuvre began."""
    side: float = 1.0
    touched: list[tuple[str, float]] = field(default_factory=list)

    @property
    def done(self) -> bool:
        return self.target >= len(self.course)

    def _to(self, mode: str, s: Sensed) -> None:
        self.mode, self.since, self.mark = mode, s.t, (s.x, s.y, s.yaw)

    def _cone(self, s: Sensed, index: int | None = None) -> tuple[float, float]:
        """(distance m, bearing rad) of a cone's centre by odometry (default the target's)."""
        _, cx, cy = self.course[self.target if index is None else index]
        return math.hypot(cx - s.x, cy - s.y), wrap(math.atan2(cy - s.y, cx - s.x) - s.yaw)

    def _explained(self, s: Sensed) -> bool:
        """Whether the IR sees the target cone or the one just touched: one of them about
        ahead, at about the range its place on the map gives (its centre less ~0.21 m: the
        robot's front and the cone's radius)."""
        for index in (self.target, self.target - 1):
            distance, bearing = self._cone(s, index)
            if index >= 0 and abs(bearing) < 0.35 and abs(s.ir - (distance - 0.21)) < 0.3:
                return True
        return False

    def _avoid(self, s: Sensed, bearing: float) -> tuple[float, float]:
        """Something not a cone is ahead: turn away from it (the target's side)."""
        self.side = 1.0 if bearing >= 0 else -1.0
        self._to("turn_away", s)
        return 0.0, self.side * TURN

    def _moved(self, s: Sensed) -> float:
        return math.hypot(s.x - self.mark[0], s.y - self.mark[1])

    def step(self, s: Sensed) -> tuple[float, float]:
        if self.done:
            return 0.0, 0.0
        return getattr(self, f"_{self.mode}")(s)

    def _head(self, s: Sensed) -> tuple[float, float]:
        distance, bearing = self._cone(s)
        v, w = steer(bearing)
        if v > 0 and s.ir < OBSTACLE_RANGE and not self._explained(s):  # turning in place,
            return self._avoid(s, bearing)  # what is ahead is in nobody's way
        if distance < HOME_RANGE and self._blob(s, bearing) is not None:
            self._to("home", s)
            return self._home(s)
        if s.ir < math.inf:  # something ahead: slower, to stop short of it should it be in the way
            v = min(v, 0.3)
        return v, w

    def _turn_away(self, s: Sensed) -> tuple[float, float]:
        if abs(wrap(s.yaw - self.mark[2])) >= AVOID_TURN:
            self._to("pass_by", s)
            return SPEED, 0.0
        return 0.0, self.side * TURN

    def _pass_by(self, s: Sensed) -> tuple[float, float]:
        if s.ir < OBSTACLE_RANGE:  # still in the way: turn further
            self._to("turn_away", s)
            return 0.0, self.side * TURN
        if self._moved(s) >= AVOID_DRIVE:
            self._to("head", s)
        return SPEED, 0.0

    def _blob(self, s: Sensed, bearing: float) -> float | None:
        """The bearing of the orange blob nearest `bearing`, if within HOME_GATE of it."""
        near = min(s.bearings or (), key=lambda b: abs(b - bearing), default=None)
        return near if near is not None and abs(near - bearing) < HOME_GATE else None

    def _home(self, s: Sensed) -> tuple[float, float]:
        if s.ir < TOUCH_RANGE:
            self.touched.append((self.course[self.target][0], s.t))
            if self.course[self.target][0] == "cone_goal":
                self.target = len(self.course)  # finished: stay touching it
            else:
                self._to("back_off", s)
            return 0.0, 0.0
        distance, bearing = self._cone(s)
        if s.ir < distance - 0.21 - 0.35:  # much nearer than the cone: in the way
            return self._avoid(s, bearing)
        if s.bearings is None:  # no fresh frame: wait for one
            return 0.0, 0.0
        seen = self._blob(s, bearing)
        if seen is None:
            if s.t - self.since > LOST:
                self._to("head", s)
            return 0.0, 0.0
        self.since = s.t
        # slow down as the IR closes in: stopped within ~1 cm of TOUCH_RANGE
        v = SPEED if math.isinf(s.ir) else min(SPEED, max(0.08, 2.5 * (s.ir - TOUCH_RANGE)))
        return v * max(0.0, 1 - abs(seen) / CENTRED), max(-TURN, min(TURN, 3.0 * seen))

    def _back_off(self, s: Sensed) -> tuple[float, float]:
        if self._moved(s) >= BACK_OFF:
            self.target += 1
            self._to("head", s)
            return 0.0, 0.0
        return -0.35, 0.0


def steer(bearing: float) -> tuple[float, float]:
    """(linear, angular) towards `bearing` (rad, left positive): turn in place when it is
    more than ~35 deg off, else drive on, slower the more it is off."""
    w = max(-TURN, min(TURN, 2.0 * bearing))
    if abs(bearing) > 0.6:
        return 0.0, w
    return SPEED * (1 - 0.5 * abs(bearing) / 0.6), w


# --- ROS 2 -----------------------------------------------------------------------------------


class Contestant:
    """The ROS 2 side: the subscriptions feed a `Driver`, each /odom steps it to a /cmd_vel."""

    def __init__(self, node, driver: Driver, prefix: str, time_limit: float,
                 verbose: bool = False):
        from geometry_msgs.msg import Twist
        from nav_msgs.msg import Odometry
        from rclpy.qos import qos_profile_sensor_data
        from sensor_msgs.msg import CameraInfo, Image, Range

        self.node, self.driver, self.time_limit = node, driver, time_limit
        self.verbose = verbose
        self.ir, self.bearings, self.frame, self.camera = math.inf, [], -math.inf, None
        self.last_odom, self.t0, self.failed = time.monotonic(), None, ""
        self.cmd_vel, self.prefix, self._twist = None, prefix, Twist
        sensor = qos_profile_sensor_data
        self.subscriptions = [
            node.create_subscription(Odometry, f"{prefix}/odom", self.on_odom, 10),
            node.create_subscription(Range, f"{prefix}/ir/front", self.on_ir, sensor),
            node.create_subscription(CameraInfo, f"{prefix}/camera/camera_info", self.on_info,
                                     sensor),
            node.create_subscription(Image, f"{prefix}/camera/image_raw", self.on_image, sensor)]

    def ready(self) -> bool:
        """Every topic it reads has its publisher: then it publishes /cmd_vel (a referee's
        start waits for that publisher)."""
        if self.cmd_vel is None and all(s.get_publisher_count() for s in self.subscriptions):
            self.cmd_vel = self.node.create_publisher(self._twist, f"{self.prefix}/cmd_vel", 10)
        return self.cmd_vel is not None

    def on_ir(self, msg) -> None:
        self.ir = msg.range if not math.isnan(msg.range) else math.inf

    def on_info(self, msg) -> None:
        self.camera = (msg.k[0], msg.k[2])  # fx, cx (pixels)

    def on_image(self, msg) -> None:
        if self.camera is None or msg.encoding != "rgb8":
            return
        rows = np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.step)
        rgb = rows[:, :3 * msg.width].reshape(msg.height, msg.width, 3)
        fx, cx = self.camera
        self.bearings = [math.atan2(cx - u, fx) for u, _ in orange_blobs(rgb)]
        self.frame = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec

    def on_odom(self, msg) -> None:
        self.last_odom = time.monotonic()
        t = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
        self.t0 = t if self.t0 is None else self.t0
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
        before = (self.driver.mode, self.driver.target)
        fresh = self.bearings if t - self.frame <= STALE else None
        v, w = self.driver.step(Sensed(t, p.x, p.y, yaw, self.ir, fresh))
        if (self.driver.mode, self.driver.target) != before and not self.driver.done:
            self.report(t, (p.x, p.y, yaw), fresh)
        if t - self.t0 > self.time_limit and not self.driver.done:
            self.failed = f"no goal cone in {self.time_limit:g} s of simulated time"
            v, w = 0.0, 0.0
        twist = self._twist()
        twist.linear.x, twist.angular.z = float(v), float(w)
        if self.cmd_vel is not None:
            self.cmd_vel.publish(twist)

    def report(self, t: float, pose: tuple[float, float, float], bearings) -> None:
        """A line for the driver's new mode; `verbose`: what it was sensing."""
        d = self.driver
        line = f"{t:7.2f} s  {d.course[d.target][0]}: {MODES[d.mode]}"
        if self.verbose:
            seen = "-" if bearings is None else [round(math.degrees(b)) for b in bearings]
            line += (f"  (odom {pose[0]:.2f} {pose[1]:.2f} m {math.degrees(pose[2]):.0f} deg,"
                     f" IR {self.ir:.2f} m, orange at {seen} deg)")
        print(line, flush=True)


def main(argv=None) -> int:
    try:  # without the [ros2] extra: one line naming it, not a traceback
        import rclpy
        from rclpy.utilities import remove_ros_args
    except ImportError:
        from corobot_drake.extras import exit_without

        exit_without("examples/ros2_magellan.py", "ros2")

    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--course", type=Path, default=COURSE,
                   help="the course's scenario file (default scenarios/robo_magellan.yaml)")
    p.add_argument("--robot", default="", help="the robot's namespace (several robots)")
    p.add_argument("--time-limit", type=float, default=300.0,
                   help="s of simulated time before giving up (default 300)")
    p.add_argument("--timeout", type=float, default=TIMEOUT,
                   help=f"s (wall clock) to wait for /odom (default {TIMEOUT:g})")
    p.add_argument("--verbose", action="store_true",
                   help="with each new mode, the odometry, IR and camera it acted on")
    args = p.parse_args(remove_ros_args(sys.argv if argv is None else ["", *argv])[1:])
    for name in ("time_limit", "timeout"):
        if not (math.isfinite(getattr(args, name)) and getattr(args, name) > 0):
            p.error(f"--{name.replace('_', '-')}: a number of s > 0; got {getattr(args, name)}")
    try:
        course = load_course(args.course)
    except (OSError, ValueError, KeyError, TypeError, yaml.YAMLError) as e:
        print(f"error: --course: {e}", file=sys.stderr)
        return 2
    refuse_unusable("examples/ros2_magellan.py")  # before any DDS
    rclpy.init(args=sys.argv if argv is None else ["", *argv])
    node = rclpy.create_node("magellan_contestant")
    prefix = f"/{args.robot}" if args.robot else ""
    contestant = Contestant(node, Driver(course), prefix, args.time_limit, args.verbose)
    print(f"course: {' -> '.join(name for name, _, _ in course)}", flush=True)
    try:
        while not contestant.driver.done and not contestant.failed:
            rclpy.spin_once(node, timeout_sec=0.1)
            if not contestant.ready():
                contestant.last_odom = time.monotonic()  # the timeout runs once ready
            elif time.monotonic() - contestant.last_odom > args.timeout:
                contestant.failed = (f"no {prefix}/odom in {args.timeout:g} s (is `python -m "
                                     "corobot_drake --ros2` running, and playing?)")
        if contestant.cmd_vel is not None:
            contestant.cmd_vel.publish(contestant._twist())  # stop
        if contestant.failed:
            print(f"error: {contestant.failed}", file=sys.stderr)
            return 1
        name, when = contestant.driver.touched[-1]
        print(f"{when:7.2f} s  {name}: touched: finished", flush=True)
        return 0
    except KeyboardInterrupt:
        return 130
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main())
