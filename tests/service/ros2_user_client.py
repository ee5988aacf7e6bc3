"""A ROS 2 user's node against `python -m corobot_drake --ros2`, run by a Python that has only
ROS 2's wheels and the interface packages built from the clone (tools/setup's .venv-ros), never
corobot_drake: tests/service/test_ros2_user.py runs it.

    .venv-ros/bin/python tests/service/ros2_user_client.py PLAN.json

The plan (JSON) names the node, its topics ({name: type}, the node's own table), an RViz
config whose displays it subscribes to as RViz would, the velocity topic and the calls to make
in order (services with their request's fields, actions with their goal's). It subscribes to
every topic as foxglove_bridge does (each topic's QoS from its publishers' offers) and to each
RViz display's topic with the display's QoS (tf2_ros's for /tf and /tf_static), drives,
makes each call, and prints what it got as one JSON object on stdout. A wait is bounded by the
plan's `timeout` (s, wall clock); what did not come is reported, not raised.
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import sys
import threading
import time

import rclpy
import yaml
from rclpy.action import ActionClient
from rclpy.executors import MultiThreadedExecutor
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

FOXGLOVE_MAX_DEPTH = 25
"""foxglove_bridge's `max_qos_depth` default: a subscription's depth is its publishers'
depths summed, at most this (and at least 1: Fast DDS's graph gives another process's
publisher depth 0)."""
TF2_DEPTH = 100
"""tf2_ros's TransformListener: /tf reliable volatile, /tf_static reliable transient local,
keep last 100 (DynamicListenerQoS, StaticListenerQoS)."""
RVIZ_TF_DISPLAY = "rviz_default_plugins/TF"
VELOCITY_PERIOD = 0.05
"""s between /cmd_vel messages while driving (20 Hz, a teleop's rate)."""
RETRY = 5.0
"""s (wall clock) an idempotent service call waits before asking again: Fast DDS drops an
answer sent before the server has matched the client's reader."""


def ros_type(name: str):
    """The class of `package/msg/Name` (or srv, action)."""
    package, kind, cls = name.split("/")
    return getattr(importlib.import_module(f"{package}.{kind}"), cls)


def fill(message, fields: dict):
    """`message` with `fields` set, nested dicts into nested messages (as `ros2 service call`'s
    YAML)."""
    for key, value in fields.items():
        if isinstance(value, dict):
            fill(getattr(message, key), value)
        else:
            setattr(message, key, value)
    return message


def as_data(value, limit: int = 64):
    """A message as JSON data (fields by name; a long array cut to `limit` items)."""
    if hasattr(value, "get_fields_and_field_types"):
        return {f: as_data(getattr(value, f), limit) for f in value.get_fields_and_field_types()}
    if isinstance(value, (list, tuple)) or hasattr(value, "tolist"):
        items = list(value)
        return [as_data(v, limit) for v in items[:limit]]
    if isinstance(value, (bytes, bytearray)):
        return value.hex()[:limit]
    if isinstance(value, float) and value != value:
        return "nan"
    if isinstance(value, float) and value in (float("inf"), float("-inf")):
        return str(value)
    return value


def profile_data(qos: QoSProfile) -> dict:
    return {"reliability": qos.reliability.name.lower(),
            "durability": qos.durability.name.lower(), "depth": qos.depth}


def foxglove_qos(node, topic: str) -> QoSProfile:
    """foxglove_bridge's subscription QoS for `topic` (its subscribeHandler, as `ros2 topic
    echo`): reliable if every publisher offers reliable, transient local if every publisher
    offers it, keep last the publishers' depths summed (1 to `FOXGLOVE_MAX_DEPTH`)."""
    offers = [p.qos_profile for p in node.get_publishers_info_by_topic(topic)]
    depth = min(FOXGLOVE_MAX_DEPTH, sum(q.depth for q in offers))
    reliable = bool(offers) and all(q.reliability == ReliabilityPolicy.RELIABLE for q in offers)
    latched = bool(offers) and all(q.durability == DurabilityPolicy.TRANSIENT_LOCAL
                                   for q in offers)
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=max(depth, 1),
                      reliability=ReliabilityPolicy.RELIABLE if reliable
                      else ReliabilityPolicy.BEST_EFFORT,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if latched
                      else DurabilityPolicy.VOLATILE)


