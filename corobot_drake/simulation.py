"""The Python API: build a simulation from a scenario, drive its robots, read them back.

    sim = Simulation.from_file("scenarios/corobot.yaml")
    bot = sim.robot()            # the only robot, or sim.robot("name")
    bot.set_power(0.5, 0.5)
    sim.advance(2.0)             # simulated seconds
    print(bot.pose(), sim.summary())

All of a run's memory is in the Drake Context, so two runs of one scenario agree bit for bit.
"""

import collections
import copy
import dataclasses as dc
import functools
import logging
import math
import threading
import time
import weakref
from pathlib import Path

import numpy as np
from pydrake.common.yaml import yaml_dump_typed
from pydrake.geometry import HalfSpace, Role
from pydrake.math import RollPitchYaw
from pydrake.multibody.cenic import CenicIntegrator
from pydrake.multibody.math import SpatialVelocity
from pydrake.systems.analysis import ApplySimulatorConfig, Simulator
from pydrake.systems.framework import EventStatus

from corobot_drake import limits
from corobot_drake.config import scenario as sc
from corobot_drake.config.placement import Owner
from corobot_drake.config.poses import transform_from
from corobot_drake.config.validate import check_scenario
from corobot_drake.names import unknown_robot
from corobot_drake.readings import (
    BodyPose,
)
from corobot_drake.robot_api.commands import RobotCommands, _one_thread
from corobot_drake.robot_api.drive import RobotDrive
from corobot_drake.robot_api.sensors import Cameras, IrSensors, RobotSensors
from corobot_drake.robot_api.telemetry import RobotTelemetry
from corobot_drake.robots import robot_spec
from corobot_drake.station import RobotParts, Station, build_station
from corobot_drake.systems.runlog import (
    RUN_LOG_CHUNK,
    ContactSamples,
    log_rows,
    max_tilt_deg,
    spec_layout,
)

STEP_ROUNDING = 1e-6
"""Steps: a time this close to a physics step (in steps, 10 ns at 10 ms) is on it
(`Simulation.on_step`)."""

MIN_RUN_CHUNK = 1e-4
"""s: the shortest chunk `Simulation.run` advances by (a smaller one is refused: at 1e-300 s
the time never moved and `run` never ended)."""

_log = logging.getLogger(__name__)


class Robot(RobotCommands, RobotDrive, RobotTelemetry, RobotSensors):
    """One robot of a running simulation: its commands and measurements. A view: it keeps
    its Simulation alive and holds nothing of its own (`Simulation.robots` makes them).

    Its core is here (its Simulation, its station parts, its `spec`); each part's accessors
    come from `robot_api`: the commands (`RobotCommands`), the drive and motion
    (`RobotDrive`), the monitors and run log (`RobotTelemetry`) and the sensors of every
    kind (`RobotSensors`: `reading`, `ir_distances`, which is {} without IR sensors, ...).
    A robot with IR sensors also has their own accessors (`IrSensors`: `ir`, ...), one with
    a camera the cameras' (`Cameras`: `camera_image`, ...); one without them has none of
    those (`robot_type`)."""

    def __init__(self, sim: "Simulation", parts: RobotParts):
        self._sim = sim
        self._parts = parts
        self.name = parts.name
        self.spec = robot_spec(sim.scenario.robots[parts.name].robot)
        """What the robot is (`robots.RobotSpec`): its wheels, radius, track, drive, links."""
        self._layout = spec_layout(self.spec, parts.sensors)
        """Its run log's columns and its signals (`runlog.Layout`: keyed by its wheels; its
        sensors' columns last)."""

    def _plant_context(self):
        return self._sim.station.plant.GetMyContextFromRoot(self._sim.context)


@functools.cache
def _robot_type(ir: bool, cameras: bool) -> type:
    parts = (*((IrSensors,) if ir else ()), *((Cameras,) if cameras else ()))
    return type("Robot", (Robot, *parts), {"__doc__": Robot.__doc__,
                                           "__module__": Robot.__module__}) if parts else Robot


