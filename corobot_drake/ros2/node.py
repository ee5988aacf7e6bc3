"""The ROS 2 node `corobot_drake`: the bus's topics published live, and the robot's commands
taken from /cmd_vel, the actions and the services (`interfaces`).

Threads: the node spins in an executor thread of its own (a MultiThreadedExecutor: an action
waits for its command while others are served). Its callbacks never touch Drake: they hand
functions to the simulation thread through a `serving.runner.Runner` (`submit`, `watch`), the
HTTP server's way in (`serving.calls`), and wait on the futures. The topics are written from
the simulation thread, by the publishers' events (`publishers`), as serialized messages.
"""

from __future__ import annotations

import collections
import concurrent.futures
import contextlib
import dataclasses as dc
import logging
import math
import sys
import threading
import time
from functools import partial

import rclpy
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.clock import Clock, ClockType
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.time import Time

from corobot_drake import commands
from corobot_drake import limits as lim
from corobot_drake.config import scenario as sc
from corobot_drake.ros2 import diagnostics, parameters
from corobot_drake.ros2 import interfaces as ifc
from corobot_drake.ros2.graph import configure_discovery, ros_type
from corobot_drake.serving import calls
from corobot_drake.serving.runner import SimulationStoppedError
from corobot_drake.topics import robot_names

ANSWER_TIMEOUT = 10.0
"""s (wall clock) a service or a goal waits for the simulation thread to take its command."""
FEEDBACK_PERIOD = 0.1
"""s of simulated time between an action's feedback messages (at any rate the simulation
runs)."""
WAKE_PERIOD = 0.1
"""s (wall clock) a running goal waits at most for its end or its next feedback before it
looks for a cancel or the node's stop."""
SERVICE_SETTLE_TIMEOUT = 30.0
"""s (wall clock) /set_pose waits for the robot to settle at its new pose."""

BLOCKING_CALLBACKS_PER_ROBOT = len(ifc.ACTIONS) + 1
"""Callbacks that wait on the simulation, per robot: each action's running goal, /set_pose."""
SPAWNED_ROBOTS = 8
"""Robots the node takes beyond the scenario's (SpawnEntity): its executor keeps threads for
their blocking callbacks too (a thread pool makes a thread only when one is needed)."""
OTHER_CALLBACK_THREADS = 4
"""Executor threads for the quick callbacks (/cmd_vel, the services, the parameters)."""
REQUEST_QUEUE = 1000
"""Requests a service (and an action's goal, cancel and result services) keeps waiting:
the executor takes them one at a time, so a burst waits in this queue (ROS's default 10
dropped the rest of a burst unanswered); as rclpy's parameter services keep."""
YAW = lim.Range(math.radians(lim.YAW_DEG.low), math.radians(lim.YAW_DEG.high), unit="rad")
"""/set_pose's `yaw` (rad): the scenario command's yaw_deg range."""
NODE_STOPPED = "the node stopped (the simulation ended) before the goal did"
"""The reason of a goal still running when the node stops (aborted)."""
ROBOT_GONE = "the robot left the simulation (DeleteEntity, or a reset) before the goal ended"
"""The reason of a goal whose robot is deleted while it runs (aborted)."""
RESULT_GRACE = 1.0
"""s (wall clock) the node keeps serving after aborting the goals still running as it
stops, for their results to reach their clients (an rclpy task sends each)."""
GRAPH_CHECK_PERIOD = 2.0
"""s (wall clock) between looks for another node of the same name in the domain."""

_log = logging.getLogger(__name__)


def qos_profile(qos: ifc.Qos, sensor_qos: str = "reliable") -> QoSProfile:
    """The rclpy profile of a topic's offer (`interfaces.offer`: the one place it is said)."""
    o = ifc.offer(qos, sensor_qos)
    return QoSProfile(
        depth=o.depth,
        reliability=ReliabilityPolicy.RELIABLE if o.reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=(DurabilityPolicy.TRANSIENT_LOCAL if o.transient_local
                    else DurabilityPolicy.VOLATILE))


SERVICE_QOS = QoSProfile(depth=REQUEST_QUEUE, reliability=ReliabilityPolicy.RELIABLE)


