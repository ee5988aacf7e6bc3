"""The ROS 2 Simulation Interfaces (package `simulation_interfaces` 2.1.0, the simulator-agnostic
control surface Gazebo and Isaac Sim serve) served by the node: play, pause, stop, step
(`StepSimulation`, the `SimulateSteps` action), reset, the entities' states, spawning and
deleting world bodies, model files' models and robots, and what can be spawned.

A *step* is one physics step (`Simulation.physics_step`: 10 ms by default). Entities are the
robots (category ROBOT) and the world's bodies beside them (`Simulation.bodies`: `world.bodies`
by name, a directive's model's bodies as `model::body`; OBJECT when free, STATIC_OBJECT when
welded). Poses and twists are in the `world` frame, at the simulated time of the header.
A robot spawned from its robot file gets its topics, frames, actions and services under its
name (`topics.robot_names`: the scenario's robots keep theirs); the node takes its commands
from then on (`Ros2Node.set_robots`), until it is deleted or a reset ends it.

The services and the action are named relative to the node's namespace, as Gazebo's
(`--ros-args -r __ns:=/sim` serves `/sim/spawn_entity`; at the root, `/spawn_entity`).

Threads: as the node's own services (`node`), each callback hands its work to the simulation
thread (`Runner.submit`) and waits; what is refused comes back as `RefusedError`, the interface's
result code with one line naming what is wrong.
"""

from __future__ import annotations

import contextlib
import json
import math
import re
import threading
from functools import partial
from pathlib import Path

from rclpy.action import ActionServer, CancelResponse, GoalResponse

from corobot_drake.names import did_you_mean
from corobot_drake.ros2.graph import ros_type
from corobot_drake.ros2.node import ANSWER_TIMEOUT, SERVICE_QOS
from corobot_drake.serving.runner import SimulationStoppedError, StepJob

PACKAGE = "simulation_interfaces"
MAX_STEPS = 1_000_000
"""Steps one StepSimulation or SimulateSteps may ask for (10^4 s of the default 10 ms step)."""
STEP_TIMEOUT_PER_STEP = 0.05
"""s (wall clock) a step may take before a StepSimulation gives up waiting (plus
`node.ANSWER_TIMEOUT`): a camera scene steps at ~0.3x real time on 2 cores."""
UNIT_TOLERANCE = 1e-3
"""How far from 1 a pose's quaternion's norm may be (float32 rounding of a client's)."""
LEVEL_TOLERANCE = 1e-3
"""rad: the roll and pitch a robot's new pose may have (it stands on the ground)."""
BLOCKING_CALLBACKS = 2
"""Executor threads the calls that wait for steps hold: StepSimulation, a SimulateSteps goal."""

SERVICES = {
    "get_simulator_features": "GetSimulatorFeatures",
    "get_simulation_state": "GetSimulationState",
    "set_simulation_state": "SetSimulationState",
    "reset_simulation": "ResetSimulation",
    "step_simulation": "StepSimulation",
    "get_entities": "GetEntities",
    "get_entity_info": "GetEntityInfo",
    "get_entity_state": "GetEntityState",
    "get_entities_states": "GetEntitiesStates",
    "set_entity_state": "SetEntityState",
    "spawn_entity": "SpawnEntity",
    "delete_entity": "DeleteEntity",
    "get_spawnables": "GetSpawnables",
}
"""Service name (at the node's namespace, as Isaac Sim's) -> its type in `PACKAGE`."""
ACTION = ("simulate_steps", "SimulateSteps")


def _t(kind: str, name: str):
    return ros_type(f"{PACKAGE}/{kind}/{name}")


class RefusedError(Exception):
    """A request answered with `code` (a `Result` code, or a service's own above 100) and
    `message` (one line naming what is wrong)."""

    def __init__(self, code: int, message: str):
        super().__init__(message)
        self.code = code


def result(code: int | None = None, message: str = ""):
    """A `simulation_interfaces/msg/Result` (default RESULT_OK)."""
    Result = _t("msg", "Result")
    return Result(result=Result.RESULT_OK if code is None else code, error_message=message)


def step_problem(steps) -> str | None:
    """Why `steps` cannot be stepped (one line), None if it can."""
    if not 1 <= steps <= MAX_STEPS:
        return f"steps: must be in [1, {MAX_STEPS}]; got {steps}"
    return None


# --- poses ---------------------------------------------------------------------------------


def pose_transform(pose, field: str):
    """A `geometry_msgs/Pose` as a RigidTransform; RefusedError (`INVALID_POSE`-like code given
    by the caller as ValueError) naming `field` when not finite or the quaternion not unit."""
    from pydrake.common.eigen_geometry import Quaternion
    from pydrake.math import RigidTransform

    p, q = pose.position, pose.orientation
    position = [p.x, p.y, p.z]
    wxyz = [q.w, q.x, q.y, q.z]
    for name, v in zip(("position.x", "position.y", "position.z", "orientation.w",
                        "orientation.x", "orientation.y", "orientation.z"),
                       position + wxyz, strict=True):
        if not math.isfinite(v):
            raise ValueError(f"{field}.{name}: must be a finite number; got {v}")
    norm = math.sqrt(sum(c * c for c in wxyz))
    if abs(norm - 1.0) > UNIT_TOLERANCE:
        raise ValueError(f"{field}.orientation: must be a unit quaternion; its norm is {norm:.6g}")
    return RigidTransform(Quaternion([c / norm for c in wxyz]), position)


def pose_message(X, Pose):
    """A RigidTransform as a `geometry_msgs/Pose`."""
    p, q = X.translation(), X.rotation().ToQuaternion()
    msg = Pose()
    msg.position.x, msg.position.y, msg.position.z = (float(v) for v in p)
    msg.orientation.w, msg.orientation.x = float(q.w()), float(q.x())
    msg.orientation.y, msg.orientation.z = float(q.y()), float(q.z())
    return msg


