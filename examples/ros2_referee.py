#!/usr/bin/env python3
"""A Robo-Magellan referee over ROS 2: watches the robot and the cones through the ROS 2
Simulation Interfaces (simulation_interfaces GetEntitiesStates: the simulation's ground truth,
not the robot's topics) and scores the run: its time, the cones touched.

    python -m corobot_drake robo_magellan.yaml --ros2 --paused &   # then, in that ROS_DOMAIN_ID:
    python examples/ros2_magellan.py &
    python examples/ros2_referee.py --start

The rules it keeps (after the SRS Robo-Magellan contest's):
- The cones are the entities named `cone_bonus_*` (bonus cones) and `cone_goal` (the goal).
- A cone is touched when its side comes within `--touch` m (default 0.05) of the robot's
  footprint: the rectangle that holds its chassis and wheels in plan (`--footprint`, default
  the Corobot's 0.305 x 0.279 m) about its base frame.
- The run's time is simulated time from the start to the goal cone's first touch. With
  `--start` the referee gives the start: it waits for a contestant on /cmd_vel, then plays
  the (paused) simulation; without, the time runs from its first look.
- Each bonus cone touched before the goal cone multiplies the time by `--bonus-factor`
  (default 0.8): the score, lower is better. A cone counts once, however often touched.
- No goal cone within `--time-limit` s of simulated time: no score (the cones touched are
  still reported), exit 1.

It looks as often as the simulation answers (a few ms of wall clock apart); after the finish
it pauses the simulation once the contestant has left /cmd_vel, or 5 s of simulated time later
(`--no-pause` leaves it playing). `--json` prints the result as one
JSON line. It never waits for ever: no answer for `--timeout` s (wall clock) ends it, exit 1.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import dataclass, field

try:  # corobot_drake's one-line check of ROS 2's environment variables
    from corobot_drake.ros2.graph import refuse_unusable
except ImportError:  # a ROS 2 install without corobot_drake: rcl's own errors

    def refuse_unusable(program: str) -> None:
        """(corobot_drake is not installed here)"""


FOOTPRINT = (0.305, 0.279)
"""m: the Corobot in plan, its wheels included (length x width), centred on base_link."""
TIMEOUT = 60.0
"""s (wall clock) to wait for the simulation's services, a contestant, an answer."""
CONES = "^cone_"
GRACE = 5.0
"""s (simulated) the simulation plays on after the finish, for the contestant to see it."""


def gap(robot: tuple[float, float, float], footprint: tuple[float, float],
        cone: tuple[float, float], radius: float) -> float:
    """m between a cone's side (its axis at `cone` (x, y), `radius`) and the robot's footprint
    rectangle (length, width) centred at `robot` (x, y, yaw), in plan; < 0 overlapping."""
    x, y, yaw = robot
    dx, dy = cone[0] - x, cone[1] - y
    along = math.cos(yaw) * dx + math.sin(yaw) * dy  # the cone's axis in the robot's frame
    across = -math.sin(yaw) * dx + math.cos(yaw) * dy
    outside = (max(abs(along) - footprint[0] / 2, 0.0), max(abs(across) - footprint[1] / 2, 0.0))
    return math.hypot(*outside) - radius


@dataclass
class Scorecard:
    """The run as the rules see it: the start, each cone's first touch (simulated s)."""

    bonus_factor: float
    start: float | None = None
    touched: dict[str, float] = field(default_factory=dict)
    finish: float | None = None

    def look(self, t: float, touching: list[str]) -> None:
        """What was seen at simulated time `t`: the cones touching the robot."""
        if self.start is None:
            self.start = t
        if self.finish is not None:
            return
        for name in touching:
            self.touched.setdefault(name, t)
        if "cone_goal" in self.touched:
            self.finish = self.touched["cone_goal"]

    @property
    def bonus(self) -> list[str]:
        """The bonus cones touched before the goal cone (all so far without one)."""
        end = math.inf if self.finish is None else self.finish
        return sorted(n for n, t in self.touched.items() if n != "cone_goal" and t <= end)

    def result(self) -> dict:
        time_ = None if self.finish is None else self.finish - self.start
        score = None if time_ is None else time_ * self.bonus_factor ** len(self.bonus)
        return {"finished": self.finish is not None, "time": time_, "score": score,
                "bonus_cones": self.bonus, "bonus_factor": self.bonus_factor,
                "touched": {n: t - self.start for n, t in sorted(self.touched.items(),
                                                                 key=lambda i: i[1])}}


