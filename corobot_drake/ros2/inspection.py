"""`python -m corobot_drake.ros2 list | echo TOPIC | hz TOPIC`: a look at the running node's
topics for users without a ROS install (what `ros2 topic list / echo / hz` do).

Discovery as the node's (`graph.configure_discovery`: this machine unless
ROS_AUTOMATIC_DISCOVERY_RANGE or `--network` says otherwise), in ROS_DOMAIN_ID. A subscription
asks for the QoS its publisher offers (a best-effort sensor stream, a latched /tf_static).

`--timeout` bounds each command (echo, hz: the listening, after discovery's `--wait`), and a
watchdog ends it with a line naming what it was waiting for should ROS 2 itself not answer (a
starved machine): it never hangs.

Exit status: 0; 1 when the topic or the node is not found within `--wait` s, or too few
messages came by `--timeout`; 2 for bad arguments or a bad ROS 2 environment (one line).
"""

from __future__ import annotations

import argparse
import contextlib
import itertools
import math
import os
import sys
import threading
import time

DEFAULT_WAIT = 10.0
"""s to wait for discovery (0.3-4.5 s on one machine) before saying the topic is not there."""
INSPECT_NODE = "corobot_drake_inspect"
"""The tool's own node (its parameter services are left out of `list`)."""
HZ_REPORT = 1.0
"""s (wall clock) between `hz`'s lines."""
STAGE_GRACE = 30.0
"""s (wall clock) ROS 2 gets beyond a stage's own limit (starting, closing: rclpy calls that
wait on DDS) before the watchdog ends the tool."""


class _ArgumentParser(argparse.ArgumentParser):
    def error(self, message):
        self.exit(2, f"error: {message}\n")


def _seconds(text: str) -> float:
    """An argparse type: a finite number of s >= 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"a number of s >= 0; got {text!r}") from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"a number of s >= 0; got {text}")
    return value


def _count(text: str) -> int:
    """An argparse type: a whole number >= 0."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"a whole number >= 0; got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"a whole number >= 0; got {text}")
    return value


def topic_problem(topic: str) -> str | None:
    """Why `topic` is not a ROS 2 topic name (rcl's rules), else None."""
    from rclpy.expand_topic_name import expand_topic_name
    from rclpy.validate_full_topic_name import validate_full_topic_name
    from rclpy.validate_topic_name import validate_topic_name

    try:
        validate_topic_name(topic)
        validate_full_topic_name(expand_topic_name(topic, INSPECT_NODE, "/"))
    except Exception as e:  # rclpy's InvalidTopicNameException (several lines), ValueError
        first = str(e).splitlines()[0].removeprefix("Invalid topic name: ").rstrip(":")
        return first.split(" is invalid: ")[-1].split(", at ")[0]
    return None


def _parser() -> argparse.ArgumentParser:
    p = _ArgumentParser(prog="python -m corobot_drake.ros2",
                        description=__doc__.split("\n\n")[0])
    p.add_argument("--wait", type=_seconds, default=DEFAULT_WAIT,
                   help=f"s to wait for discovery (default {DEFAULT_WAIT:g})")
    p.add_argument("--timeout", type=_seconds, default=None,
                   help="list: s it waits at most; echo, hz: s of listening once the topic is "
                   "found, then they report what came (default: until -n messages or Ctrl-C)")
    p.add_argument("--network", action="store_true",
                   help="discover on the local network (SUBNET), not this machine only")
    sub = p.add_subparsers(dest="command", required=True)
    listing = sub.add_parser("list", help="the topics, services and actions, with their types")
    listing.add_argument("--timeout", type=_seconds, default=argparse.SUPPRESS,
                         help="s the listing takes at most (default: its discovery waits)")
    echo = sub.add_parser("echo", help="print a topic's messages (YAML)")
    echo.add_argument("topic")
    echo.add_argument("--count", "-n", type=_count, default=0,
                      help="stop after this many messages (default: until Ctrl-C)")
    echo.add_argument("--timeout", type=_seconds, default=argparse.SUPPRESS,
                      help="stop after this many s (default: until Ctrl-C)")
    hz = sub.add_parser("hz", help="a topic's rate: messages per second of wall clock and "
                                   "of simulation time (from their stamps)")
    hz.add_argument("topic")
    hz.add_argument("--count", "-n", type=_count, default=0,
                    help="stop after this many messages (default: until Ctrl-C)")
    hz.add_argument("--timeout", type=_seconds, default=argparse.SUPPRESS,
                    help="stop after this many s (default: until Ctrl-C)")
    return p