# --- entities, in the simulation thread ------------------------------------------------------


def entity_names(sim) -> list[str]:
    """The robots (the scenario's order), then the world's bodies (`Simulation.bodies`)."""
    return [*sim.robots, *sim.bodies()]


def level(X, code: int, field: str):
    """The RollPitchYaw of a robot's pose `X`; RefusedError `code` naming `field` when it is
    not level (a robot stands on the ground: only a yaw, within `LEVEL_TOLERANCE`)."""
    from pydrake.math import RollPitchYaw

    rpy = RollPitchYaw(X.rotation())
    if max(abs(rpy.roll_angle()), abs(rpy.pitch_angle())) > LEVEL_TOLERANCE:
        raise RefusedError(code, f"{field}: a robot stands on the ground: only a yaw (roll "
                           f"{rpy.roll_angle():.3g} rad, pitch {rpy.pitch_angle():.3g} rad)")
    return rpy


def entity_body(sim, name: str):
    """(the body an entity's state is that of: a robot's chassis, else the body; whether it is
    a robot); RefusedError NOT_FOUND naming the entity and those there are."""
    if name in sim.station.robots:
        return sim.station.robots[name].chassis, True
    body = sim.bodies().get(name)
    if body is None:
        names = entity_names(sim)
        raise RefusedError(result().RESULT_NOT_FOUND,
                      f"entity: no entity named {name!r}{did_you_mean(name, names)} (there are: "
                      f"{', '.join(names)})")
    return body, False


def entity_category(sim, name: str) -> int:
    EntityCategory = _t("msg", "EntityCategory")
    body, robot = entity_body(sim, name)
    if robot:
        return EntityCategory.CATEGORY_ROBOT
    if body.is_floating_base_body():
        return EntityCategory.CATEGORY_OBJECT
    return EntityCategory.CATEGORY_STATIC_OBJECT


def entity_state(sim, name: str):
    """An entity's `EntityState`: pose, twist and acceleration in the world frame, now."""
    from pydrake.math import RigidTransform

    body, _ = entity_body(sim, name)
    plant = sim.station.plant
    context = plant.GetMyContextFromRoot(sim.context)
    X = plant.EvalBodyPoseInWorld(context, body)
    V = plant.EvalBodySpatialVelocityInWorld(context, body)
    A = plant.EvalBodySpatialAccelerationInWorld(context, body)
    state = _t("msg", "EntityState")()
    state.header.frame_id = "world"
    ns = round(sim.time * 1e9)
    state.header.stamp.sec, state.header.stamp.nanosec = divmod(ns, 1_000_000_000)
    state.pose = pose_message(RigidTransform(X.rotation(), X.translation()),
                              ros_type("geometry_msgs/msg/Pose"))
    for target, vector in ((state.twist.linear, V.translational()),
                           (state.twist.angular, V.rotational()),
                           (state.acceleration.linear, A.translational()),
                           (state.acceleration.angular, A.rotational())):
        target.x, target.y, target.z = (float(v) for v in vector)
    return state


def matching_entities(sim, filters) -> list[str]:
    """The entities `filters` (`EntityFilters`) select: name by regular expression, any of the
    categories; tags and bounds filters are not supported (RefusedError FEATURE_UNSUPPORTED)."""
    Result, Bounds = _t("msg", "Result"), _t("msg", "Bounds")
    if filters.tags.tags:
        raise RefusedError(Result.RESULT_FEATURE_UNSUPPORTED,
                      "filters.tags: entities have no tags here")
    if filters.bounds.type != Bounds.TYPE_EMPTY or filters.bounds.points:
        raise RefusedError(Result.RESULT_FEATURE_UNSUPPORTED,
                      "filters.bounds: filtering by bounds is not supported")
    try:
        pattern = re.compile(filters.filter)
    except re.error as e:
        raise RefusedError(Result.RESULT_OPERATION_FAILED,
                      f"filters.filter: not a regular expression: {e}") from None
    categories = {c.category for c in filters.categories}
    return [name for name in entity_names(sim)
            if pattern.search(name)
            and (not categories or entity_category(sim, name) in categories)]


# --- the services ----------------------------------------------------------------------------