CLOCK = f"/{ifc.TOPIC['clock'].name}"
"""/clock: the simulation publishes it, and the node takes its own clock from it."""
GLOBAL_TOPICS = frozenset(f"/{t.name}" for t in ifc.TOPICS if t.shared)
"""/clock, /tf and /tf_static: global whatever the node's namespace, as ROS tools expect."""


def relative(name: str) -> str:
    """A robot's topic, service or action relative to the node's namespace (`--ros-args -r
    __ns:=/sim` puts it under /sim; none: at the root, as before); the global topics stay."""
    return name if name in GLOBAL_TOPICS else name.lstrip("/")


class LiveSink:
    """A `bus.Bus` sink: publishes each serialized message on the node's publisher (made as
    the topic is declared; destroyed when it is forgotten, made again if it is used again)."""

    def __init__(self, node, sensor_qos: str = "reliable"):
        self._node = node
        self._sensor_qos = sensor_qos
        self._offers: dict = {}  # topic: (type, Qos)
        self._publishers: dict = {}

    def declare(self, topic: str, msgtype: str, qos: ifc.Qos) -> None:
        self._offers[topic] = (msgtype, qos)
        self._publisher(topic)

    def forget(self, topic: str) -> None:
        """`topic` is no longer published (a robot deleted): its publisher goes, and the topic
        leaves the ROS graph."""
        publisher = self._publishers.pop(topic, None)
        if publisher is not None:
            self._node.destroy_publisher(publisher)

    def _publisher(self, topic: str):
        publisher = self._publishers.get(topic)
        if publisher is None:
            msgtype, qos = self._offers[topic]
            publisher = self._publishers[topic] = self._node.create_publisher(
                ros_type(msgtype), relative(topic), qos_profile(qos, self._sensor_qos))
        return publisher

    def write(self, topic: str, data, t_ns: int) -> None:
        self._publisher(topic).publish(bytes(data))
        if topic == CLOCK:  # the node's own clock (`Ros2Node.own_clock`)
            self._node.get_clock().set_ros_time_override(
                Time(nanoseconds=t_ns, clock_type=ClockType.ROS_TIME))

    def watched(self, topic: str) -> bool:
        """Whether `topic` has a subscriber now (the graph as Fast DDS last saw it); /clock
        always: the node's own clock follows it (`write`)."""
        return topic == CLOCK or self._publisher(topic).get_subscription_count() > 0


@dc.dataclass
class _Twist:
    """The command a robot's latest /cmd_vel issued and the simulated time it was issued."""

    seq: int
    time: float