class _Watchdog:
    """Ends the process (`exit`) with a line naming what it waited for when a stage outlasts
    its limit: an rclpy call that never returns on a starved machine must not hang the tool.
    The results printed so far stay (stdout is flushed first)."""

    def __init__(self, exit=os._exit):
        self._exit = exit
        self._timer: threading.Timer | None = None

    def stage(self, what: str, limit: float | None, status: int = 1) -> None:
        """From now on: waiting for `what`, at most `limit` s (None: no limit)."""
        self.stop()
        if limit is not None:
            self._timer = threading.Timer(limit, self._expired, (what, limit, status))
            self._timer.daemon = True
            self._timer.start()

    def stop(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def _expired(self, what: str, limit: float, status: int) -> None:
        with contextlib.suppress(Exception):
            sys.stdout.flush()
        print(f"error: still waiting for {what} after {limit:g} s (a starved machine?): "
              "stopped", file=sys.stderr, flush=True)
        self._exit(status)


class _Session:
    """An rclpy context and node of the tool's own, spinning in a thread."""

    def __init__(self):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor

        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node(INSPECT_NODE, context=self.context)
        self._executor = SingleThreadedExecutor(context=self.context)
        self._executor.add_node(self.node)
        self._thread = threading.Thread(target=self._executor.spin, daemon=True)
        self._thread.start()

    def close(self) -> None:
        import rclpy

        self._executor.shutdown(timeout_sec=2.0)
        self._thread.join(2.0)
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)

    def wait_for(self, found, wait: float):
        """`found()` once it returns something (polled as the graph fills), else None."""
        deadline = time.monotonic() + wait
        while True:
            value = found()
            if value or time.monotonic() >= deadline:
                return value
            time.sleep(0.1)

    def topic_type(self, topic: str, wait: float) -> str | None:
        """The type its publishers offer, once one is discovered (a subscriber alone, another
        tool's, says nothing of the QoS to ask for)."""
        def lookup():
            infos = self.node.get_publishers_info_by_topic(topic)
            return infos[0].topic_type if infos else None
        return self.wait_for(lookup, wait)

    def offered_qos(self, topic: str):
        """The QoS to subscribe with: its publishers' reliability and durability, depth 10."""
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

        infos = self.node.get_publishers_info_by_topic(topic)
        best_effort = any(i.qos_profile.reliability == ReliabilityPolicy.BEST_EFFORT
                          for i in infos)
        latched = infos and all(i.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL
                                for i in infos)
        return QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT if best_effort
                          else ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.TRANSIENT_LOCAL if latched
                          else DurabilityPolicy.VOLATILE)


def _list(session: _Session, args, out) -> int:
    from corobot_drake.ros2.interfaces import NODE_NAME

    found = session.wait_for(lambda: NODE_NAME in session.node.get_node_names(),
                             _left(args, args.wait))
    if not found:
        print(f"error: no node /{NODE_NAME} found in {args.wait:g} s (is `python -m "
              "corobot_drake --ros2` running in this ROS_DOMAIN_ID?)", file=sys.stderr)
        return 1
    # Its topics, services and actions appear over a moment after the node itself.
    session.wait_for(lambda: any(n.endswith("/_action/status") for n, _ in
                                 session.node.get_topic_names_and_types()),
                     _left(args, args.wait))
    topics = session.node.get_topic_names_and_types()
    actions = sorted(n.removesuffix("/_action/status") for n, _ in topics
                     if n.endswith("/_action/status"))
    print("topics:", file=out)
    for name, types in sorted(topics):
        if "/_action/" not in name:
            print(f"  {name} [{', '.join(types)}]", file=out)
    print("services:", file=out)
    for name, types in sorted(session.node.get_service_names_and_types()):
        if "/_action/" not in name and not name.startswith((f"/{NODE_NAME}/",
                                                             f"/{INSPECT_NODE}/")):
            print(f"  {name} [{', '.join(types)}]", file=out)
    print("actions:", file=out)
    for name in actions:
        print(f"  {name}", file=out)
    return 0


def _subscribe(session: _Session, args, on_message, raw: bool = False) -> bool:
    from corobot_drake.ros2.graph import ros_type

    msgtype = session.topic_type(args.topic, args.wait)
    if msgtype is None:
        print(f"error: no topic {args.topic} found in {args.wait:g} s (`python -m "
              "corobot_drake.ros2 list` shows them)", file=sys.stderr)
        return False
    session.node.create_subscription(ros_type(msgtype), args.topic, on_message,
                                     session.offered_qos(args.topic), raw=raw)
    return True


def _left(args, wait: float | None = None) -> float | None:
    """s left of `wait` and of `--timeout` (counted from the start), None if neither."""
    left = None if args.deadline is None else max(0.0, args.deadline - time.monotonic())
    return wait if left is None else left if wait is None else min(wait, left)


def _until(done: threading.Event, timeout: float | None, report=None) -> None:
    """Waits for `done`, Ctrl-C or `timeout` s (None: no limit), calling `report()` every
    `HZ_REPORT` s if given."""
    end = None if timeout is None else time.monotonic() + timeout
    try:
        while not done.wait(HZ_REPORT if end is None else
                            max(0.0, min(HZ_REPORT, end - time.monotonic()))):
            if end is not None and time.monotonic() >= end:
                return
            if report is not None:
                report()
    except KeyboardInterrupt:
        pass