class SimulationServices:
    """The Simulation Interfaces of `node` (a `node.Ros2Node`), served through `runner` (a
    `serving.runner.SimRunner`): made by `Ros2Node.attach`."""

    def __init__(self, node, runner):
        self._node = node
        self._runner = runner
        self._stopped = False
        """STATE_STOPPED: paused at the scenario's start (SetSimulationState), until played,
        paused or stepped."""
        self._original = None
        """The scenario the node started with, once a spawn or a delete has rebuilt the
        simulation from another (a reset rebuilds it from this one); None before."""
        self._models: set[str] = set()
        """The directive models spawned since the start (deleted as they came)."""
        self._lock = threading.Lock()  # the state's transitions, one at a time
        ros = node.node
        for name, srv in SERVICES.items():
            ros.create_service(_t("srv", srv), name, getattr(self, f"_{name}"),
                               qos_profile=SERVICE_QOS, callback_group=node._group)
        name, action = ACTION
        self._action = ActionServer(
            ros, _t("action", action), name, execute_callback=self._simulate_steps,
            goal_callback=self._check_goal, cancel_callback=lambda goal: CancelResponse.ACCEPT,
            callback_group=node._group, goal_service_qos_profile=SERVICE_QOS,
            result_service_qos_profile=SERVICE_QOS, cancel_service_qos_profile=SERVICE_QOS)
        node._servers.append(self._action)

    def _call(self, fn, timeout: float = ANSWER_TIMEOUT):
        return self._runner.submit(fn).result(timeout)

    def _answer(self, response, fn, fill=None):
        """Runs `fn(sim)` in the simulation thread; `fill(response, value)` on success; the
        response's `result` from what it raised otherwise."""
        Result = _t("msg", "Result")
        try:
            value = self._call(fn)
        except RefusedError as e:
            response.result = result(e.code, str(e))
            return response
        except (SimulationStoppedError, TimeoutError) as e:
            response.result = result(Result.RESULT_OPERATION_FAILED,
                                     str(e) or "the simulation did not answer in time")
            return response
        except (ValueError, KeyError, RuntimeError) as e:
            response.result = result(Result.RESULT_OPERATION_FAILED, str(e))
            return response
        if fill is not None:
            fill(response, value)
        response.result = result()
        return response

    # --- features, state ---
    def _get_simulator_features(self, request, response):
        F = _t("msg", "SimulatorFeatures")
        rebuilds = self._can_rebuild()
        response.features.features = [
            F.SPAWNING, F.DELETING, F.ENTITY_CATEGORIES, F.SPAWNING_RESOURCE_STRING,
            F.ENTITY_STATE_GETTING, F.ENTITY_STATE_SETTING, F.ENTITY_INFO_GETTING,
            F.SPAWNABLES, F.SIMULATION_RESET, F.SIMULATION_STATE_GETTING,
            F.SIMULATION_STATE_SETTING, F.SIMULATION_STATE_PAUSE, F.STEP_SIMULATION_SINGLE,
            F.STEP_SIMULATION_MULTIPLE, F.STEP_SIMULATION_ACTION]
        if not rebuilds:
            response.features.features = [f for f in response.features.features
                                          if f not in (F.SPAWNING, F.DELETING,
                                                       F.SPAWNING_RESOURCE_STRING)]
        response.features.spawn_formats = list(SPAWN_FORMATS) if rebuilds else []
        response.features.custom_info = FEATURES_INFO
        return response

    def state(self) -> int:
        S = _t("msg", "SimulationState")
        if self._stopped:
            return S.STATE_STOPPED
        return S.STATE_PAUSED if self._runner.paused else S.STATE_PLAYING

    def _get_simulation_state(self, request, response):
        response.state.state = self.state()
        response.result = result()
        return response

    def _set_simulation_state(self, request, response):
        S, srv = _t("msg", "SimulationState"), _t("srv", "SetSimulationState").Response
        target = request.state.state
        with self._lock:
            if target == self.state():
                response.result = result(srv.ALREADY_IN_TARGET_STATE,
                                         f"state: already {STATE_NAMES[target]}")
                return response
            if target == S.STATE_PLAYING:
                self._stopped = False
                self._runner.pause(False)
            elif target == S.STATE_PAUSED:
                self._stopped = False
                self._runner.pause(True)
            elif target == S.STATE_STOPPED:
                self._runner.pause(True)
                self._answer(response, self._reset)
                self._sync_robots()
                if response.result.result != response.result.RESULT_OK:
                    return response
                self._stopped = True
            elif target in STATE_NAMES:
                response.result = result(response.result.RESULT_FEATURE_UNSUPPORTED,
                                         f"state: {STATE_NAMES[target]} is not supported here "
                                         "(the node ends with the simulation: Ctrl-C)")
                return response
            else:
                response.result = result(srv.INCORRECT_TRANSITION,
                                         f"state: {target} is not a SimulationState")
                return response
        response.result = result()
        return response

    # --- reset ---
    def _reset_simulation(self, request, response):
        R = _t("srv", "ResetSimulation").Request
        if request.scope not in (R.SCOPE_DEFAULT, R.SCOPE_ALL):
            response.result = result(response.result.RESULT_FEATURE_UNSUPPORTED,
                                     f"scope: only a full reset (SCOPE_ALL or SCOPE_DEFAULT) "
                                     f"is supported; got {request.scope}")
            return response
        with self._lock:
            self._answer(response, self._reset)
            self._sync_robots()
            return response

    def _reset(self, sim) -> None:
        """In the simulation thread: back to the start of the scenario the node started with
        (the spawned bodies gone, the deleted back): a run from there is the first run again,
        bit for bit."""
        if self._original is not None:
            self._runner.replace(self._runner.rebuild(self._original))
            self._original = None
            self._models.clear()
        else:
            sim.reset()
        self._node.forget_commands()  # the deadman's: the robots' commands are reset

    def _sync_robots(self) -> None:
        """The node takes commands for the simulation's robots (after a spawn, a delete or a
        reset changed them)."""
        with contextlib.suppress(SimulationStoppedError, TimeoutError):
            self._node.set_robots(self._call(lambda sim: list(sim.robots)))

    # --- stepping ---
    def _step_problem(self, steps) -> RefusedError | None:
        Result = _t("msg", "Result")
        problem = step_problem(steps)
        if problem:
            return RefusedError(Result.RESULT_OPERATION_FAILED, problem)
        if not self._runner.paused:
            return RefusedError(Result.RESULT_OPERATION_FAILED,
                                "the simulation is playing: steps are taken when it is paused "
                                "(set_simulation_state STATE_PAUSED)")
        return None

    def _step_simulation(self, request, response):
        refused = self._step_problem(request.steps)
        if refused is not None:
            response.result = result(refused.code, str(refused))
            return response
        self._stopped = False
        job = self._runner.step(StepJob(request.steps))
        try:
            job.future.result(ANSWER_TIMEOUT + STEP_TIMEOUT_PER_STEP * request.steps)
        except (TimeoutError, SimulationStoppedError) as e:
            job.cancel()
            response.result = result(response.result.RESULT_OPERATION_FAILED,
                                     f"steps: {job.done} of {request.steps} taken: "
                                     f"{str(e) or 'the simulation did not take them in time'}")
            return response
        response.result = result()
        return response

    def _check_goal(self, goal) -> GoalResponse:
        """A goal of no steps or too many is rejected when sent (its reason logged)."""
        problem = step_problem(goal.steps)
        if problem:
            self._node.log.warning(f"{ACTION[0]}: goal rejected: {problem}")
            return GoalResponse.REJECT
        # Counted from here: rclpy answers "accepted" before its executor starts the execute
        # callback, and a stop in between must still wait for the goal's abort.
        self._node.goal_accepted()
        return GoalResponse.ACCEPT

    def _simulate_steps(self, goal_handle):
        """Takes the goal's steps (the simulation paused), feedback after each; a cancel
        stops after the step under way, the simulation staying paused; the node's stop aborts
        it, and the node waits for its result to go out (`Ros2Node.goal_running`)."""
        with self._node.goal_running():
            return self._take_steps(goal_handle)

    def _take_steps(self, goal_handle):
        Action = _t("action", ACTION[1])
        steps = goal_handle.request.steps
        refused = self._step_problem(steps)
        if refused is not None:
            goal_handle.abort()
            return Action.Result(result=result(refused.code, str(refused)))
        self._stopped = False
        job = self._runner.step(StepJob(steps, progress=lambda done, left: (
            goal_handle.publish_feedback(Action.Feedback(completed_steps=done,
                                                         remaining_steps=left)))))
        while True:
            try:
                job.future.result(0.05)
                break
            except TimeoutError:
                if goal_handle.is_cancel_requested or self._node._closing.is_set():
                    job.cancel()
            except SimulationStoppedError as e:
                self._node.aborted_at_stop()
                goal_handle.abort()
                return Action.Result(result=result(Action.Result().result.RESULT_OPERATION_FAILED,
                                                   str(e)))
        if job.done < steps:
            said = f"cancelled after {job.done} of {steps} steps"
            if not goal_handle.is_cancel_requested:  # the node stopping
                self._node.aborted_at_stop()
                goal_handle.abort()
                return Action.Result(result=result(Action.Result().result.RESULT_OPERATION_FAILED,
                                                   f"{said}: the node stopped"))
            goal_handle.canceled()
            return Action.Result(result=result(message=said))
        goal_handle.succeed()
        return Action.Result(result=result())

    # --- entities ---
    def _get_entities(self, request, response):
        def fill(r, names):
            r.entities = names
        return self._answer(response, partial(matching_entities, filters=request.filters), fill)

    def _get_entity_info(self, request, response):
        def info(sim):
            return entity_category(sim, request.entity)

        def fill(r, category):
            r.info.category.category = category
            r.info.description = ("robot" if category == r.info.category.CATEGORY_ROBOT
                                  else "world body")
        return self._answer(response, info, fill)

    def _get_entity_state(self, request, response):
        def fill(r, state):
            r.state = state
        return self._answer(response, partial(entity_state, name=request.entity), fill)

    def _get_entities_states(self, request, response):
        def states(sim):
            names = matching_entities(sim, request.filters)
            return names, [entity_state(sim, name) for name in names]

        def fill(r, value):
            r.entities, r.states = value
        return self._answer(response, states, fill)

    def _set_entity_state(self, request, response):
        """A robot teleports as /set_pose does (on the ground: z is its, the orientation a yaw),
        and the call returns once it has settled (at once when paused: it settles as the steps
        are taken); a free body takes the pose and twist at once; a fixed one cannot move."""
        from corobot_drake.serving import calls

        Srv = _t("srv", "SetEntityState").Response
        try:
            start = self._call(partial(self._set_state, request))
        except RefusedError as e:
            response.result = result(e.code, str(e))
            return response
        except (SimulationStoppedError, TimeoutError) as e:
            response.result = result(Srv().result.RESULT_OPERATION_FAILED, str(e))
            return response
        if start is not None and start.end_time is None and not self._runner.paused:
            from corobot_drake.ros2.node import SERVICE_SETTLE_TIMEOUT

            try:
                start = self._runner.watch(partial(calls.ended_command, request.entity,
                                                   start.seq)).result(SERVICE_SETTLE_TIMEOUT)
            except (SimulationStoppedError, TimeoutError) as e:
                response.result = result(Srv().result.RESULT_OPERATION_FAILED,
                                         str(e) or "the robot did not settle in time")
                return response
        if start is not None and start.end_time is not None and not start.succeeded:
            response.result = result(Srv().result.RESULT_OPERATION_FAILED,
                                     f"state.pose: the robot cannot stand there: {start.reason}")
            return response
        self._stopped = False  # (no longer the scenario's start: paused)
        response.result = result()
        return response

    def _set_state(self, request, sim):
        """In the simulation thread: the new state applied (a robot's teleport issued: its
        CommandResult; None for a body)."""
        from pydrake.multibody.math import SpatialVelocity

        from corobot_drake.serving import calls

        Result, Srv = _t("msg", "Result"), _t("srv", "SetEntityState").Response
        state = request.state
        body, robot = entity_body(sim, request.entity)
        if state.header.frame_id not in ("", "world"):
            raise RefusedError(Result.RESULT_FEATURE_UNSUPPORTED,
                               f"state.header.frame_id: only the world frame ('world' or "
                               f"empty); got {state.header.frame_id!r}")
        X = None
        if request.set_pose:
            try:
                X = pose_transform(state.pose, "state.pose")
            except ValueError as e:
                raise RefusedError(Srv.INVALID_POSE, str(e)) from None
        twist = [*_xyz(state.twist.angular), *_xyz(state.twist.linear)]
        if request.set_twist and not all(math.isfinite(v) for v in twist):
            raise RefusedError(Result.RESULT_OPERATION_FAILED,
                               f"state.twist: must be finite numbers; got {twist}")
        if robot:
            if request.set_twist and any(twist):
                raise RefusedError(Result.RESULT_FEATURE_UNSUPPORTED,
                                   "state.twist: a robot moves by its drive (cmd_vel): a "
                                   "teleport leaves it at rest")
            if X is None:
                return None
            rpy = level(X, Srv.INVALID_POSE, "state.pose.orientation")
            p = X.translation()
            try:
                return calls.start_operation(request.entity, "set_pose", {
                    "x": float(p[0]), "y": float(p[1]),
                    "yaw_deg": math.degrees(rpy.yaw_angle())}, sim)
            except ValueError as e:
                raise RefusedError(Srv.INVALID_POSE, f"state.pose: {e}") from None
        if not body.is_floating_base_body():
            if X is not None or (request.set_twist and any(twist)):
                raise RefusedError(Result.RESULT_OPERATION_FAILED,
                                   f"entity: {request.entity!r} is fixed (welded to the world): "
                                   "it cannot move")
            return None
        plant = sim.station.plant
        context = plant.GetMyMutableContextFromRoot(sim.context)
        if X is not None:
            plant.SetFreeBodyPose(context, body, X)
        if request.set_twist:
            plant.SetFreeBodySpatialVelocity(context, body,
                                             SpatialVelocity(twist[:3], twist[3:]))
        return None

    # --- spawning, deleting ---
    def _can_rebuild(self) -> bool:
        """Whether the runner can rebuild the simulation: known once it is built (the node
        serves while it is built), so this waits for that."""
        with contextlib.suppress(SimulationStoppedError, TimeoutError):
            self._call(lambda sim: None)
        return getattr(self._runner, "rebuild", None) is not None

    def _spawn_entity(self, request, response):
        """A world body from its YAML (a scenario's `world.bodies` entry: `resource_string`,
        or a `.yaml` file `uri`), a model file's model, or a robot from its robot file (`uri`:
        a shipped robot's name or the file) at `initial_pose`; the simulation is rebuilt with
        it, going on from where it is (`Simulation.saved_scenario`)."""
        Result = _t("msg", "Result")
        if not self._can_rebuild():
            response.result = result(Result.RESULT_FEATURE_UNSUPPORTED,
                                     "spawning needs the simulation's builder (the node runs "
                                     "without one here)")
            return response

        def fill(r, name):
            r.entity_name = name
        with self._lock:
            self._answer(response, partial(self._spawn, request), fill)
            self._sync_robots()
            return response

    def _spawn(self, request, sim) -> str:
        from pydrake.math import RollPitchYaw

        from corobot_drake.config import scenario as sc

        Srv = _t("srv", "SpawnEntity").Response
        robot = robot_resource(request.entity_resource)
        name = spawn_name(sim, request.name, request.allow_renaming,
                          "body" if robot is None else Path(robot).stem)
        if request.entity_namespace and not NAMESPACE.fullmatch(request.entity_namespace):
            raise RefusedError(Srv.NAMESPACE_INVALID,
                               f"entity_namespace: {request.entity_namespace!r} is not a ROS "
                               "namespace")
        frame = request.initial_pose.header.frame_id
        if frame not in ("", "world"):
            raise RefusedError(Srv.INVALID_POSE, "initial_pose.header.frame_id: only the world "
                               f"frame ('world' or empty); got {frame!r}")
        try:
            X = pose_transform(request.initial_pose.pose, "initial_pose.pose")
        except ValueError as e:
            raise RefusedError(Srv.INVALID_POSE, str(e)) from None
        if robot is not None:
            return self._spawn_robot(sim, name, robot, X, request.entity_namespace)
        uri = request.entity_resource.uri
        if uri and model_format(uri) is not None:
            return self._spawn_model(sim, name, uri, X)
        field, text = resource_text(request.entity_resource)
        rpy = RollPitchYaw(X.rotation()).vector()
        pose = (f"pose: {{translation: [{', '.join(repr(float(v)) for v in X.translation())}], "
                f"rotation: !Rpy {{deg: [{', '.join(repr(math.degrees(v)) for v in rpy)}]}}}}")
        head = ["world:", "  bodies:", f"    {name}:", f"      {pose}"]
        layer = "\n".join([*head, *("      " + line for line in text.splitlines())])
        try:
            scenario = sc.load_scenario(data=layer, defaults=sim.saved_scenario())
        except sc.ScenarioError as e:
            if e.field.endswith(".pose"):  # it would overlap a robot, a body or the ground
                raise RefusedError(Srv.INVALID_POSE, f"initial_pose: {e.field}: {e.message}"
                                   ) from None
            raise body_refusal(e, field, name, len(head), len(text.splitlines())) from None
        self._rebuild(sim, scenario, Srv.RESOURCE_PARSE_ERROR, Srv.INVALID_POSE)
        return name

    def _spawn_robot(self, sim, name: str, robot: str, X, namespace: str) -> str:
        """A robot (`robot`: a scenario's `robots.<name>.robot`) added to the scenario at `X`
        as a robot starts (on the ground: its x, y and yaw; z is the robot's own), its drive,
        tyres and sensors its robot file's. Returns its name."""

        from corobot_drake.config import scenario as sc

        Result, Srv = _t("msg", "Result"), _t("srv", "SpawnEntity").Response
        if namespace and namespace.strip("/") != name:
            raise RefusedError(Result.RESULT_FEATURE_UNSUPPORTED,
                               f"entity_namespace: a robot's topics and frames are under its "
                               f"name (/{name}/...): leave it empty or give /{name}; got "
                               f"{namespace!r}")
        if len(sim.robots) >= self._node.robot_capacity:
            raise RefusedError(Result.RESULT_OPERATION_FAILED,
                               f"name: {name!r}: the node takes at most "
                               f"{self._node.robot_capacity} robots at once; delete one first")
        rpy = level(X, Srv.INVALID_POSE, "initial_pose.pose.orientation")
        x, y = (float(v) for v in X.translation()[:2])
        layer = (f"robots:\n  {name}:\n    robot: {json.dumps(robot)}\n    pose: {{translation: "
                 f"[{x!r}, {y!r}, 0.0], rotation: !Rpy {{deg: [0.0, 0.0, "
                 f"{math.degrees(rpy.yaw_angle())!r}]}}}}\n")
        try:
            scenario = sc.load_scenario(data=layer, defaults=sim.saved_scenario())
        except sc.ScenarioError as e:
            raise robot_refusal(e) from None
        self._rebuild(sim, scenario, Srv.RESOURCE_PARSE_ERROR, Srv.INVALID_POSE)
        return name

    def _spawn_model(self, sim, name: str, uri: str, X) -> str:
        """A model file's model (`MODEL_FORMATS`) added as a directive: free, its base body
        at `X`; welded there when none of its bodies has mass (a wall, a maze). Returns the
        entity's name, `name::base`."""
        from pydrake.common.schema import Transform
        from pydrake.multibody.parsing import AddModel, AddWeld, ModelDirective

        base, massless = model_base(uri)
        if not uri.startswith(("package://", "file://")):  # a directive's file is a URI
            uri = Path(uri).resolve().as_uri()
        add = AddModel(name=name, file=uri)
        directives = [ModelDirective(add_model=add)]
        if massless:
            directives.append(ModelDirective(add_weld=AddWeld(
                parent="world", child=f"{name}::{base}", X_PC=Transform(X))))
        else:
            add.default_free_body_pose = {base: Transform(X)}
            directives[0] = ModelDirective(add_model=add)
        scenario = sim.saved_scenario()
        scenario.directives = [*scenario.directives, *directives]
        Srv = _t("srv", "SpawnEntity").Response
        self._rebuild(sim, scenario, Srv.RESOURCE_PARSE_ERROR, Srv.INVALID_POSE)
        self._models.add(name)
        return f"{name}::{base}"

    def _rebuild(self, sim, scenario, code: int, pose_code: int | None = None) -> None:
        self._stopped = False  # (no longer the scenario's start: paused)
        self._replace(sim, scenario, code, pose_code)

    def _replace(self, sim, scenario, code: int, pose_code: int | None) -> None:
        """In the simulation thread: the runner's simulation replaced by one built from
        `scenario` (the one the node started with kept for a reset); RefusedError `code`
        saying why it could not be built (`pose_code` when it is a start pose's overlap)."""
        from corobot_drake.config import scenario as sc

        try:
            new = self._runner.rebuild(scenario)
        except (sc.ScenarioError, ValueError) as e:
            overlap = isinstance(e, sc.ScenarioError) and (
                e.field.endswith("pose") or " inside " in e.message)
            raise RefusedError(pose_code if overlap and pose_code is not None else code,
                               str(e)) from None
        if self._original is None:
            self._original = sim.scenario
        self._runner.replace(new)

    def _delete_entity(self, request, response):
        Result = _t("msg", "Result")
        if not self._can_rebuild():
            response.result = result(Result.RESULT_FEATURE_UNSUPPORTED,
                                     "deleting needs the simulation's builder (the node runs "
                                     "without one here)")
            return response
        with self._lock:
            self._answer(response, partial(self._delete, request.entity))
            self._sync_robots()
            return response

    def _delete(self, name: str, sim) -> None:
        Result = _t("msg", "Result")
        entity_body(sim, name)  # NOT_FOUND
        model = name.split("::")[0] if "::" in name else None
        scenario = sim.saved_scenario()
        if name in scenario.world.bodies:
            del scenario.world.bodies[name]
        elif model in self._models:  # a spawned model: its directives go, every body
            scenario.directives = [
                d for d in scenario.directives
                if not (d.add_model is not None and d.add_model.name == model)
                and not (d.add_weld is not None and d.add_weld.child.startswith(f"{model}::"))]
        elif name in scenario.robots:
            if len(scenario.robots) == 1:
                raise RefusedError(Result.RESULT_OPERATION_FAILED,
                                   f"entity: {name!r} is the only robot: the simulation keeps "
                                   "one (spawn another first)")
            del scenario.robots[name]
        else:
            raise RefusedError(Result.RESULT_FEATURE_UNSUPPORTED,
                               f"entity: {name!r} is a body of the scenario's directives: "
                               "robots, world bodies and spawned models are deleted")
        self._rebuild(sim, scenario, Result.RESULT_OPERATION_FAILED)
        self._models.discard(model)
        if name in sim.robots:
            self._node.forget_commands(name)

    def _get_spawnables(self, request, response):
        from corobot_drake.robots import ROBOTS

        Spawnable, Resource = _t("msg", "Spawnable"), _t("msg", "Resource")
        response.spawnables = [
            *(Spawnable(entity_resource=Resource(resource_string=text), description=description)
              for description, text in SPAWNABLE_BODIES.items()),
            *(Spawnable(entity_resource=Resource(uri=uri), description=description)
              for uri, description in SPAWNABLE_MODELS.items()),
            *(Spawnable(entity_resource=Resource(uri=name), description=robot_description(
                name, path)) for name, path in ROBOTS.items())]
        notes = [] if SPAWNABLE_MODELS else [NO_SHIPPED_MODELS]
        if request.sources:
            notes.append(f"sources: not searched here: {', '.join(request.sources)}")
        response.result = result(message="; ".join(notes))
        return response