def yaw_of(q) -> float:
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


class Referee:
    """The ROS 2 side: service clients of the simulation, called and waited on in turn."""

    def __init__(self, node, timeout: float):
        from simulation_interfaces.srv import GetEntitiesStates, SetSimulationState

        self.node, self.timeout = node, timeout
        self.states = node.create_client(GetEntitiesStates, "/get_entities_states")
        self.set_state = node.create_client(SetSimulationState, "/set_simulation_state")

    def call(self, client, request, what: str):
        """The answer to `request`, asked again each second without one (a server that has
        not yet discovered the client drops its answer); TimeoutError after `timeout` s."""
        import rclpy

        deadline = time.monotonic() + self.timeout
        if not client.wait_for_service(timeout_sec=self.timeout):
            raise TimeoutError(f"no {client.srv_name} service in {self.timeout:g} s (is "
                               "`python -m corobot_drake --ros2` running in this ROS_DOMAIN_ID?)")
        while time.monotonic() < deadline:
            future = client.call_async(request)
            rclpy.spin_until_future_complete(self.node, future, timeout_sec=1.0)
            if future.done():
                response = future.result()
                if response.result.result != response.result.RESULT_OK:
                    raise RuntimeError(f"{what}: {response.result.error_message}")
                return response
            client.remove_pending_request(future)
        raise TimeoutError(f"{what}: no answer in {self.timeout:g} s")

    def look(self, robot: str) -> tuple[float, dict[str, tuple]]:
        """(simulated s, {entity: (x, y, yaw)}) of the robot and the cones, now."""
        from simulation_interfaces.srv import GetEntitiesStates

        request = GetEntitiesStates.Request()
        request.filters.filter = f"^{robot}$|{CONES}"
        r = self.call(self.states, request, "get_entities_states")
        stamp = r.states[0].header.stamp if r.states else None
        t = 0.0 if stamp is None else stamp.sec + 1e-9 * stamp.nanosec
        return t, {n: (s.pose.position.x, s.pose.position.y, yaw_of(s.pose.orientation))
                   for n, s in zip(r.entities, r.states, strict=True)}

    def play(self, playing: bool) -> None:
        from simulation_interfaces.msg import SimulationState
        from simulation_interfaces.srv import SetSimulationState

        state = SimulationState.STATE_PLAYING if playing else SimulationState.STATE_PAUSED
        request = SetSimulationState.Request(state=SimulationState(state=state))
        try:
            self.call(self.set_state, request, "set_simulation_state")
        except RuntimeError as e:  # already in that state: nothing to do
            if "already" not in str(e):
                raise

    def wait_for_contestant(self, topic: str) -> None:
        deadline = time.monotonic() + self.timeout
        while self.node.count_publishers(topic) == 0:
            if time.monotonic() > deadline:
                raise TimeoutError(f"no contestant publishing {topic} in {self.timeout:g} s")
            time.sleep(0.05)


