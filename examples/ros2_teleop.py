#!/usr/bin/env python3
"""Keyboard teleop over ROS 2, as teleop_twist_keyboard: keys to geometry_msgs/Twist on
/cmd_vel of the simulated robot (`python -m corobot_drake --ros2`).

    u i o      i forward, , back, j / l turn left / right in place,
    j k l      u o m . forward and back while turning; k or space stops
    m , .      q / z: all speeds x 1.1 / x 0.9; Ctrl-C quits (and stops the robot)

The Twist is sent again every 0.1 s while a move is on: the simulation stops the robot when
none has come for 0.5 s (its `cmd_vel_timeout`), as a real base's watchdog would.

    python -m corobot_drake --ros2 &                 # Meshcat shows it; then:
    python examples/ros2_teleop.py [--robot NAME]

It first waits for the simulation's /cmd_vel subscription, at most `--timeout` s, and says
so if none comes (keys sent to nobody would look like a robot that does not move).
"""

import argparse
import math
import select
import sys
import termios
import time
import tty

try:  # without the [ros2] extra: one line naming it, not a traceback
    import rclpy
    from geometry_msgs.msg import Twist
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("examples/ros2_teleop.py", "ros2")

try:  # corobot_drake's one-line check of ROS 2's environment variables
    from corobot_drake.ros2.graph import refuse_unusable
except ImportError:  # a ROS 2 install without corobot_drake: rcl's own errors

    def refuse_unusable(program: str) -> None:
        """(corobot_drake is not installed here)"""


MOVES = {"i": (1, 0), ",": (-1, 0), "j": (0, 1), "l": (0, -1), "u": (1, 1), "o": (1, -1),
         "m": (-1, -1), ".": (-1, 1), "k": (0, 0), " ": (0, 0)}
"""key: (forward, turn) as signs of the linear and angular speeds (teleop_twist_keyboard's)."""
SCALES = {"q": 1.1, "z": 0.9}
REPEAT = 0.1
"""s between Twists while a move is on (well inside the simulation's 0.5 s deadman)."""
TIMEOUT = 30.0
"""s (wall clock) to wait for the simulation's /cmd_vel subscription (discovery takes a few
seconds)."""


def read_key(timeout: float) -> str | None:
    """One key from the terminal (raw mode), None if none came within `timeout` s."""
    ready, _, _ = select.select([sys.stdin], [], [], timeout)
    return sys.stdin.read(1) if ready else None


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--robot", default="", help="the robot's namespace (several robots)")
    p.add_argument("--speed", type=float, default=0.3, help="m/s (default 0.3)")
    p.add_argument("--turn", type=float, default=1.0, help="rad/s (default 1.0)")
    p.add_argument("--timeout", type=float, default=TIMEOUT,
                   help=f"s to wait for the simulation's /cmd_vel (default {TIMEOUT:g})")
    args = p.parse_args(argv)
    if not (math.isfinite(args.timeout) and args.timeout > 0):
        p.error(f"--timeout: a number of s > 0; got {args.timeout}")
    refuse_unusable("examples/ros2_teleop.py")  # before any DDS
    if not sys.stdin.isatty():
        print("error: ros2_teleop.py reads keys from a terminal", file=sys.stderr)
        return 2
    rclpy.init()
    node = rclpy.create_node("corobot_teleop")
    topic = f"/{args.robot}/cmd_vel" if args.robot else "/cmd_vel"
    publisher = node.create_publisher(Twist, topic, 10)
    deadline = time.monotonic() + args.timeout
    while publisher.get_subscription_count() == 0:  # the graph fills as discovery goes
        if time.monotonic() >= deadline:
            print(f"error: no subscriber on {topic} in {args.timeout:g} s (is `python -m "
                  "corobot_drake --ros2` running in this ROS_DOMAIN_ID?)", file=sys.stderr)
            node.destroy_node()
            rclpy.try_shutdown()
            return 1
        time.sleep(0.1)
    speed, turn, move = args.speed, args.turn, (0, 0)
    saved = termios.tcgetattr(sys.stdin)
    print(__doc__.split("\n\n")[1])
    try:
        tty.setcbreak(sys.stdin.fileno())
        while True:
            key = read_key(REPEAT)
            if key == "\x03":
                break
            if key in MOVES:
                move = MOVES[key]
            elif key in SCALES:
                speed, turn = speed * SCALES[key], turn * SCALES[key]
                print(f"\rspeed {speed:.2f} m/s  turn {turn:.2f} rad/s   ", end="", flush=True)
            if move != (0, 0) or key in MOVES:
                twist = Twist()
                twist.linear.x, twist.angular.z = move[0] * speed, move[1] * turn
                publisher.publish(twist)
    except KeyboardInterrupt:
        pass
    finally:
        termios.tcsetattr(sys.stdin, termios.TCSADRAIN, saved)
        publisher.publish(Twist())  # stop
        node.destroy_node()
        rclpy.try_shutdown()
        print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