def _xyz(v) -> list[float]:
    return [v.x, v.y, v.z]


NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,63}")
"""An entity's name: a ROS name's token (its topics and frames could take it)."""
NAMESPACE = re.compile(r"/?[A-Za-z][A-Za-z0-9_]*(/[A-Za-z][A-Za-z0-9_]*)*")
SPAWN_FORMATS = ("yaml", "sdf", "urdf", "mjcf")
"""yaml: a world body as a scenario's `world.bodies` entry (its shape: a box, sphere, cylinder,
capsule, ellipsoid, or a mesh file), by `resource_string` or a `.yaml` file's `uri`; the
others: a model file's `uri` (a path or `package://`), added as the scenario's directives add
one (`MODEL_FORMATS`)."""
MODEL_FORMATS = {".sdf": "sdf", ".urdf": "urdf", ".xml": "mjcf"}


def model_format(uri: str) -> str | None:
    return MODEL_FORMATS.get(Path(uri.split("?")[0]).suffix.lower())


MISSING_ASSET = re.compile(r"which does not exist|unknown package|[Uu]nable to (find|resolve)")
"""Drake's parser's words for a file a model refers to (a mesh, an include) not found."""


def model_base(uri: str) -> tuple[str, bool]:
    """(the name of the first body of the one model a model file holds, whether none of its
    bodies has mass), read into a scratch plant and scene graph (its geometry's files looked
    up); RefusedError naming what is wrong: MISSING_ASSETS for a mesh (or an included file)
    that is not found, RESOURCE_PARSE_ERROR for the rest (a file that is missing, too large,
    does not parse, holds no model or several, or welds its base to the world)."""
    from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
    from pydrake.systems.framework import DiagramBuilder

    from corobot_drake.config.directives import MAX_MODEL_BYTES
    from corobot_drake.config.scenario import one_line
    from corobot_drake.resources import make_parser, resolve_file

    Srv = _t("srv", "SpawnEntity").Response
    field = f"entity_resource.uri: {uri!r}"
    try:
        path = Path(resolve_file(uri.removeprefix("file://")))
        size = path.stat().st_size
    except (OSError, RuntimeError) as e:
        raise RefusedError(Srv.RESOURCE_PARSE_ERROR, f"{field}: {one_line(e)}") from None
    if not path.is_file() or size > MAX_MODEL_BYTES:
        raise RefusedError(Srv.RESOURCE_PARSE_ERROR, f"{field}: not a regular file of at most "
                           f"{MAX_MODEL_BYTES} bytes")
    plant, _ = AddMultibodyPlantSceneGraph(DiagramBuilder(), 0.0)
    try:
        models = make_parser(plant).AddModels(str(path))
        plant.Finalize()
    except (RuntimeError, ValueError) as e:
        code = (Srv.MISSING_ASSETS if MISSING_ASSET.search(str(e))
                else Srv.RESOURCE_PARSE_ERROR)
        raise RefusedError(code, f"{field}: {one_line(e)}") from None
    if len(models) != 1 or not plant.GetBodyIndices(models[0]):
        raise RefusedError(Srv.RESOURCE_PARSE_ERROR, f"{field}: holds {len(models)} models: "
                           "spawn a file of one model with a body")
    bodies = [plant.get_body(i) for i in plant.GetBodyIndices(models[0])]
    if not bodies[0].is_floating_base_body():
        raise RefusedError(Srv.RESOURCE_PARSE_ERROR, f"{field}: welds its base "
                           f"{bodies[0].name()!r} to the world: remove that joint")
    return bodies[0].name(), all(b.default_mass() == 0 for b in bodies)