def robot_type(parts: RobotParts) -> type:
    """The class of the `Robot` of a robot with these parts: `Robot` with the IR sensors'
    accessors if it has IR sensors and the cameras' if it has a camera (turned on)."""
    return _robot_type(bool(parts.ir_sensors), bool(parts.cameras))


def _teleport_monitor(sources, root_context) -> EventStatus:
    """Stops the Simulator after the step in which a command source issued a SetPose."""
    for source in sources:
        if source.has_teleport(source.GetMyContextFromRoot(root_context)):
            return EventStatus.ReachedTermination(source, "teleport")
    return EventStatus.Succeeded()


class Simulation:
    """A scenario built into a Drake diagram with its Simulator and Context."""

    def __init__(self, scenario: sc.Scenario, meshcat=None, save_camera=None, *,
                 record: bool = False, foxglove=None, run_log_window: float | None = None,
                 check: bool = True, extras=(), started_with: tuple[str, ...] | None = None):
        """`save_camera`: a directory; each robot's front camera frames go to `<dir>/<robot>/`,
        another camera's to `<dir>/<robot>/<camera>/`.
        `record`: keep a Meshcat replay of the run (`save_recording`; without `meshcat`, an
        offline one records without a browser). `foxglove`: a `foxglove.Context` to publish
        the run's topics on (`recording.publishers`; its sinks: an MCAP file, a live server).
        `run_log_window`: see the attribute. The scenario gets the checks `load_scenario`
        runs (it may have been built or changed in Python): ScenarioError names the field;
        one unchanged since `load_scenario` returned it is not checked twice (`mark_checked`).
        `check=False` skips them, for a tool that measures beyond the bounds on purpose
        (`lab/step_limit.py`); `reset` then skips them too unless asked. `extras`:
        functions that add systems to the diagram (`station.build_station`'s; the ROS 2
        topics). `started_with`: the robots the run started with, when this simulation is a
        rebuild of it with robots added or removed (ROS 2's SpawnEntity): the Foxglove topics
        keep their names (`topics.robot_names`); default: this scenario's robots."""
        if check:
            check_scenario(scenario)
        self._thread_lock = threading.RLock()
        """Held while a thread advances, resets or commands the simulation (`_one_thread`)."""
        self._check = check
        self.scenario = scenario
        self._record_live: bool | None = None
        """Recording: True with a browser's Meshcat (frames shown live), False offline."""
        if record:
            from corobot_drake.recording.meshcat_html import offline_meshcat

            self._record_live = meshcat is not None
            meshcat = meshcat or offline_meshcat()
        extras = list(extras)
        if meshcat is not None:  # the IR rays and slip marks beside Drake's visualizers
            from corobot_drake.markers import add_meshcat_markers

            extras.append(functools.partial(add_meshcat_markers, meshcat,
                                            record=self._record_live))
        if foxglove is not None:  # the run's Foxglove topics, attached as a front end
            from corobot_drake.recording.publishers import add_foxglove_topics

            extras.append(functools.partial(add_foxglove_topics, context=foxglove,
                                            first=started_with))
        # Ctrl-drag only where someone watches: an offline recording stays free of it.
        self.station: Station = build_station(scenario, meshcat, save_camera, extras=extras,
                                              mouse_drag=self._record_live is not False)
        # The cameras' render threads end with this simulation, in the thread that frees it.
        weakref.finalize(self, self.station.close)
        self._owners = None
        self._output_ports: dict = {}
        """The station's output ports read so far (`output_port`), by name."""
        self.simulator = Simulator(self.station.diagram)
        apply_simulator_config(scenario, self.simulator)
        self.context = self.simulator.get_mutable_context()
        # The built diagram's key, now: the scenario may be changed in place before a reset.
        self._diagram_key = diagram_key(scenario)
        self._physics_step = sc.physics_step(scenario.plant_config, scenario.simulator_config)
        self.continuous_step = sc.continuous_step(scenario.plant_config,
                                                  scenario.simulator_config)
        """s: the continuous plant's step, to which stops and looks keep; 0 on a discrete one."""
        self.run_log_window: float | None = run_log_window
        """s of run log kept in memory (the newest, plus up to `runlog.RUN_LOG_CHUNK`
        samples); None keeps the whole run. A long-running simulation (`--serve`) sets it so
        that its memory stays flat: the log takes 64 bytes a sample, 23 MB an hour."""
        self._run_log_chunks = {name: collections.deque() for name in self.robots}
        """Each robot's run-log samples moved out of its Drake log sink when bounded
        (`_collect_run_logs`): arrays of `runlog.COLUMNS` rows, oldest first."""
        self._max_tilt_moved_out = dict.fromkeys(self.robots, 0.0)
        """Each robot's largest tilt (deg) over the samples moved out of its sink (kept
        whatever the window)."""
        self._contact_samples = (ContactSamples(
            self.station.diagram, self.station.plant, self.robots,
            {name: robot._layout for name, robot in self.robots.items()})
            if self.continuous_step else None)
        """On a continuous plant, what makes the robots' run-log contact telemetry when it
        is read (with the chunks, what was moved out of the Context)."""
        self._start()

    def _start(self) -> None:
        """Puts the scenario's per-run values (`diagram_key` leaves them out) into the
        Context, then initializes the simulator."""
        self._set_per_run_values()
        self._set_initial_velocities()
        self._scripted_teleports = any(isinstance(c, sc.SetPose)
                                       for r in self.scenario.robots.values() for c in r.commands)
        if self._scripted_teleports:
            # A scripted SetPose: stop after the step that issued it, to teleport (advance_to).
            # The monitor holds the command sources, not this Simulation: the Simulator keeps
            # it from C++, where a reference back to the Simulation is a cycle never freed.
            self.simulator.set_monitor(functools.partial(
                _teleport_monitor, [p.command_source for p in self.station.robots.values()]))
        else:
            self.simulator.clear_monitor()
        if self._record_live is not None:  # before Initialize: its publish is the first frame
            from corobot_drake.recording.meshcat_html import start_recording

            start_recording(self.station.meshcat, live=self._record_live)
        self.simulator.Initialize()
        self._wall_seconds = 0.0

    @_one_thread
    def reset(self, scenario: sc.Scenario | None = None, *, key: str | None = None,
              check: bool | None = None) -> None:
        """Starts again from the beginning of `scenario` (default: this simulation's) on the
        diagram already built: the Context goes back to its defaults, then takes the
        scenario's seed, start time, scripts and initial poses and velocities. A run after a
        reset is bit for bit a run of a freshly built simulation. The scenario gets the
        constructor's checks (ScenarioError; `check` defaults to the constructor's), then may
        differ from the built one only in those values (`diagram_key`; pass `key` if you have
        it: it costs more than the reset); ValueError otherwise."""
        if self._check if check is None else check:
            check_scenario(scenario or self.scenario)
        # Also without a scenario: this simulation's may have been changed in place.
        if (key or diagram_key(scenario or self.scenario)) != self._diagram_key:
            raise ValueError("the scenario differs from the built one in more than its seed, "
                             "start time, scripts and initial state: build a new Simulation")
        self.scenario = scenario or self.scenario
        self.station.diagram.SetDefaultContext(self.context)
        for name in self.robots:  # a log sink keeps its log beside the state: clear it too
            self._clear_log(self._run_log_sink(name))
            self._run_log_chunks[name].clear()
            self._max_tilt_moved_out[name] = 0.0
        if self._contact_samples is not None:
            self._clear_log(self._contact_samples.sink)
            self._contact_samples.clear()
        self.context.SetTime(self.scenario.simulator_config.start_time)
        self._start()

    def _set_per_run_values(self) -> None:
        plant = self.station.plant
        plant_context = plant.GetMyMutableContextFromRoot(self.context)
        for name, parts in self.station.robots.items():
            spec = self.scenario.robots[name]
            plant.SetFreeBodyPose(plant_context, parts.chassis, spec.pose.GetDeterministicValue())
            source = parts.command_source
            source.SetScript(source.GetMyMutableContextFromRoot(self.context), spec.commands)
            for field, sensors in parts.sensors.items():
                for sensor_name, sensor in sensors.items():
                    sensor.kind.set_seed(sensor, self.context, self.scenario.random_seed,
                                         getattr(spec, field)[sensor_name])
        for name, body in self.station.bodies.items():
            spec = self.scenario.world.bodies[name]
            if not spec.fixed:
                plant.SetFreeBodyPose(plant_context, body, spec.pose.GetDeterministicValue())

    @classmethod
    def from_file(cls, filename: str | Path, overrides: list[str] = (), meshcat=None,
                  save_camera=None, **kwargs):
        """`kwargs`: `record`, `foxglove`, as the constructor's."""
        return cls(sc.load_scenario(filename, overrides=overrides), meshcat, save_camera,
                   **kwargs)

    @property
    def time(self) -> float:
        """Simulated time now, s (the Context's; the scenario's `start_time` at the start)."""
        return self.context.get_time()

    def output_port(self, name: str):
        """The station's exported output port `name`, looked up once (a name lookup costs
        more than a cached Eval)."""
        port = self._output_ports.get(name)
        if port is None:
            port = self._output_ports[name] = self.station.diagram.GetOutputPort(name)
        return port

    @property
    def robots(self) -> dict[str, Robot]:
        """Each robot by name, in the scenario's order. A `Robot` is a view that keeps its
        Simulation alive; the Simulation keeps none of them, so it is freed the moment its
        last reference goes, in that thread, not by the cycle collector in whichever thread
        runs it next (its renderers' GL contexts must not be torn down beside another
        thread's)."""
        return {name: robot_type(parts)(self, parts)
                for name, parts in self.station.robots.items()}

    def robot(self, name: str | None = None) -> Robot:
        """The named robot; without a name, the only one."""
        if name is None:
            if len(self.robots) != 1:
                raise ValueError(f"the scenario has {len(self.robots)} robots "
                                 f"({', '.join(self.robots)}): name one")
            return next(iter(self.robots.values()))
        try:
            return self.robots[name]
        except KeyError:
            raise KeyError(unknown_robot(name, self.robots)) from None

    def _set_initial_velocities(self) -> None:
        """The scenario's robot and free-body velocities, the robots' wheel angles and
        speeds, the drive's commanded axle speeds (default: the front wheels') and hold
        angles (default: the wheel angles), the odometry's start (default: the true pose)."""
        plant = self.station.plant
        plant_context = plant.GetMyMutableContextFromRoot(self.context)
        for name, parts in self.station.robots.items():
            spec = self.scenario.robots[name]
            plant.SetFreeBodySpatialVelocity(plant_context, parts.chassis, SpatialVelocity(
                np.asarray(spec.velocity[:3]), np.asarray(spec.velocity[3:])))
            for joint, angle, speed in zip(parts.wheel_joints, spec.wheel_angles,
                                           spec.wheel_speeds, strict=True):
                joint.set_angle(plant_context, angle)
                joint.set_angular_rate(plant_context, speed)
            controller = parts.drive_controller
            controller_context = controller.GetMyMutableContextFromRoot(self.context)
            left, right = parts.spec.encoded  # the Corobot's front wheels
            command = spec.axle_speed_command or [spec.wheel_speeds[left],
                                                  spec.wheel_speeds[right]]
            if any(command):
                controller.SetAxleSpeeds(controller_context, *command)
            controller.SetHoldAngles(controller_context,
                                     spec.wheel_hold_angles or spec.wheel_angles)
            odometry = self._dead_reckoning(name)
            odometry.SetStart(odometry.GetMyMutableContextFromRoot(self.context), spec.odometry)
        for name, body in self.station.bodies.items():
            spec = self.scenario.world.bodies[name]
            if not spec.fixed:
                plant.SetFreeBodySpatialVelocity(plant_context, body, SpatialVelocity(
                    np.asarray(spec.velocity[:3]), np.asarray(spec.velocity[3:])))

    def _dead_reckoning(self, name: str):
        return self.station.diagram.GetSubsystemByName(f"{name}.dead_reckoning")

    @property
    def physics_step(self) -> float:
        """s: the physics' step (`scenario.physics_step`): a discrete plant's time step or
        CENIC's fixed step."""
        return self._physics_step

    @property
    def continuous(self) -> bool:
        """Whether the plant is continuous (stepped by CENIC): its motion then depends on
        where the Simulator stops, and every stop between its steps is a step of its own."""
        return self.continuous_step > 0

    def stop_time(self, t: float) -> float:
        """The time to stop at for a loop that may stop anywhere up to `t` (the server's
        wall clock, the Meshcat view): `t` on a discrete plant; on a continuous one its last
        physics step at or before `t` (on Drake's grid: `on_step`), so that such a loop
        changes nothing of the motion."""
        if not self.continuous_step:
            return t
        return self.on_step(math.floor(t / self._physics_step + STEP_ROUNDING)
                            * self._physics_step)

    def on_step(self, t: float) -> float:
        """`t`, or on a continuous plant, when it is within `STEP_ROUNDING` of a physics
        step k h, that step's time as Drake computes its events' (k * h), so that stopping
        there adds no step (0.1 x 3 is not 0.01 x 30 in floating point)."""
        if not self.continuous_step:
            return t
        k = round(t / self._physics_step)
        return k * self._physics_step if abs(t / self._physics_step - k) < STEP_ROUNDING else t

    @_one_thread
    def advance_to(self, t: float) -> None:
        """Advances to simulated time `t` (s; finite, not before now: ValueError otherwise),
        applying scripted SetPose teleports. On a continuous plant a `t` within rounding of
        a physics step stops on that step (`on_step`)."""
        limits.number("t", t, self.time)
        t = max(self.on_step(t), self.time)
        start = time.perf_counter()
        try:
            while True:
                self._advance_simulator(t)
                # Only a script leaves a SetPose pending (one the API issues is applied at
                # once): without one, no robot is looked at (this runs at every advance).
                if not self._scripted_teleports:
                    break
                applied = [robot._apply_teleport() for robot in self.robots.values()]
                if not any(applied) or self.time >= t:
                    break
        finally:
            self._wall_seconds += time.perf_counter() - start
        if self.run_log_window is not None:
            self._collect_run_logs()

    def _advance_simulator(self, t: float) -> None:
        """The Simulator's `AdvanceTo(t)`; CENIC's solver giving up on a step is a
        PhysicsError saying what to change."""
        try:
            self.simulator.AdvanceTo(t)
        except RuntimeError as e:
            if not (isinstance(self.simulator.get_integrator(), CenicIntegrator)
                    and any(failure in str(e) for failure in CENIC_FAILED)):
                raise  # (SAP's line search raises the same words: not cenic_solver's)
            solver = self.scenario.cenic_solver
            raise PhysicsError(
                f"cenic_solver: CENIC's step from t = {self.time:.6g} s did not converge within "
                f"max_iterations {solver.max_iterations} (line searches to linesearch_tolerance "
                f"{solver.linesearch_tolerance:g} in at most max_linesearch_iterations "
                f"{solver.max_linesearch_iterations}): raise the iterations, tighten the line "
                "search or loosen min_tolerance") from e

    def _run_log_sink(self, name: str):
        return self.station.diagram.GetSubsystemByName(f"{name}.run_log")

    def _collect_run_logs(self) -> None:
        """Bounds the run logs to `run_log_window`: once a sink holds `RUN_LOG_CHUNK` samples
        they move out of it (the sink then starts again, small) into the robot's chunks,
        whose samples older than the window go."""
        moved = False
        for name, chunks in self._run_log_chunks.items():
            sink = self._run_log_sink(name)
            log = sink.GetMutableLog(sink.GetMyMutableContextFromRoot(self.context))
            if log.num_samples() < RUN_LOG_CHUNK:
                continue
            moved = True
            chunks.append(log_rows(sink, self.context, self.robots[name]._tip_margin(),
                                   self._contact_samples, name, self.robots[name]._layout))
            self._max_tilt_moved_out[name] = max(self._max_tilt_moved_out[name],
                                                 max_tilt_deg(log.data().T))
            log.Clear()
            cutoff = self.time - self.run_log_window
            while chunks and chunks[0][-1, 0] < cutoff:
                chunks.popleft()
            if chunks and chunks[0][0, 0] < cutoff:  # a long advance: one chunk spans it
                chunks[0] = chunks[0][chunks[0][:, 0] >= cutoff].copy()
        if moved and self._contact_samples is not None:  # every robot's rows made from it
            self._contact_samples.moved_out(self.context)
            self._clear_log(self._contact_samples.sink)

    def _clear_log(self, sink) -> None:
        sink.GetMutableLog(sink.GetMyMutableContextFromRoot(self.context)).Clear()

    def saved_scenario(self) -> sc.Scenario:
        """This scenario with the current state: time, every robot's and free body's pose
        and velocity, the wheels' angles, speeds and hold angles, the drives' commanded axle
        speeds, the dead-reckoned odometry, and each robot's commands from now on
        (`Robot.continuation_commands`). Running it continues from here."""
        saved = sc.load_scenario(data=yaml_dump_typed(self.scenario, schema=sc.Scenario),
                                 defaults=sc.Scenario())
        saved.simulator_config.start_time = self.time
        plant = self.station.plant
        plant_context = plant.GetMyContextFromRoot(self.context)

        def velocity(body) -> list[float]:
            V = plant.EvalBodySpatialVelocityInWorld(plant_context, body)
            return [float(v) for v in (*V.rotational(), *V.translational())]

        for name, robot in self.robots.items():
            spec, parts = saved.robots[name], robot._parts
            spec.pose = transform_from(plant.EvalBodyPoseInWorld(plant_context, parts.chassis))
            spec.velocity = velocity(parts.chassis)
            spec.wheel_angles = [float(j.get_angle(plant_context)) for j in parts.wheel_joints]
            spec.wheel_speeds = [float(j.get_angular_rate(plant_context))
                                 for j in parts.wheel_joints]
            spec.axle_speed_command = parts.drive_controller.speeds(self.context)[1]
            spec.wheel_hold_angles = parts.drive_controller.hold_angles(self.context)
            odometry = self._dead_reckoning(name)
            spec.odometry = odometry.State(odometry.GetMyContextFromRoot(self.context))
            spec.commands = robot.continuation_commands()
        for name, body in self.station.bodies.items():
            spec = saved.world.bodies[name]
            if not spec.fixed:
                spec.pose = transform_from(plant.EvalBodyPoseInWorld(plant_context, body))
                spec.velocity = velocity(body)
        self._save_directive_poses(saved)
        return saved

    def _save_directive_poses(self, saved: sc.Scenario) -> None:
        """The free bodies of the directives' models start where they are now (their
        `default_free_body_pose`; a directive has no initial velocity: they start at rest)."""
        plant = self.station.plant
        plant_context = plant.GetMyContextFromRoot(self.context)
        for directive in saved.directives:
            model = directive.add_model
            if model is None or model.name not in self.station.models:
                continue
            poses = model.default_free_body_pose  # a copy (a C++ map): set it back
            for index in plant.GetBodyIndices(self.station.models[model.name]):
                body = plant.get_body(index)
                if body.is_floating_base_body():
                    poses[body.name()] = transform_from(
                        plant.EvalBodyPoseInWorld(plant_context, body))
            model.default_free_body_pose = poses

    def save_scenario(self, filename: str | Path) -> None:
        """Writes `saved_scenario()` as a scenario YAML file."""
        sc.save_scenario(self.saved_scenario(), filename)

    def save_recording(self, path: str | Path) -> int:
        """Writes the run so far as a self-contained Meshcat replay (HTML with its timeline;
        `recording.meshcat_html`) and carries on recording; returns the file's size in bytes.
        Needs `Simulation(..., record=True)`."""
        from corobot_drake.recording.meshcat_html import write_recording

        if self._record_live is None:
            raise RuntimeError("this simulation is not recording: build it with record=True "
                               "(--record FILE.html)")
        return write_recording(self.station.meshcat, path)

    def advance(self, seconds: float) -> None:
        """Advances by `seconds` of simulated time (a finite number >= 0; ValueError
        otherwise)."""
        self.advance_to(self.time + limits.number("seconds", seconds, 0.0))

    @_one_thread
    def run(self, duration: float, progress=None, chunk: float = 0.5) -> None:
        """Advances by `duration` s (finite, >= 0) in chunks of `chunk` s (finite, at least
        `MIN_RUN_CHUNK`), calling `progress(sim)` after each."""
        duration = limits.number("duration", duration, 0.0)
        chunk = limits.number("chunk", chunk, MIN_RUN_CHUNK)
        end = self.time + duration
        while self.time < end - 1e-12:
            # At a time so large that adding the chunk rounds to it, the last step goes to end.
            step_end = self.time + chunk
            self.advance_to(min(end, step_end) if step_end > self.time else end)
            if progress is not None:
                progress(self)

    @property
    def realtime_factor(self) -> float:
        """Simulated seconds per wall-clock second spent in advance calls so far."""
        elapsed = self.time - self.scenario.simulator_config.start_time
        return elapsed / self._wall_seconds if self._wall_seconds > 0 else math.nan

    def _placement_owners(self) -> tuple[dict, dict]:
        """({collision geometry id: `placement.Owner`}, {robot name: its Owner}) of the
        built plant's shapes, in the loader's words (made once: the geometry is fixed)."""
        if self._owners is None:
            plant, station = self.station.plant, self.station
            inspector = station.scene_graph.model_inspector()
            robots = {parts.model_instance: Owner(f"robot {name!r}", f"robots.{name}.pose",
                                                  "robot")
                      for name, parts in station.robots.items()}
            bodies = {body.index(): name for name, body in station.bodies.items()}
            welded = {b.index() for b in plant.GetBodiesWeldedTo(plant.world_body())}
            owners = {}
            for gid in inspector.GetAllGeometryIds(Role.kProximity):
                body = plant.GetBodyFromFrameId(inspector.GetFrameId(gid))
                kind = "fixed body" if body.index() in welded else "free body"
                if isinstance(inspector.GetShape(gid), HalfSpace):
                    owners[gid] = Owner("the ground", None, "ground")
                elif body.model_instance() in robots:
                    owners[gid] = robots[body.model_instance()]
                elif body.index() in bodies:
                    name = bodies[body.index()]
                    owners[gid] = Owner(f"world body {name!r}", f"world.bodies.{name}.pose",
                                        kind)
                else:
                    model = plant.GetModelInstanceName(body.model_instance())
                    owners[gid] = Owner(f"model body '{model}::{body.name()}'", None, kind)
            self._owners = owners, {name: robots[parts.model_instance]
                                    for name, parts in station.robots.items()}
        return self._owners

    def body_pose(self, body) -> BodyPose:
        """A body's pose in the world now (m, rad)."""
        plant = self.station.plant
        X = plant.EvalBodyPoseInWorld(plant.GetMyContextFromRoot(self.context), body)
        rpy = RollPitchYaw(X.rotation()).vector()
        return BodyPose(*(float(v) for v in (*X.translation(), *rpy)))

    def bodies(self) -> dict:
        """The world's bodies beside the robots, by name: `world.bodies`, then each body of the
        models the directives add, as `model::body`."""
        plant = self.station.plant
        bodies = dict(self.station.bodies)
        for model, instance in self.station.models.items():
            for index in plant.GetBodyIndices(instance):
                body = plant.get_body(index)
                bodies[f"{model}::{body.name()}"] = body
        return bodies

    def summary(self) -> dict:
        """The run's figures; only `realtime_factor` and `wall_seconds` depend on the clock."""
        return {
            "time": self.time,
            "realtime_factor": self.realtime_factor,
            "wall_seconds": self._wall_seconds,
            "robots": {name: robot.summary() for name, robot in self.robots.items()},
            "bodies": {name: {"pose": dc.asdict(self.body_pose(body))}
                       for name, body in self.bodies().items()},
        }


