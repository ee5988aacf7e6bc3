"""What `--rosbag` and `--ros2` cost (`tools/bench_ros2.py`).

`headless_run(kind, seconds, out_dir)` simulates the default scene (IR and camera on, 30 Hz,
the robot driving a circle) for `seconds` as fast as it can, as `python -m corobot_drake
--headless` does: plain, with the ROS 2 topics written to a rosbag2 (`rosbag`), published by
the live node (`ros2`: serialized and handed to Fast DDS, no subscriber), or both. The wall
time counts the run and the bag's closing, not the diagram's build.

`realtime_run(seconds)` runs the scene in real time as `--ros2` does (a `SimRunner`, the node
attached, camera at 30 Hz) for `seconds` of wall clock with a subscriber of its own to the
camera and /odom in the process (the node's messages really go out), and returns the runner's
figures: the real-time factor held and the slips. DDS runs in a private network namespace
when one can be made (root), as in the tests; else on LOCALHOST discovery.
"""

from __future__ import annotations

import contextlib
import threading
import time
import types
from functools import partial
from pathlib import Path

from corobot_drake.config.scenario import load_scenario
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.simulation import Simulation, quiet_drake_warnings

CIRCLE = "robots: {corobot: {commands: [!SetPower {left: 0.4, right: 0.8}]}}"
KINDS = ("plain", "rosbag", "ros2", "ros2+rosbag")


@contextlib.contextmanager
def dds_network():
    """A private network namespace if one can be made, else nothing (LOCALHOST discovery)."""
    from corobot_drake.ros2.graph import PrivateNetworkError, configure_discovery, private_network

    configure_discovery()
    stack = contextlib.ExitStack()
    with contextlib.suppress(PrivateNetworkError):
        stack.enter_context(private_network())
    with stack:
        yield


def headless_run(kind: str, seconds: float, out_dir: str | Path) -> tuple[float, float]:
    """(wall seconds, CPU seconds of the process's threads) of one run of `kind` (one of
    `KINDS`). The CPU time is the steadier figure on a shared machine (the wall time counts
    the other processes' turns too)."""
    from corobot_drake.ros2.bag import BagSink
    from corobot_drake.ros2.bus import Bus
    from corobot_drake.ros2.publishers import add_ros2_topics

    quiet_drake_warnings()
    with contextlib.ExitStack() as stack:
        sinks = []
        if "rosbag" in kind:
            bag = BagSink(Path(out_dir) / f"{kind}-{time.monotonic_ns()}")
            sinks.append(bag)
        if "ros2" in kind.split("+"):
            from corobot_drake.ros2.node import Ros2Node

            node = Ros2Node()
            stack.callback(node.close)
            sinks.append(node.sink)
        extras = [partial(add_ros2_topics, Bus(sinks))] if sinks else []
        sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[CIRCLE]), extras=extras)
        start, cpu = time.perf_counter(), time.process_time()
        sim.advance(seconds)
        if "rosbag" in kind:
            bag.close()
        return time.perf_counter() - start, time.process_time() - cpu


def realtime_run(seconds: float, ros2: bool = True) -> dict:
    """The runner's stats after `seconds` of wall clock in real time (camera at 30 Hz), with
    the ROS 2 node attached and a subscriber to /camera/image_raw and /odom (or, without
    `ros2`, the plain runner): its `realtime_factor`, `slips` and messages received."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import qos_profile_sensor_data

    from corobot_drake.ros2.graph import ros_type
    from corobot_drake.ros2.run import Ros2Front
    from corobot_drake.serving.runner import SimRunner

    quiet_drake_warnings()
    scenario = load_scenario(DEFAULT_SCENARIO, overrides=[CIRCLE])

    flags = types.SimpleNamespace(ros2=ros2, ros2_network=False, rosbag=None)  # as parsed
    received = [0]
    with Ros2Front(flags, list(scenario.robots)) as front:
        runner = SimRunner(lambda: Simulation(scenario, extras=front.extras if ros2 else ()))
        if ros2:
            front.attach(runner)
            context = rclpy.Context()
            rclpy.init(context=context)
            listener = rclpy.create_node("bench_listener", context=context)
            for topic, msgtype in (("/camera/image_raw", "sensor_msgs/msg/Image"),
                                   ("/odom", "nav_msgs/msg/Odometry")):
                listener.create_subscription(ros_type(msgtype), topic,
                                             lambda m: received.__setitem__(0, received[0] + 1),
                                             qos_profile_sensor_data)
            executor = SingleThreadedExecutor(context=context)
            executor.add_node(listener)
            spinner = threading.Thread(target=executor.spin, daemon=True)
            spinner.start()
        runner.start()
        time.sleep(seconds)  # the wall-clock span measured
        stats = runner.stats()
        runner.stop()
        if ros2:
            executor.shutdown(timeout_sec=5.0)
            spinner.join(5)
            listener.destroy_node()
            rclpy.try_shutdown(context=context)
    return {"realtime_factor": stats["realtime_factor"], "slips": stats["slips"],
            "received": received[0]}