FEATURES_INFO = (
    "corobot_drake: a step is one physics step (10 ms by default); entities are the robots "
    "and the world's bodies, states in the world frame; spawn and delete take world bodies "
    "(YAML as a scenario's world.bodies entry), model files (SDFormat, URDF, MJCF: free, "
    "or fixed when massless) and robots (a robot file's uri, or a shipped robot's name: its "
    "topics, frames, actions and services under /<name>/, the scenario's robots keeping "
    "theirs) and rebuild the simulation, which goes on from where it was; a reset returns to "
    "the scenario's start (bit for bit its first run)")
STATE_NAMES = {0: "STATE_STOPPED", 1: "STATE_PLAYING", 2: "STATE_PAUSED", 3: "STATE_QUITTING",
               4: "STATE_NO_WORLD", 5: "STATE_LOADING_WORLD"}
SPAWNABLE_BODIES = {
    "a free box, 0.3 m, 1 kg (a world body: set shape, mass, color as a scenario's)":
        "shape: !Box {size: [0.3, 0.3, 0.3]}\nmass: 1.0",
    "a free ball, 0.1 m radius, 0.5 kg": "shape: !Sphere {radius: 0.1}\nmass: 0.5\n"
                                         "hydroelastic_modulus: 0",
    "a fixed wall, 2 m x 0.1 m x 0.5 m": "shape: !Box {size: [2.0, 0.1, 0.5]}\nfixed: true",
}