_PER_RUN_ROBOT_FIELDS = ("pose", "velocity", "wheel_angles", "wheel_speeds",
                         "axle_speed_command", "wheel_hold_angles", "odometry", "commands")


class PhysicsError(RuntimeError):
    """The physics could not take a step; `str()` is one line saying what to change."""


CENIC_FAILED = ("CenicIntegrator: optimization failed",
                "NewtonWithBisectionFallback did not converge")
"""What Drake's CENIC raises when its solver gives up on a step (`cenic_solver`'s limits): its
Newton iterations, or a line search, ran out (SAP's line search raises the second too)."""


def apply_simulator_config(scenario: sc.Scenario, simulator: Simulator) -> None:
    """Drake's `ApplySimulatorConfig` of the scenario's `simulator_config`, then, when that
    makes a CENIC integrator, the parameters of its solver (`cenic_solver`)."""
    ApplySimulatorConfig(scenario.simulator_config, simulator)
    integrator = simulator.get_mutable_integrator()
    if isinstance(integrator, CenicIntegrator):
        integrator.SetSolverParameters(scenario.cenic_solver)


def diagram_key(scenario: sc.Scenario) -> str:
    """The scenario as YAML without what `Simulation.reset` sets in the Context (the seed,
    start time and duration, the robots' and free bodies' initial poses and velocities, the
    wheels' initial angles, speeds and hold angles, the odometry's start, the scripts):
    scenarios with one key build one diagram."""
    s = copy.deepcopy(scenario)
    s.random_seed, s.simulation_duration = 0, math.inf
    s.simulator_config.start_time = 0.0
    default_robot, default_body = sc.Robot(), sc.WorldBody()
    for robot in s.robots.values():
        for field in _PER_RUN_ROBOT_FIELDS:
            setattr(robot, field, getattr(default_robot, field))
    for body in s.world.bodies.values():
        if not body.fixed:
            body.pose, body.velocity = default_body.pose, default_body.velocity
    return yaml_dump_typed(s, schema=sc.Scenario)


def quiet_drake_warnings() -> None:
    """Drake's warnings off (half-spaces take no part in deformable contact: we have none),
    but for those that say something a scenario gave is ignored (a model's GLB visual, which
    the cameras' renderer does not draw)."""
    drake = logging.getLogger("drake")
    drake.setLevel(logging.WARNING)
    if _only_what_is_ignored not in drake.filters:
        drake.addFilter(_only_what_is_ignored)


def _only_what_is_ignored(record: logging.LogRecord) -> bool:
    return record.levelno >= logging.ERROR or "ignored" in record.getMessage()


