#!/usr/bin/env python3
"""The book's square over ROS 2: four times DriveDistance then RotateDegrees 90, as an action
client of the simulated robot (`python -m corobot_drake --ros2`), printing each result.

    python -m corobot_drake --ros2 --headless &      # then, in the same ROS_DOMAIN_ID:
    python examples/ros2_square.py --side 1.0 --power 0.5
    python examples/ros2_square.py --robot corobot_2  # several robots: its namespace

It never waits for ever: with no action server, or a goal that neither answers nor reports
progress for `--timeout` s (a stopped or starved simulation), it says which and exits 1.

A ROS 2 Jazzy install runs it as it is (it needs corobot_interfaces: copy
corobot_drake/ros2/ros_packages/corobot_interfaces into a colcon workspace).
"""

import argparse
import math
import sys
import time

try:  # without the [ros2] extra: one line naming it, not a traceback
    import rclpy
    from corobot_interfaces.action import DriveDistance, RotateDegrees
    from rclpy.action import ActionClient
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("examples/ros2_square.py", "ros2")

try:  # corobot_drake's one-line check of ROS 2's environment variables
    from corobot_drake.ros2.graph import refuse_unusable
except ImportError:  # a ROS 2 install without corobot_drake: rcl's own errors

    def refuse_unusable(program: str) -> None:
        """(corobot_drake is not installed here)"""


TIMEOUT = 60.0
"""s (wall clock) to wait for the simulation: its action servers (discovery takes a few
seconds), a goal's acceptance, and news of a running goal (feedback every 0.1 s)."""


class NoAnswerError(Exception):
    """The simulation did not answer in time: what was waited for."""


def wait(node, future, timeout: float, what: str, progress=lambda: 0) -> None:
    """Spins `node` until `future` is done; NoAnswerError(`what`) after `timeout` s without it,
    counted again from each change of `progress()` (the feedback received so far)."""
    seen, last = progress(), time.monotonic()
    while not future.done():
        rclpy.spin_until_future_complete(node, future, timeout_sec=0.1)
        if progress() != seen:
            seen, last = progress(), time.monotonic()
        elif time.monotonic() - last > timeout:
            raise NoAnswerError(f"{what} in {timeout:g} s")


def run_goal(node, client: ActionClient, goal, label: str, timeout: float) -> bool:
    """Sends `goal`, prints the feedback's last value and the result; True if it succeeded."""
    feedback = []
    sent = client.send_goal_async(goal, feedback_callback=lambda f: feedback.append(f.feedback))
    wait(node, sent, timeout, f"{label}: no answer to the goal")
    handle = sent.result()
    if not handle.accepted:
        print(f"{label}: rejected")
        return False
    done = handle.get_result_async()
    wait(node, done, timeout, f"{label}: no feedback nor result", lambda: len(feedback))
    result = done.result().result
    print(f"{label}: {'succeeded' if result.success else 'failed (' + result.reason + ')'}"
          f" after {len(feedback)} feedback messages")
    return result.success


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--side", type=float, default=1.0, help="m (default 1.0)")
    p.add_argument("--power", type=float, default=0.5, help="in (0, 1] (default 0.5)")
    p.add_argument("--robot", default="", help="the robot's namespace (several robots)")
    p.add_argument("--timeout", type=float, default=TIMEOUT,
                   help="s to wait for the simulation's action servers, a goal's answer, and "
                   f"news of a running goal (default {TIMEOUT:g})")
    args = p.parse_args(argv)
    if not (math.isfinite(args.timeout) and args.timeout > 0):
        p.error(f"--timeout: a number of s > 0; got {args.timeout}")
    prefix = f"/{args.robot}" if args.robot else ""
    refuse_unusable("examples/ros2_square.py")  # before any DDS
    rclpy.init()
    node = rclpy.create_node("corobot_square")
    drive = ActionClient(node, DriveDistance, f"{prefix}/drive_distance")
    rotate = ActionClient(node, RotateDegrees, f"{prefix}/rotate_degrees")
    try:
        for client, name in ((drive, "drive_distance"), (rotate, "rotate_degrees")):
            if not client.wait_for_server(timeout_sec=args.timeout):
                print(f"error: no action server {prefix}/{name} in {args.timeout:g} s (is "
                      "`python -m corobot_drake --ros2` running in this ROS_DOMAIN_ID?)",
                      file=sys.stderr)
                return 1
        for leg in range(1, 5):
            if not run_goal(node, drive, DriveDistance.Goal(distance=args.side,
                                                            power=args.power),
                            f"leg {leg}: drive {args.side:g} m", args.timeout):
                return 1
            if not run_goal(node, rotate, RotateDegrees.Goal(degrees=90.0, power=args.power),
                            f"leg {leg}: rotate 90 deg", args.timeout):
                return 1
        return 0
    except NoAnswerError as e:
        print(f"error: {e} (is the simulation stopped, or the machine starved?)",
              file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main())