SPAWNABLE_MODELS: dict[str, str] = {}
"""Shipped model files that spawn (uri -> description): none yet. The maze's walls
(`maze.sdf`) are rigid boxes with SDFormat's default 1 kg: free, they would sink through the
ground (the loader refuses them); its scenario welds them."""


NO_SHIPPED_MODELS = (
    "no shipped model file is listed: the maze (models/maze.sdf) has walls of SDFormat's "
    "default 1 kg, so it would spawn free, not as the fixed walls its scenario welds; spawn a "
    "model file of your own by its uri (free, or fixed when none of its bodies has mass), or "
    "a world body or robot listed here")
"""GetSpawnables' message while `SPAWNABLE_MODELS` is empty."""


def spawn_name(sim, name: str, allow_renaming: bool, default: str = "body") -> str:
    """The new entity's name: `name`, or with `allow_renaming` the first free `name_N`
    (`<default>_N` for an empty one); RefusedError NAME_INVALID / NAME_NOT_UNIQUE otherwise."""
    Srv = _t("srv", "SpawnEntity").Response
    taken = {*entity_names(sim), *sim.station.models}
    if name and not NAME.fullmatch(name):
        raise RefusedError(Srv.NAME_INVALID, f"name: {name!r} is not a name (a letter, then "
                           "letters, digits or _, at most 64)")
    if name and name not in taken:
        return name
    if not allow_renaming:
        raise RefusedError(Srv.NAME_NOT_UNIQUE if name else Srv.NAME_INVALID,
                           f"name: {name!r} is taken" if name else
                           "name: empty (give one, or allow_renaming)")
    base = name or default
    return next(f"{base}_{i}" for i in range(1, len(taken) + 2) if f"{base}_{i}" not in taken)