class Ros2Node:
    """The node; `sink` for the bus (before the simulation is built), `attach(runner,
    robots)` once the runner exists, `start()`, then `close()`."""

    def __init__(self, network: bool = False, domain_id: int | None = None,
                 ros_args: list[str] | tuple = ()):
        """`ros_args`: what followed `--ros-args` on the command line (remaps, a namespace,
        `-p` and `--params-file`), as rcl takes them; a parameter's bad value: ParameterError
        (one line), the node shut down."""
        self.discovery = configure_discovery(network)
        self.context = rclpy.Context()
        args = [ifc.NODE_NAME, "--ros-args", *ros_args] if ros_args else None
        rclpy.init(context=self.context, domain_id=domain_id, args=args)
        # Its clock is the simulation's (/clock, which it publishes): an action goal's stamp,
        # a log's, a result's expiry. `use_sim_time` true whatever the arguments say.
        self.node = parameters.make_node(ifc.NODE_NAME, self.context,
                                         [Parameter("use_sim_time", value=True)])
        self.own_clock()
        try:
            self.settings = parameters.declare(self.node)
        except parameters.ParameterError:
            self.node.destroy_node()
            rclpy.shutdown(context=self.context)
            raise
        self.deadman = float(self.node.get_parameter("cmd_vel_timeout").value)
        self.node.add_post_set_parameters_callback(self._on_parameters)
        self.sink = LiveSink(self.node, self.settings.sensor_qos)
        self.runner = None
        self._group = ReentrantCallbackGroup()
        self._twists: dict[str, _Twist] = {}
        self._executor: MultiThreadedExecutor | None = None
        self._thread: threading.Thread | None = None
        self._closing = threading.Event()
        self._servers: list = []
        self._first: tuple[str, ...] = ()  # the scenario's robots: they name the robots
        self._robot_entities: dict[str, list] = {}  # each robot's subscription, servers
        self._robots_lock = threading.Lock()
        self._goals = 0  # accepted and not yet ended (`_check_goal`, `_execute`)
        self._robot_goals: collections.Counter = collections.Counter()  # the same, by robot
        self._leaving: set[str] = set()  # robots whose goals end as they are removed
        self._goals_changed = threading.Condition()
        self._aborted_at_stop = threading.Event()
        self._namesakes = 1
        self._slips = 0  # the runner's, at the last /diagnostics
        self._cmd_vel_topics: dict[str, str] = {}  # robot: its /cmd_vel's full name
        self._other_types: set = set()  # (topic, type) reported
        self.node.create_timer(GRAPH_CHECK_PERIOD, self._check_graph, clock=wall_clock())

    def own_clock(self) -> None:
        """The node's clock is set as the simulation publishes /clock (`LiveSink.write`, in
        the simulation thread), not by rclpy's subscription to /clock, which goes: its
        callback, ~1 ms of the executor's each, nearly doubled the CPU time of a run at
        --rate max (100 a simulated second)."""
        for subscription in list(self.node.subscriptions):
            if subscription.topic_name == CLOCK:
                self.node.destroy_subscription(subscription)

    @property
    def log(self):
        return self.node.get_logger()

    def _on_parameters(self, changed) -> None:
        """A run-time parameter set (`parameters.declare` checked it)."""
        for p in changed:
            if p.name == "cmd_vel_timeout":
                self.deadman = float(p.value)

    # --- commands ---
    def attach(self, runner, robots) -> None:
        """Takes commands for `robots` (names, the scenario's order) through `runner`."""
        self.runner = runner
        self._first = tuple(robots)
        self.set_robots(robots)
        runner.hooks.append(self._check_deadman)
        self._diagnostics = self.node.create_publisher(
            ros_type(diagnostics.TOPIC[1]), f"/{diagnostics.TOPIC[0]}", 10)
        self.node.create_timer(diagnostics.PERIOD, self._publish_diagnostics,
                               callback_group=self._group, clock=wall_clock())
        from corobot_drake.ros2.simulation_services import SimulationServices

        self.simulation = SimulationServices(self, runner)
        """The ROS 2 Simulation Interfaces: play, pause, step, reset, entities, spawning."""

    @property
    def robot_capacity(self) -> int:
        """How many robots the node takes commands for at most (the scenario's, and
        `SPAWNED_ROBOTS` more)."""
        return len(self._first) + SPAWNED_ROBOTS

    def set_robots(self, robots) -> None:
        """Takes commands for `robots` from now on: a robot new to the node gets its
        /cmd_vel subscription, actions and services (named by `topics.robot_names`), one
        gone loses them (a spawn, a delete, a reset: the simulation's robots changed)."""
        with self._robots_lock:
            for robot in [r for r in self._robot_entities if r not in robots]:
                self._remove_robot(robot)
            for robot in robots:
                if robot not in self._robot_entities:
                    self._add_robot(robot)

    def _add_robot(self, robot: str) -> None:
        names = robot_names(robot, self._first)
        stamped = self.settings.cmd_vel_stamped
        subscription = self.node.create_subscription(
            ros_type(cmd_vel_type(stamped)), relative(names.topic(ifc.CMD_VEL[0])),
            partial(self._on_twist, robot, stamped), 10, callback_group=self._group)
        self._cmd_vel_topics[robot] = subscription.topic_name
        entities = [subscription]
        for action in ifc.ACTIONS:
            entities.append(ActionServer(
                self.node, ros_type(action.type), relative(names.topic(action.name)),
                execute_callback=partial(self._execute, robot, action),
                goal_callback=partial(self._check_goal, robot, action),
                cancel_callback=lambda goal: CancelResponse.ACCEPT,
                callback_group=self._group, goal_service_qos_profile=SERVICE_QOS,
                result_service_qos_profile=SERVICE_QOS,
                cancel_service_qos_profile=SERVICE_QOS))
        for service in ifc.SERVICES:
            entities.append(self.node.create_service(
                ros_type(service.type), relative(names.topic(service.name)),
                partial(self._service_handler(service), robot), qos_profile=SERVICE_QOS,
                callback_group=self._group))
        self._robot_entities[robot] = entities

    def _remove_robot(self, robot: str) -> None:
        """Its goals still running aborted (`_run_goal`) and their results sent, then its
        subscription, action servers and services destroyed (rclpy defers each while the
        executor uses it)."""
        self._leaving.add(robot)
        with self._goals_changed:  # each aborts within a feedback period
            running = self._robot_goals[robot] > 0
            self._goals_changed.wait_for(lambda: self._robot_goals[robot] == 0,
                                         ANSWER_TIMEOUT)
        if running:
            time.sleep(RESULT_GRACE)  # their results go out before their servers do
        self._leaving.discard(robot)
        subscription, *rest = self._robot_entities.pop(robot)
        self._cmd_vel_topics.pop(robot, None)
        self.node.destroy_subscription(subscription)
        for entity in rest:
            if isinstance(entity, ActionServer):
                entity.destroy()
            else:
                self.node.destroy_service(entity)

    def forget_commands(self, robot: str | None = None) -> None:
        """In the simulation thread: the deadman forgets `robot`'s latest /cmd_vel (every
        robot's: None), as a reset or the robot's deletion ends it."""
        if robot is None:
            self._twists.clear()
        else:
            self._twists.pop(robot, None)

    def _call(self, fn, timeout: float = ANSWER_TIMEOUT):
        """`fn(sim)` in the simulation thread; its result (or exception)."""
        return self.runner.submit(fn).result(timeout)

    def _on_twist(self, robot: str, stamped: bool, msg) -> None:
        if stamped:
            msg = msg.twist  # (its header: the sender's time and frame, base_link's)
        future = self.runner.submit(partial(self._issue_twist, robot, msg.linear.x,
                                            msg.angular.z))
        future.add_done_callback(partial(self._report, f"{robot}: cmd_vel"))

    def _report(self, what: str, future) -> None:
        error = future.exception() if not future.cancelled() else None
        if error is not None and not isinstance(error, SimulationStoppedError):
            self.log.warning(f"{what}: {error}", throttle_duration_sec=1.0)

    def _issue_twist(self, robot: str, linear: float, angular: float, sim) -> None:
        """In the simulation thread: SetVelocity, remembered for the deadman."""
        seq = sim.robot(robot).set_velocity(linear, angular)
        self._twists[robot] = _Twist(seq, sim.time)

    def _check_deadman(self, sim) -> None:
        """In the simulation thread, between steps: a robot whose latest command is still its
        latest Twist's, issued more than `deadman` s ago, gets an AllStop."""
        if not self.deadman:
            return
        for robot, twist in list(self._twists.items()):
            if robot in sim.robots and sim.time - twist.time <= self.deadman:
                continue
            del self._twists[robot]
            if robot not in sim.robots:  # deleted meanwhile
                continue
            last = sim.robot(robot).last_command()
            if last is not None and last.seq == twist.seq:
                sim.robot(robot).all_stop()

    def _check_graph(self) -> None:
        self._check_namesakes()
        self._check_cmd_vel_publishers()

    def _check_cmd_vel_publishers(self) -> None:
        """Reports, once each, a publisher of the other Twist type on a /cmd_vel: DDS never
        delivers its messages to this node's subscription (the types differ)."""
        expected = cmd_vel_type(self.settings.cmd_vel_stamped).replace("/msg/", "/")
        for topic in list(self._cmd_vel_topics.values()):
            for info in self.node.get_publishers_info_by_topic(topic):
                other = info.topic_type.replace("/msg/", "/")
                if other == expected or (topic, other) in self._other_types:
                    continue
                self._other_types.add((topic, other))
                self.log.warning(
                    f"{topic}: node {info.node_namespace.rstrip('/')}/{info.node_name} "
                    f"publishes {other}, this node takes {expected} (parameter "
                    f"cmd_vel_stamped: {str(self.settings.cmd_vel_stamped).lower()}): its "
                    "messages do not reach the robot")

    def _publish_diagnostics(self) -> None:
        """/diagnostics (`diagnostics`): the runner's real-time figures and each robot's."""
        try:
            values = self._call(lambda sim: diagnostics.sample(list(sim.robots), sim))
        except (SimulationStoppedError, TimeoutError):
            return  # stopping, or too busy to answer: the next look reports
        stats = {**self.runner.stats(), "paused": getattr(self.runner, "paused", False)}
        items = diagnostics.statuses(stats, values, self._slips)
        self._slips = int(stats.get("slips") or 0)
        self._diagnostics.publish(diagnostics.message(values["time"], items))

    def _check_namesakes(self) -> None:
        """Warns (a line on stderr) when another node of this one's name joins the domain:
        its commands and topics would mix with this one's."""
        me = (self.node.get_name(), self.node.get_namespace())
        namesakes = self.node.get_node_names_and_namespaces().count(me)
        if namesakes > self._namesakes:
            print(f"warning: ROS 2: {namesakes} nodes named {self.node.get_fully_qualified_name()}"
                  f" in ROS_DOMAIN_ID {self.context.get_domain_id()}: their topics, services "
                  "and actions mix (run each simulation in a ROS_DOMAIN_ID of its own)",
                  file=sys.stderr, flush=True)
        self._namesakes = max(namesakes, 1)

    # --- actions ---
    def _check_goal(self, robot: str, action: ifc.Action, goal) -> GoalResponse:
        """A goal whose command would be refused (a field out of its range) is rejected as it
        is sent, the reason logged (a GoalResponse carries none)."""
        arguments = {name: getattr(goal, name) for name in ifc.goal_fields(action.command)}
        try:
            commands.make(action.call, **arguments)
        except (ValueError, TypeError) as e:
            self.log.warning(f"{robot}: {action.name} goal rejected: {e}")
            return GoalResponse.REJECT
        # Counted from here, not from `_execute`: rclpy answers "accepted" before its executor
        # starts the execute callback, and a stop in between must still wait for the goal.
        with self._goals_changed:
            self._goals += 1
            self._robot_goals[robot] += 1
        return GoalResponse.ACCEPT

    @contextlib.contextmanager
    def goal_running(self):
        """Counts a goal of another action server of the node's (the Simulation Interfaces'
        SimulateSteps) from its acceptance until the block ends, so that `close` waits for
        it as for the robots' goals; `aborted_at_stop` says its end was the node's stop."""
        try:
            yield
        finally:
            with self._goals_changed:
                self._goals -= 1
                self._goals_changed.notify_all()

    def goal_accepted(self) -> None:
        """A goal of another action server of the node's accepted (`goal_running` ends it)."""
        with self._goals_changed:
            self._goals += 1

    def aborted_at_stop(self) -> None:
        """A goal the node's stop ended was aborted: `close` serves a moment longer, for its
        result to go out."""
        self._aborted_at_stop.set()

    def _execute(self, robot: str, action: ifc.Action, goal_handle):
        """A goal, counted from its acceptance (`_check_goal`) until it ends (`close` waits
        for them to be aborted)."""
        try:
            return self._run_goal(robot, action, goal_handle)
        finally:
            with self._goals_changed:
                self._goals -= 1
                self._robot_goals[robot] -= 1
                self._goals_changed.notify_all()

    def _run_goal(self, robot: str, action: ifc.Action, goal_handle):
        Result = ros_type(action.type).Result
        goal = goal_handle.request
        arguments = {name: getattr(goal, name) for name in ifc.goal_fields(action.command)}
        try:
            started = self._call(partial(calls.start_operation, robot, action.call, arguments))
        except SimulationStoppedError:
            return self._abort_at_stop(goal_handle, Result)
        except (ValueError, TimeoutError) as e:
            goal_handle.abort()
            return Result(success=False, reason=str(e) or type(e).__name__)
        ended = self.runner.watch(partial(calls.ended_command, robot, started.seq))
        feedback = self._feedback_watch(robot, action, started.start_time + FEEDBACK_PERIOD)
        try:
            while True:
                concurrent.futures.wait((ended, feedback), WAKE_PERIOD,
                                        concurrent.futures.FIRST_COMPLETED)
                if ended.done():
                    try:
                        result = ended.result()
                        break
                    except SimulationStoppedError:
                        return self._abort_at_stop(goal_handle, Result)
                    except KeyError as e:  # the robot deleted (DeleteEntity, a reset)
                        goal_handle.abort()
                        return Result(success=False, reason=e.args[0])
                if robot in self._leaving:  # (its robot gone before a step told the watch)
                    goal_handle.abort()
                    return Result(success=False, reason=f"{robot}: {ROBOT_GONE}")
                if self._closing.is_set():
                    with contextlib.suppress(SimulationStoppedError, TimeoutError):
                        self._call(partial(stop_if_running, robot, started.seq), RESULT_GRACE)
                    return self._abort_at_stop(goal_handle, Result)
                if goal_handle.is_cancel_requested:
                    return self._cancel(robot, started.seq, goal_handle, ended, Result)
                if feedback.done():
                    feedback = self._feed_back(robot, action, goal_handle, feedback)
        finally:
            feedback.cancel()  # (stops watching)
        if result.succeeded:
            goal_handle.succeed()
        else:
            goal_handle.abort()
        return Result(success=result.succeeded, reason=result.reason)

    def _feedback_watch(self, robot: str, action: ifc.Action, due: float):
        """A future of (time, what is left) once simulated time reaches `due` s."""
        return self.runner.watch(partial(remaining_at, robot, action.command, due))

    def _feed_back(self, robot: str, action: ifc.Action, goal_handle, done):
        """Publishes the feedback `done` (a `_feedback_watch`) brought; the next one's
        watch, `FEEDBACK_PERIOD` s of simulated time later."""
        try:
            t, left = done.result()
        except (SimulationStoppedError, KeyError):
            return concurrent.futures.Future()  # none more: the goal's end says why
        if left is not None:
            goal_handle.publish_feedback(ros_type(action.type).Feedback(
                **{action.feedback: left}))
        return self._feedback_watch(robot, action, t + FEEDBACK_PERIOD)

    def _abort_at_stop(self, goal_handle, Result):
        """A goal the node's stop (or the simulation's) ends: aborted, saying so (`close`
        then serves a moment longer, for its result to go out)."""
        self._aborted_at_stop.set()
        goal_handle.abort()
        return Result(success=False, reason=NODE_STOPPED)

    def _cancel(self, robot: str, seq: int, goal_handle, ended, Result):
        """Stops the robot (an AllStop, unless the command ended meanwhile), waits for the
        command to end, and reports the goal cancelled."""
        self._call(partial(stop_if_running, robot, seq))
        with contextlib.suppress(concurrent.futures.TimeoutError, SimulationStoppedError):
            ended.result(ANSWER_TIMEOUT)
        goal_handle.canceled()
        return Result(success=False, reason=ifc.CANCELED)

    # --- services ---
    def _service_handler(self, service: ifc.Service):
        """What serves a command table's service, by its type: a Trigger issues the command,
        a SetBool the command with `data` as its one flag, SetPose a teleport."""
        spec = commands.by_method(service.call)
        if service.type == "std_srvs/srv/Trigger":
            return partial(self._trigger, spec)
        if service.type == "std_srvs/srv/SetBool":
            return partial(self._set_bool, spec)
        if service.type == f"{ifc.PACKAGE}/srv/SetPose":
            return self._set_pose
        raise ValueError(f"{service.name}: the node serves no {service.type}")

    def _trigger(self, spec, robot: str, request, response):
        return self._simple(robot, spec.method, {}, response, spec.name)

    def _set_bool(self, spec, robot: str, request, response):
        (flag,) = spec.args
        value = bool(request.data)
        return self._simple(robot, spec.method, {flag.name: value}, response,
                            f"{spec.name} {flag.name}={str(value).lower()}")

    def _simple(self, robot: str, command: str, arguments: dict, response, what: str):
        try:
            seq, t = self._call(partial(calls.issue, robot, command, arguments))
        except (ValueError, SimulationStoppedError, TimeoutError) as e:
            response.success, response.message = False, str(e) or type(e).__name__
            return response
        response.success, response.message = True, f"{what} issued (seq {seq}, t = {t:.3f} s)"
        return response

    def _set_pose(self, robot: str, request, response):
        # The service's own field, in rad (the command's yaw_deg would name another).
        problem = YAW.problem(request.yaw)
        if problem:
            response.success, response.reason = False, f"yaw: {problem}"
            return response
        arguments = {"x": request.x, "y": request.y, "yaw_deg": math.degrees(request.yaw)}
        try:
            result = self._call(partial(calls.start_operation, robot, "set_pose", arguments))
            if result.end_time is None:
                result = self.runner.watch(partial(calls.ended_command, robot, result.seq)
                                           ).result(SERVICE_SETTLE_TIMEOUT)
        except (ValueError, SimulationStoppedError, TimeoutError) as e:
            response.success, response.reason = False, str(e) or type(e).__name__
            return response
        except KeyError as e:  # the robot deleted meanwhile
            response.success, response.reason = False, e.args[0]
            return response
        response.success, response.reason = result.succeeded, result.reason
        return response

    # --- life cycle ---
    def start(self) -> Ros2Node:
        """Spins the node in a thread of its own."""
        # A goal's execute callback holds a thread until its command ends, and /set_pose one
        # until the robot settles (both wait, the GIL released). rclpy's default, a thread
        # per core, left a 2-core machine with two goals running nothing to serve /cmd_vel,
        # the parameters or any other service: a thread per blocking callback a robot can
        # have at once, and some for the rest.
        from corobot_drake.ros2.simulation_services import BLOCKING_CALLBACKS

        threads = (BLOCKING_CALLBACKS_PER_ROBOT * self.robot_capacity + OTHER_CALLBACK_THREADS
                   + BLOCKING_CALLBACKS)
        self._executor = MultiThreadedExecutor(num_threads=threads, context=self.context)
        self._executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, name="corobot-ros2", daemon=True)
        self._thread.start()
        return self

    def _spin(self) -> None:
        spin_until_closed(self._executor, self._closing)

    def close(self) -> None:
        """Stops spinning and shuts the node down, in the order rclpy needs (the executor,
        its thread, the node, the context)."""
        if self._closing.is_set():
            return
        self._closing.set()
        with self._goals_changed:  # each aborts within a feedback period (`_run_goal`)
            self._goals_changed.wait_for(lambda: self._goals == 0, ANSWER_TIMEOUT)
        if self._aborted_at_stop.is_set() and self._executor is not None:
            time.sleep(RESULT_GRACE)  # still spinning: their results go out
        if self._executor is not None:
            self._executor.shutdown(timeout_sec=5.0)
        if self._thread is not None:
            self._thread.join(5.0)
        robot_servers = [e for entities in self._robot_entities.values() for e in entities
                         if isinstance(e, ActionServer)]
        for server in [*self._servers, *robot_servers]:
            server.destroy()
        self.node.destroy_node()
        if self.context.ok():
            rclpy.shutdown(context=self.context)