def referee_run(referee: Referee, card: Scorecard, args) -> None:
    """Looks until the goal cone is touched or the time limit passes."""
    t, seen = referee.look(args.robot)
    if args.robot not in seen:
        raise RuntimeError(f"no robot named {args.robot!r} (there are: {', '.join(seen)})")
    if "cone_goal" not in seen:
        raise RuntimeError("no cone_goal: the course needs one")
    topic = f"{'/' + args.robot if args.namespaced else ''}/cmd_vel"
    if args.start:
        card.look(t, [])  # the start: the paused simulation's time
        referee.wait_for_contestant(topic)
        referee.play(True)
        print(f"{0.0:7.2f} s  start", flush=True)
    while card.finish is None and (card.start is None or t - card.start <= args.time_limit):
        t, seen = referee.look(args.robot)
        touching = [n for n, (x, y, _) in seen.items() if n != args.robot
                    and gap(seen[args.robot], args.footprint, (x, y), args.cone_radius)
                    <= args.touch]
        before = set(card.touched)
        card.look(t, touching)
        for name in sorted(set(card.touched) - before, key=card.touched.get):
            print(f"{card.touched[name] - card.start:7.2f} s  {name} touched", flush=True)
        time.sleep(0.002)
    if not args.no_pause:
        # the contestant sees its own touch a little later: pause once it has left, or after
        # GRACE s of simulated time
        while card.finish and referee.node.count_publishers(topic) and t - card.finish < GRACE:
            t, _ = referee.look(args.robot)
            time.sleep(0.01)
        referee.play(False)


def main(argv=None) -> int:
    try:  # without the [ros2] extra: one line naming it, not a traceback
        import rclpy
        from rclpy.utilities import remove_ros_args
    except ImportError:
        from corobot_drake.extras import exit_without

        exit_without("examples/ros2_referee.py", "ros2")

    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--robot", default="corobot", help="the robot's entity name (default corobot)")
    p.add_argument("--namespaced", action="store_true",
                   help="the robot's topics are under /ROBOT/ (several robots)")
    p.add_argument("--start", action="store_true",
                   help="give the start: wait for a contestant on /cmd_vel, then play")
    p.add_argument("--touch", type=float, default=0.05, help="m (default 0.05)")
    p.add_argument("--footprint", type=float, nargs=2, default=FOOTPRINT,
                   metavar=("LENGTH", "WIDTH"), help="m (default the Corobot's 0.305 0.279)")
    p.add_argument("--cone-radius", type=float, default=0.1, help="m (default 0.1)")
    p.add_argument("--bonus-factor", type=float, default=0.8, help="in (0, 1] (default 0.8)")
    p.add_argument("--time-limit", type=float, default=300.0,
                   help="s of simulated time (default 300)")
    p.add_argument("--timeout", type=float, default=TIMEOUT,
                   help=f"s (wall clock) to wait for the simulation (default {TIMEOUT:g})")
    p.add_argument("--no-pause", action="store_true", help="leave the simulation playing")
    p.add_argument("--json", action="store_true", help="print the result as one JSON line")
    args = p.parse_args(remove_ros_args(sys.argv if argv is None else ["", *argv])[1:])
    for name, low in (("touch", 0.0), ("cone_radius", 0.0), ("time_limit", 0.0),
                      ("timeout", 0.0)):
        value = getattr(args, name)
        if not (math.isfinite(value) and value > low):
            p.error(f"--{name.replace('_', '-')}: a number > 0; got {value}")
    if not 0.0 < args.bonus_factor <= 1.0:
        p.error(f"--bonus-factor: in (0, 1]; got {args.bonus_factor}")
    refuse_unusable("examples/ros2_referee.py")  # before any DDS
    rclpy.init(args=sys.argv if argv is None else ["", *argv])
    node = rclpy.create_node("magellan_referee")
    card = Scorecard(args.bonus_factor)
    try:
        referee_run(Referee(node, args.timeout), card, args)
    except (TimeoutError, RuntimeError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return report(card.result(), args)


def report(result: dict, args) -> int:
    """Prints the result (a line each, or one JSON line); 0 if the run finished."""
    if args.json:
        print(json.dumps(result), flush=True)
    elif result["finished"]:
        n = len(result["bonus_cones"])
        print(f"finished in {result['time']:.2f} s, {n} bonus cone{'s' * (n != 1)}: score "
              f"{result['time']:.2f} x {args.bonus_factor:g}^{n} = {result['score']:.2f} s")
    else:
        print(f"no goal cone in {args.time_limit:g} s: no score "
              f"({len(result['touched'])} cones touched)")
    return 0 if result["finished"] else 1


if __name__ == "__main__":
    sys.exit(main())