def resource_text(resource) -> tuple[str, str]:
    """(the field it came from, the YAML text of a world body) of a `Resource`; RefusedError
    NO_RESOURCE, UNSUPPORTED_FORMAT or RESOURCE_PARSE_ERROR naming what is wrong."""
    Srv = _t("srv", "SpawnEntity").Response
    if resource.uri:
        uri = resource.uri.removeprefix("file://")
        if Path(uri).suffix.lower() not in (".yaml", ".yml"):
            raise RefusedError(Srv.UNSUPPORTED_FORMAT,
                               f"entity_resource.uri: {resource.uri!r}: spawn formats are "
                               "yaml (a world body), sdf, urdf and mjcf (.xml: a model file)")
        try:
            field, text = f"entity_resource.uri: {uri}", Path(uri).read_text()
        except (OSError, UnicodeDecodeError) as e:
            raise RefusedError(Srv.RESOURCE_PARSE_ERROR,
                               f"entity_resource.uri: {resource.uri!r}: {e}") from None
    elif not resource.resource_string.strip():
        raise RefusedError(Srv.NO_RESOURCE, "entity_resource: both uri and resource_string "
                           "are empty")
    elif resource.resource_string.lstrip().startswith("<"):
        raise RefusedError(Srv.UNSUPPORTED_FORMAT,
                           "entity_resource.resource_string: XML (a model's SDFormat, URDF or "
                           "MJCF?): a resource_string is yaml (a world body); give a model "
                           "file by its uri")
    else:
        field, text = "entity_resource.resource_string", resource.resource_string
    return field, text