def wall_clock() -> Clock:
    """The clock of the node's timers that must run while the simulation is paused or runs
    as fast as it can (the node's own clock is the simulation's: it stops with it)."""
    return Clock(clock_type=ClockType.STEADY_TIME)


def cmd_vel_type(stamped: bool) -> str:
    """/cmd_vel's type (the `cmd_vel_stamped` parameter)."""
    return "geometry_msgs/msg/TwistStamped" if stamped else ifc.CMD_VEL[1]


def spin_until_closed(executor, closing: threading.Event) -> None:
    """Spins `executor` until it is shut down or `closing` is set. A callback's exception
    (rclpy re-raises it from `spin`) is logged and the node goes on serving: one lost answer,
    e.g. a response Fast DDS drops because the server has not yet discovered the client's
    reader, must not end every service, action and subscription of the node."""
    while not closing.is_set():
        try:
            executor.spin()
            return
        except ExternalShutdownException:
            return
        except Exception:
            if closing.is_set():
                return
            _log.exception("a ROS 2 callback failed; the node goes on serving")


def remaining(robot: str, command: type, sim) -> float | None:
    """In the simulation thread: what is left of the robot's running `command` (a
    DriveDistance: m, signed as its distance; a RotateDegrees: deg, signed), None if none
    runs (`Robot.continuation_commands`' first)."""
    for c in sim.robot(robot).continuation_commands():
        if isinstance(c, command):
            if isinstance(c, sc.DriveDistance):
                done = abs(c.recent_progress[-1]) if c.recent_progress else 0.0
                return math.copysign(max(0.0, abs(c.distance) - done), c.distance)
            return c.degrees
    return None


def remaining_at(robot: str, command: type, due: float, sim) -> tuple | None:
    """In the simulation thread (a watch): (now, `remaining`) once simulated time has reached
    `due` s, else None."""
    if sim.time < due - 1e-9:
        return None
    return sim.time, remaining(robot, command, sim)


def stop_if_running(robot: str, seq: int, sim) -> None:
    """In the simulation thread: an AllStop if command `seq` still runs."""
    r = sim.robot(robot)
    if r.command_result(seq).end_time is None:
        r.all_stop()