def _echo(session: _Session, args, out) -> int:
    import yaml

    from corobot_drake.ros2.graph import as_data

    done, seen = threading.Event(), [0]

    def on_message(msg):
        if done.is_set():
            return
        try:
            print(yaml.safe_dump(as_data(msg), sort_keys=False).rstrip() + "\n---", file=out,
                  flush=True)
        except BrokenPipeError:  # `| head` had enough
            done.set()
            return
        seen[0] += 1
        if args.count and seen[0] >= args.count:
            done.set()

    if not _subscribe(session, args, on_message):
        return 1
    _until(done, args.timeout)
    return _enough(args, seen[0], 1)


def _enough(args, received: int, needed: int) -> int:
    """0, or 1 with an error line when fewer than `needed` messages arrived (by the timeout
    or Ctrl-C): a silent exit 0 would read as a topic that works."""
    if received < needed:
        when = "before Ctrl-C" if args.timeout is None else f"in {args.timeout:g} s"
        print(f"error: {received} message(s) on {args.topic} {when} ({needed} needed)",
              file=sys.stderr)
        return 1
    return 0


def _hz(session: _Session, args, out) -> int:
    lock, done = threading.Lock(), threading.Event()
    arrivals: list[tuple[float, float | None]] = []  # (wall s, stamp s or None)

    def on_message(msg):
        stamp = getattr(getattr(msg, "header", None), "stamp", None) or getattr(
            msg, "clock", None)
        with lock:
            if args.count and len(arrivals) >= args.count:
                return  # counted: one arriving before the report must not change it
            arrivals.append((time.monotonic(), None if stamp is None
                             else stamp.sec + 1e-9 * stamp.nanosec))
            if args.count and len(arrivals) >= args.count:
                done.set()

    def report():
        with lock:
            if len(arrivals) < 2:
                return
            (w0, s0), (w1, s1) = arrivals[0], arrivals[-1]
            stamps = [s for _, s in arrivals if s is not None]
            n = len(arrivals) - 1
        line = f"{args.topic}: {n / (w1 - w0):.1f} Hz (wall clock)"
        if s0 is not None and s1 is not None and s1 > s0:
            line += f", {n / (s1 - s0):.1f} per simulated s"
        line += f" over {n + 1} messages"
        # A best-effort stream drops messages under load; the closest two stamps still show
        # the publishing period.
        gaps = [b - a for a, b in itertools.pairwise(stamps) if b > a]
        if gaps:
            line += f", stamps {1e3 * min(gaps):.1f} ms apart at the closest"
        print(line, file=out, flush=True)

    if not _subscribe(session, args, on_message):
        return 1
    _until(done, args.timeout, report)
    report()
    with lock:
        received = len(arrivals)
    return _enough(args, received, 2)  # a rate needs two


def main(argv: list[str] | None = None, out=None) -> int:
    args = _parser().parse_args(argv)
    out = out or sys.stdout
    from corobot_drake.ros2.graph import configure_discovery
    from corobot_drake.ros2.run import missing

    problem = missing("python -m corobot_drake.ros2", live=True)
    if problem is None and args.command != "list":
        problem = topic_problem(args.topic)
        problem = problem and f"{args.command}: {args.topic}: not a topic name ({problem})"
        if not problem:  # as rclpy resolves it (`odom`: /odom), for the lines that name it
            from rclpy.expand_topic_name import expand_topic_name

            args.topic = expand_topic_name(args.topic, INSPECT_NODE, "/")
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    # list: its discovery waits within --timeout; echo, hz: --timeout s of listening, once
    # the topic is found (within --wait)
    if args.command == "list" and args.timeout is not None:
        args.wait = min(args.wait, args.timeout)
    args.deadline = (time.monotonic() + args.timeout
                     if args.command == "list" and args.timeout is not None else None)
    configure_discovery(args.network)
    watchdog = _Watchdog()
    watchdog.stage("ROS 2 to start (rclpy.init, the node)", STAGE_GRACE)
    session = _Session()
    status = 1
    try:
        # Each command's own waits are bounded (--wait, --timeout); the watchdog only ends
        # one whose rclpy calls stop answering.
        limit = (None if args.command != "list" and args.timeout is None
                 else 2 * args.wait + (args.timeout or 0.0) + STAGE_GRACE)
        watchdog.stage(f"`{args.command}` to finish", limit)
        status = {"list": _list, "echo": _echo, "hz": _hz}[args.command](session, args, out)
        return status
    finally:
        watchdog.stage("ROS 2 to shut down", STAGE_GRACE, status)
        session.close()
        watchdog.stop()