def body_refusal(error, field: str, name: str, head: int, lines: int) -> RefusedError:
    """A world body's ScenarioError as SpawnEntity's answer, at the line of the user's text
    (`field`: the file or the resource_string it came from, `lines` long), not of the
    scenario text it was wrapped in (`head` lines before it, under world.bodies.<name>): a
    mesh file that cannot be read MISSING_ASSETS, the rest RESOURCE_PARSE_ERROR."""
    Srv = _t("srv", "SpawnEntity").Response
    where = field
    if error.line is not None and error.line > head:  # (YAML's end of text: its last line)
        line = min(error.line - head, max(lines, 1))
        where = (f"{field}:{line}" if field.startswith("entity_resource.uri")
                 else f"{field}: line {line}")
    inner = error.field.removeprefix(f"world.bodies.{name}").lstrip(".") or "(top level)"
    code = (Srv.MISSING_ASSETS if error.field.endswith(".filename")
            else Srv.RESOURCE_PARSE_ERROR)
    return RefusedError(code, f"{where}: {inner}: {error.message}")


def robot_resource(resource) -> str | None:
    """The robot a `Resource` names, as a scenario's `robots.<name>.robot` says it: a shipped
    robot's name, or a robot file's absolute path (`uri`: the name, a path or `file://`);
    None when it is no robot (a world body, a model file). A uri of a bare word is a robot's
    name (the loader names the robots there are when it is none); RefusedError
    FEATURE_UNSUPPORTED for a robot file's text (its model is found beside the file)."""
    from corobot_drake.robots import ROBOTS

    Result = _t("msg", "Result")
    if not resource.uri:
        if resource.resource_string.strip() and is_robot(resource.resource_string):
            raise RefusedError(Result.RESULT_FEATURE_UNSUPPORTED,
                               "entity_resource.resource_string: a robot file: give its uri "
                               "instead (a path or file://; its model is found beside it) or "
                               f"a shipped robot's name ({', '.join(ROBOTS)})")
        return None
    uri = resource.uri.removeprefix("file://")
    if uri in ROBOTS or ("/" not in uri and not Path(uri).suffix):
        return uri
    path = Path(uri)
    if path.suffix.lower() not in (".yaml", ".yml"):
        return None
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError):
        return None  # (a world body's file: `resource_text` says what is wrong)
    return str(path.resolve()) if is_robot(text) else None


def robot_refusal(error) -> RefusedError:
    """A robot's ScenarioError as SpawnEntity's answer: its start overlapping something
    INVALID_POSE, the rest RESOURCE_PARSE_ERROR; one line naming the request's field (or the
    robot file's line and field, the loader's own words)."""
    Srv = _t("srv", "SpawnEntity").Response
    if error.source != "<scenario text>":  # the robot file's own line
        return RefusedError(Srv.RESOURCE_PARSE_ERROR, f"entity_resource.uri: {error}")
    if error.field.endswith(".pose"):  # it would start inside a robot or a body
        return RefusedError(Srv.INVALID_POSE, f"initial_pose: {error.message}")
    return RefusedError(Srv.RESOURCE_PARSE_ERROR, f"entity_resource.uri: {error.message}")


def robot_description(name: str, path: Path) -> str:
    """A shipped robot's GetSpawnables description: its robot file's first sentence."""
    comment = []
    for line in path.read_text().splitlines():
        if not line.startswith("#"):
            break
        comment.append(line.lstrip("#").strip())
    sentence = " ".join(comment).split(". ")[0].rstrip(".")
    return f"robot {name} (a robot file: {path.parent.name}/{path.name}): {sentence}"


def is_robot(text: str) -> bool:
    """Whether a resource's text is a robot file's (a mapping with `model` and `wheels`)."""
    import yaml

    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError:  # (a world body's shape tags, !Box ...: not a robot file's)
        return False
    return isinstance(data, dict) and {"model", "wheels"} <= set(data)