def rviz_subscriptions(path: str) -> list[tuple[str, str, QoSProfile]]:
    """(display name, topic, QoS) of each enabled display of an RViz config: a display's
    Topic (or Description Topic) with its Reliability, Durability and Depth as saved; the TF
    display's tf2_ros listener's two."""
    with open(path) as f:
        config = yaml.safe_load(f)
    out = []
    for display in config["Visualization Manager"]["Displays"]:
        if not display.get("Enabled", True):
            continue
        if display["Class"] == RVIZ_TF_DISPLAY:
            out += [(display["Name"], "/tf", QoSProfile(depth=TF2_DEPTH)),
                    (display["Name"], "/tf_static", QoSProfile(
                        depth=TF2_DEPTH, durability=DurabilityPolicy.TRANSIENT_LOCAL))]
        topic = display.get("Topic") or display.get("Description Topic")
        if isinstance(topic, dict):
            out.append((display["Name"], topic["Value"], QoSProfile(
                history=HistoryPolicy.KEEP_LAST, depth=int(topic["Depth"]),
                reliability=ReliabilityPolicy[topic["Reliability Policy"].upper()
                                              .replace(" ", "_")],
                durability=DurabilityPolicy[topic["Durability Policy"].upper()
                                            .replace(" ", "_")])))
    return out


class User:
    """The user's node: its subscriptions' counts, its clients, an executor thread."""

    def __init__(self, plan: dict):
        self.plan, self.timeout = plan, float(plan["timeout"])
        rclpy.init()
        self.node = rclpy.create_node("ros2_user")
        self._changed = threading.Condition()
        self.subscriptions: list[dict] = []
        self.latest: dict[str, object] = {}
        # Every client first: by the time each is used its server has matched it.
        self.clients = {c["name"]: (ActionClient if c["kind"] == "action" else
                                    self.node.create_client)(*self._client_args(c))
                        for c in plan["calls"]}
        self.cmd_vel = self.node.create_publisher(ros_type(plan["cmd_vel"][1]),
                                                  plan["cmd_vel"][0], 10)
        self.executor = MultiThreadedExecutor()
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self.executor.spin, daemon=True)
        self._thread.start()

    def _client_args(self, call: dict) -> tuple:
        if call["kind"] == "action":
            return self.node, ros_type(call["type"]), call["name"]
        return ros_type(call["type"]), call["name"]

    def wait(self, condition, timeout: float | None = None) -> bool:
        """Whether `condition()` came true within `timeout` s (the plan's by default)."""
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        with self._changed:
            while not condition():
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._changed.wait(min(left, 0.1))  # the graph changes without a notify
        return True

    def discover(self) -> dict:
        """Waits for the node and every topic of its table among its publishers: the graph's
        view of what the node publishes, offers included."""
        name = self.plan["node"]
        wanted = set(self.plan["topics"])

        def published() -> dict:
            if name not in self.node.get_node_names():
                return {}
            return dict(self.node.get_publisher_names_and_types_by_node(name, "/"))

        self.wait(lambda: wanted <= set(published()))
        return {topic: types for topic, types in sorted(published().items())}

    def subscribe(self, topic: str, msgtype: str, qos: QoSProfile, via: str) -> None:
        record = {"topic": topic, "via": via, "qos": profile_data(qos), "received": 0}

        def on_message(msg):
            with self._changed:
                record["received"] += 1
                self.latest[topic] = msg
                if topic in ("/tf", "/tf_static"):
                    record.setdefault("frames", set()).update(
                        (t.header.frame_id, t.child_frame_id) for t in msg.transforms)
                self._changed.notify_all()

        self.node.create_subscription(ros_type(msgtype), topic, on_message, qos)
        self.subscriptions.append(record)

    def drive(self, linear: float, seconds: float) -> None:
        """/cmd_vel at `linear` m/s for `seconds` s of wall clock, then a zero velocity."""
        twist = ros_type(self.plan["cmd_vel"][1])()
        self.wait(lambda: self.cmd_vel.get_subscription_count() > 0)
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            twist.linear.x = linear
            self.cmd_vel.publish(twist)
            time.sleep(VELOCITY_PERIOD)
        twist.linear.x = 0.0
        self.cmd_vel.publish(twist)

    def call(self, call: dict) -> dict:
        """One service call or action goal: what came back (or what did not)."""
        start = time.monotonic()
        out = self._send_goal(call) if call["kind"] == "action" else self._call_service(call)
        out.update(name=call["name"], type=call["type"],
                   seconds=round(time.monotonic() - start, 3))
        return out

    def _future(self, future, timeout: float):
        done = threading.Event()
        future.add_done_callback(lambda f: done.set())
        return future.result() if done.wait(timeout) else None

    def _call_service(self, call: dict) -> dict:
        client = self.clients[call["name"]]
        if not client.wait_for_service(timeout_sec=self.timeout):
            return {"answered": False, "why": "service not discovered"}
        request = fill(ros_type(call["type"]).Request(), call.get("request", {}))
        deadline = time.monotonic() + self.timeout
        while time.monotonic() < deadline:
            wait = RETRY if call.get("idempotent") else deadline - time.monotonic()
            future = client.call_async(request)
            response = self._future(future, min(wait, deadline - time.monotonic()))
            if response is not None:
                return {"answered": True, "response": as_data(response)}
            client.remove_pending_request(future)
        return {"answered": False, "why": f"no answer in {self.timeout} s"}

    def _send_goal(self, call: dict) -> dict:
        client = self.clients[call["name"]]
        if not client.wait_for_server(timeout_sec=self.timeout):
            return {"answered": False, "why": "action server not discovered"}
        feedback = []

        def on_feedback(message):
            with self._changed:
                feedback.append(as_data(message.feedback))
                self._changed.notify_all()

        goal = fill(ros_type(call["type"]).Goal(), call.get("goal", {}))
        handle = self._future(client.send_goal_async(goal, feedback_callback=on_feedback),
                              self.timeout)
        if handle is None:
            return {"answered": False, "why": "no answer to the goal"}
        if not handle.accepted:
            return {"answered": True, "accepted": False}
        result = self._future(handle.get_result_async(), self.timeout)
        if result is None:
            return {"answered": False, "accepted": True, "why": "no result"}
        # (A feedback handed on after the result is dropped by rclpy's ActionClient, which
        # forgets the goal's feedback callback with its result: the last ones may be missing.)
        return {"answered": True, "accepted": True, "status": result.status,
                "result": as_data(result.result), "feedback": feedback[:50],
                "feedback_count": len(feedback)}

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=5.0)
        self._thread.join(5.0)
        for client in self.clients.values():
            if isinstance(client, ActionClient):
                client.destroy()
        self.node.destroy_node()
        rclpy.try_shutdown()


