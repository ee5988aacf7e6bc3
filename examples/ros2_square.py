#!/usr/bin/env python3
"""The book's square over ROS 2: four times DriveDistance then RotateDegrees 90, as an action
client of the simulated robot (`python -m corobot_drake --ros2`), printing each result.

    python -m corobot_drake --ros2 --headless &      # then, in the same ROS_DOMAIN_ID:
    python examples/ros2_square.py --side 1.0 --power 0.5
    python examples/ros2_square.py --robot corobot_2  # several robots: its namespace

A ROS 2 Jazzy install runs it as it is (it needs corobot_interfaces: copy
corobot_drake/ros2/ros_packages/corobot_interfaces into a colcon workspace).
"""

import argparse
import sys

import rclpy
from corobot_interfaces.action import DriveDistance, RotateDegrees
from rclpy.action import ActionClient

SERVER_TIMEOUT = 30.0
"""s to wait for the simulation's action servers (discovery takes a few seconds)."""


def run_goal(node, client: ActionClient, goal, label: str) -> bool:
    """Sends `goal`, prints the feedback's last value and the result; True if it succeeded."""
    feedback = []
    sent = client.send_goal_async(goal, feedback_callback=lambda f: feedback.append(f.feedback))
    rclpy.spin_until_future_complete(node, sent)
    handle = sent.result()
    if not handle.accepted:
        print(f"{label}: rejected")
        return False
    done = handle.get_result_async()
    rclpy.spin_until_future_complete(node, done)
    result = done.result().result
    print(f"{label}: {'succeeded' if result.success else 'failed (' + result.reason + ')'}"
          f" after {len(feedback)} feedback messages")
    return result.success


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--side", type=float, default=1.0, help="m (default 1.0)")
    p.add_argument("--power", type=float, default=0.5, help="in (0, 1] (default 0.5)")
    p.add_argument("--robot", default="", help="the robot's namespace (several robots)")
    args = p.parse_args(argv)
    prefix = f"/{args.robot}" if args.robot else ""
    rclpy.init()
    node = rclpy.create_node("corobot_square")
    drive = ActionClient(node, DriveDistance, f"{prefix}/drive_distance")
    rotate = ActionClient(node, RotateDegrees, f"{prefix}/rotate_degrees")
    try:
        for client in (drive, rotate):
            if not client.wait_for_server(timeout_sec=SERVER_TIMEOUT):
                print(f"error: no action server {client._action_name} (is `python -m "
                      "corobot_drake --ros2` running in this ROS_DOMAIN_ID?)", file=sys.stderr)
                return 1
        for leg in range(1, 5):
            if not run_goal(node, drive, DriveDistance.Goal(distance=args.side,
                                                            power=args.power),
                            f"leg {leg}: drive {args.side:g} m"):
                return 1
            if not run_goal(node, rotate, RotateDegrees.Goal(degrees=90.0, power=args.power),
                            f"leg {leg}: rotate 90 deg"):
                return 1
        return 0
    except KeyboardInterrupt:
        return 130
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main())