def position(user: User, topic: str):
    msg = user.latest.get(topic)
    return None if msg is None else [msg.pose.pose.position.x, msg.pose.pose.position.y]


def environment() -> dict:
    """Where this Python's ROS comes from, and whether the project is within its reach."""
    with open("/proc/self/maps") as f:
        maps = f.read().split()
    return {"python": sys.prefix, "rclpy": rclpy.__file__,
            "librcl": sorted({p for p in maps if p.endswith("/librcl.so")}),
            "corobot_drake": importlib.util.find_spec("corobot_drake") is not None,
            "pydrake": importlib.util.find_spec("pydrake") is not None}


def run(plan: dict) -> dict:
    user = User(plan)
    try:
        report = {"environment": environment(), "published": user.discover()}
        for topic, msgtype in plan["topics"].items():
            user.subscribe(topic, msgtype, foxglove_qos(user.node, topic), "foxglove_bridge")
        for display, topic, qos in rviz_subscriptions(plan["rviz"]):
            user.subscribe(topic, plan["topics"].get(topic, "unknown/msg/Unknown"), qos,
                           f"rviz:{display}")
        everything = lambda: all(s["received"] > 0 for s in user.subscriptions)  # noqa: E731
        user.wait(everything)
        drive = plan["drive"]
        report["before"] = position(user, drive["pose_topic"])
        user.drive(drive["linear"], drive["seconds"])
        report["after"] = position(user, drive["pose_topic"])
        report["calls"] = [user.call(call) for call in plan["calls"]]
        with user._changed:  # the callbacks go on meanwhile
            report["subscriptions"] = [
                {**s, "frames": sorted(s["frames"])} if "frames" in s else dict(s)
                for s in user.subscriptions]
        return report
    finally:
        user.close()


if __name__ == "__main__":
    with open(sys.argv[1]) as f:
        print(json.dumps(run(json.load(f))))
