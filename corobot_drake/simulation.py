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
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.cenic import CenicIntegrator
from pydrake.multibody.math import SpatialVelocity
from pydrake.systems.analysis import ApplySimulatorConfig, Simulator
from pydrake.systems.framework import EventStatus

from corobot_drake import commands, limits, signals
from corobot_drake.config import scenario as sc
from corobot_drake.config.placement import Owner, Problem, overlap_problems
from corobot_drake.config.poses import ground_pose, transform_from
from corobot_drake.config.sensors import FRONT_CAMERA
from corobot_drake.config.validate import check_scenario
from corobot_drake.names import unknown_robot
from corobot_drake.readings import (
    BodyPose,
    BodyVelocity,
    CommandResult,
    IrReading,
    OdometryPose,
)
from corobot_drake.robots import robot_spec
from corobot_drake.sensors.kind import BuiltSensor, SensorKind
from corobot_drake.sensors.registry import KINDS
from corobot_drake.station import RobotParts, Station, build_station
from corobot_drake.systems.drive import CommandRecord, DriveStatus
from corobot_drake.systems.odometry import DriveState
from corobot_drake.systems.runlog import (
    RUN_LOG_CHUNK,
    ContactSamples,
    log_rows,
    max_tilt_deg,
    spec_layout,
    tip_margins,
    write_csv,
)

STEP_ROUNDING = 1e-6
"""Steps: a time this close to a physics step (in steps, 10 ns at 10 ms) is on it
(`Simulation.on_step`)."""

MIN_RUN_CHUNK = 1e-4
"""s: the shortest chunk `Simulation.run` advances by (a smaller one is refused: at 1e-300 s
the time never moved and `run` never ended)."""

_log = logging.getLogger(__name__)


def _one_thread(method):
    """`method` (of a Simulation or a Robot) run holding its Simulation's lock; RuntimeError
    at once if another thread holds it. A Drake Context is not thread-safe: two threads
    advancing one simulation corrupt its time and state."""

    @functools.wraps(method)
    def guarded(self, *args, **kwargs):
        lock = getattr(self, "_sim", self)._thread_lock
        if not lock.acquire(blocking=False):
            raise RuntimeError(f"{method.__name__}: another thread is advancing or commanding "
                               "this Simulation; use it from one thread at a time")
        try:
            return method(self, *args, **kwargs)
        finally:
            lock.release()

    return guarded


class CommandHandle:
    """A command issued without waiting: poll `status()` / `done()` while the simulation
    advances (and other commands are issued), or `wait()` for it to end."""

    def __init__(self, robot: "Robot", seq: int):
        self.robot, self.seq = robot, seq

    def __repr__(self) -> str:
        """E.g. `<CommandHandle corobot seq 3: DriveDistance succeeded, t = 0.500 to 2.310 s>`."""
        head = f"<CommandHandle {self.robot.name} seq {self.seq}"
        try:
            r = self.result()
        except KeyError:  # the command log keeps the newest records only
            return f"{head}: no longer in the command log>"
        return f"{head}: {r.describe()}>"

    def result(self) -> CommandResult:
        return self.robot.command_result(self.seq)

    def status(self) -> str:
        return self.result().status

    def done(self) -> bool:
        return self.result().end_time is not None

    def wait(self, timeout: float | None = 300.0) -> CommandResult:
        """Advances the simulation (one control period at a time) until the command ends;
        TimeoutError after `timeout` simulated seconds (None: no limit)."""
        timeout = _check_timeout(timeout)
        sim = self.robot._sim
        period = self.robot._parts.motion.drive_period
        end = math.inf if timeout is None else sim.time + timeout
        while not self.done():
            if sim.time >= end:
                raise TimeoutError(f"{self.result().command} (seq {self.seq}) still running "
                                   f"after {timeout} s")
            sim.advance(period)
        return self.result()


def _check_timeout(timeout: float | None) -> float | None:
    """A command's wait limit: None (no limit) or a number of simulated s > 0."""
    if timeout is None:
        return None
    return limits.number("timeout", timeout, 0.0, low_open=True, finite=False)


class Robot:
    """One robot of a running simulation: its commands and measurements. A view: it keeps
    its Simulation alive and holds nothing of its own (`Simulation.robots` makes them)."""

    def __init__(self, sim: "Simulation", parts: RobotParts):
        self._sim = sim
        self._parts = parts
        self.name = parts.name
        self.spec = robot_spec(sim.scenario.robots[parts.name].robot)
        """What the robot is (`robots.RobotSpec`): its wheels, radius, track, drive, links."""
        self._layout = spec_layout(self.spec)
        """Its run log's columns and its signals (`runlog.Layout`: keyed by its wheels)."""

    # --- commands -------------------------------------------------------------------------
    @_one_thread
    def issue(self, command) -> int:
        """Issues a scenario command dataclass now; returns its sequence number. ValueError
        (naming the allowed range) for a command the API does not take or an argument out of
        its range (`commands.check`)."""
        return self._issue_checked(commands.check(command))

    def _issue_checked(self, command) -> int:
        source = self._parts.command_source
        seq = source.Issue(source.GetMyMutableContextFromRoot(self._sim.context), command)
        self._apply_teleport()  # a SetPose takes the robot there now
        return seq

    @_one_thread
    def command(self, method: str, *args, **kwargs):
        """Issues the command `method` names (`commands.COMMANDS`: `set_power`, ...) with its
        arguments, as the methods below do: returns its sequence number, or a `CommandHandle`
        for a command that completes (without waiting). ValueError for an unknown command or
        an argument out of its range, TypeError for arguments it does not take."""
        spec = commands.by_method(method)
        seq = self._issue_checked(commands.make(method, *args, **kwargs))  # make checks it
        return CommandHandle(self, seq) if spec.completing else seq

    def set_power(self, left: float, right: float) -> int:
        """Power per side in [-1, 1]: axle speed = power x MotorTorqueScaling."""
        return self.command("set_power", left, right)

    def set_speed(self, left: float, right: float) -> int:
        """Rim speed per side, m/s, in [-5, 5] (`limits.SIDE_SPEED`; the drive clamps the axle
        speed to its max axle speed)."""
        return self.command("set_speed", left, right)

    def set_velocity(self, linear: float, angular: float) -> int:
        """Chassis velocity, ROS `cmd_vel` style: `linear` m/s forward, `angular` rad/s
        (positive: left), through the skid-steer kinematics (`commands.SetVelocity`); in
        [-5, 5] m/s and [-50, 50] rad/s (`limits`; ValueError otherwise)."""
        return self.command("set_velocity", linear, angular)

    def all_stop(self) -> int:
        return self.command("all_stop")

    def enable(self, enabled: bool = True) -> int:
        """Enables (True) or disables (False) the drive."""
        return self.command("enable", enabled)

    def drive_distance_async(self, distance: float, power: float = 0.5) -> CommandHandle:
        """Starts driving straight |distance| m (distance in [-100, 100]; negative: backwards)
        at `power` in (0, 1]."""
        return self.command("drive_distance", distance, power)

    def drive_distance(self, distance: float, power: float = 0.5,
                       timeout: float | None = 300.0) -> CommandResult:
        """Drives straight |distance| m (negative: backwards) at `power`, advancing the
        simulation until the command ends; returns how it ended. `timeout`: simulated s > 0,
        or None for no limit."""
        _check_timeout(timeout)
        return self.drive_distance_async(distance, power).wait(timeout)

    def rotate_degrees_async(self, degrees: float, power: float = 0.5) -> CommandHandle:
        """Starts turning in place by `degrees` in [-3600, 3600] (positive: counter-clockwise,
        left) at `power` in (0, 1]."""
        return self.command("rotate_degrees", degrees, power)

    def rotate_degrees(self, degrees: float, power: float = 0.5,
                       timeout: float | None = 300.0) -> CommandResult:
        """Turns in place by `degrees` (positive: left), advancing the simulation until the
        command ends; returns how it ended."""
        _check_timeout(timeout)
        return self.rotate_degrees_async(degrees, power).wait(timeout)

    @_one_thread
    def set_pose(self, x: float, y: float, yaw_deg: float = 0.0) -> CommandHandle:
        """Teleports the robot now to (x, y) m facing `yaw_deg`, on the ground, at rest, the
        wheels stopped; a running command fails as superseded. The returned handle ends
        (succeeded) once the robot has settled there (`motion.POSE_SETTLE_TIME`), or at once
        failed, reason `blocked`, if the robot there would be inside another body
        (`obstacle_at`, logged in the loader's words): then it stays where it was (its drive
        stopping). x, y in [-10000, 10000] m, yaw_deg in [-3600, 3600] (ValueError
        otherwise)."""
        return self.command("set_pose", x, y, yaw_deg)

    def _apply_teleport(self) -> bool:
        """Applies a pending SetPose to the plant (and stops the drive); True if there was one."""
        parts, root = self._parts, self._sim.context
        source = parts.command_source
        request = source.TakeTeleport(source.GetMyMutableContextFromRoot(root))
        if request is None:
            return False
        pose = request.command
        X_WB = ground_pose(pose.x, pose.y, pose.yaw_deg).GetDeterministicValue()
        problem = self.obstacle_at(X_WB)
        if problem is not None:
            _log.warning("SetPose %s blocked: %s", request.seq, problem.message)
            source.Fail(source.GetMyMutableContextFromRoot(root), request.seq, "blocked")
            return True
        plant = self._sim.station.plant
        plant_context = plant.GetMyMutableContextFromRoot(root)
        plant.SetFreeBodyPose(plant_context, parts.chassis, X_WB)
        plant.SetFreeBodySpatialVelocity(plant_context, parts.chassis, SpatialVelocity.Zero())
        for joint in parts.wheel_joints:
            joint.set_angular_rate(plant_context, 0.0)
        controller = parts.drive_controller
        controller.Halt(controller.GetMyMutableContextFromRoot(root))
        odometry = self._sim._dead_reckoning(self.name)  # reset there, as a driver's would be
        odometry.Teleport(odometry.GetMyMutableContextFromRoot(root), pose.x, pose.y,
                          math.radians(pose.yaw_deg))
        return True

    def obstacle_at(self, X_WB: RigidTransform) -> Problem | None:
        """What the robot would overlap with its chassis at `X_WB`, by the loader's check of
        a start pose (`placement.overlap_problems`: more than `OVERLAP_TOLERANCE`; what loads,
        SetPose accepts), in its words: the `Problem` (`.message`; `.obstacle.name`: `world
        body 'giant_box'`, a model's body, another robot), or None if the pose is clear. The
        ground (any half-space) does not count: a SetPose stands the robot on it. The Context
        is left as it was (the pose is tried, then the plant's positions are put back
        exactly)."""
        plant = self._sim.station.plant
        plant_context = plant.GetMyMutableContextFromRoot(self._sim.context)
        q = plant.GetPositions(plant_context)
        try:
            plant.SetFreeBodyPose(plant_context, self._parts.chassis, X_WB)
            query = plant.get_geometry_query_input_port().Eval(plant_context)
            me = self._sim._placement_owners()[1][self.name]
            problems = overlap_problems(query.ComputePointPairPenetration(),
                                        self._sim._placement_owners()[0].get)
            return next((p for p in problems
                         if p.subject == me and p.obstacle.kind != "ground"), None)
        finally:
            plant.SetPositions(plant_context, q)

    def continuation_commands(self) -> list:
        """Commands that carry on from now: the enable level, the running command (a
        DriveDistance/RotateDegrees carried on from where it is, the last
        SetPower/SetSpeed/SetVelocity, or an AllStop while the drive slews down to 0, also
        one not yet taken), then the script's unissued rest (after what is left of a running
        Wait, or a Wait of 0 s when it is due: it then starts at the update the saved run's
        would have)."""
        root = self._sim.context
        source, motion = self._parts.command_source, self._parts.motion
        state = source.current_state(source.GetMyContextFromRoot(root))
        commands = [] if state.request.enabled else [sc.Enable(False)]
        remaining = motion.remaining_command(motion.GetMyContextFromRoot(root))
        if remaining is not None:
            commands.append(remaining)
        elif isinstance(state.request.command, sc.SetPower | sc.SetSpeed | sc.SetVelocity):
            commands.append(state.request.command)
        else:
            target, commanded = self._parts.drive_controller.speeds(root)
            stopping = isinstance(state.request.command, sc.AllStop)  # maybe not yet taken
            if (stopping or not any(target)) and any(commanded):
                # Slewing down to 0 (an AllStop, an ended command): the reloaded drive starts
                # from the commanded speeds and must stop, not hold them.
                commands.append(sc.AllStop())
        script = source.script(source.GetMyContextFromRoot(root))
        if state.next_script_index < len(script):
            if state.script_blocked_until > self._sim.time:
                commands.append(sc.Wait(state.script_blocked_until - self._sim.time))
            elif remaining is None:
                # Due now: the source issues it at its next update (also one at this very
                # instant, not yet run), not with what is carried on at the start.
                commands.append(sc.Wait(0.0))
            commands += script[state.next_script_index:]
        return commands

    # --- measurements ---------------------------------------------------------------------
    def _plant_context(self):
        return self._sim.station.plant.GetMyContextFromRoot(self._sim.context)

    def pose(self) -> BodyPose:
        return self._sim.body_pose(self._parts.chassis)

    def velocity(self) -> BodyVelocity:
        plant = self._sim.station.plant
        V = plant.EvalBodySpatialVelocityInWorld(self._plant_context(), self._parts.chassis)
        yaw = self.pose().yaw
        c, s = math.cos(yaw), math.sin(yaw)
        vx, vy = V.translational()[:2]
        return BodyVelocity(float(c * vx + s * vy), float(-s * vx + c * vy),
                            float(V.rotational()[2]))

    def axle_speeds(self) -> dict[str, float]:
        """Measured axle speeds, rad/s, by wheel name."""
        return self.signal("axle_speeds")

    def drive_state(self) -> DriveState:
        """The four-wheel drive state (`.two_wheel()`: the differential-drive view)."""
        return self._sim.station.diagram.GetOutputPort(f"{self.name}.drive_state").Eval(
            self._sim.context)

    def encoders(self) -> dict[str, int]:
        """Front-wheel encoder counts, 600 ticks per revolution, by wheel name."""
        return self.signal("encoders")

    def heading(self) -> float:
        """Compass: chassis yaw about world z, rad in (-pi, pi]."""
        return self.signal("heading")

    def position(self) -> tuple[float, float, float]:
        """GPS: the chassis frame's origin in the world, m."""
        return tuple(self.signal("position").values())

    def odometry(self) -> OdometryPose:
        """Dead reckoning from the encoders (`systems.dead_reckoning`, with the drive's
        effective wheel radius and track width) from the start pose: x, y m, yaw rad."""
        return OdometryPose(**self.signal("odometry"))

    def signal(self, name: str):
        """The value now of the signal `name` (`signals.SIGNALS`): read from its port, or by
        its `reader`; a float, or a dict of floats by key (wheel, field or sensor name)."""
        spec = self._layout.signals[name]
        if spec.reader:
            value = getattr(self, spec.reader)()
            return dc.asdict(value) if dc.is_dataclass(value) else value
        return spec.value_of(self._sim.output_port(f"{self.name}.{spec.port}").Eval(
            self._sim.context))

    def commanded_power(self) -> dict[str, float]:
        """The drive's commanded power per wheel (its side's), in [-1, 1], by wheel name."""
        return {w: float(state.commanded_power)
                for w, state in self.drive_state().wheels.items()}

    def wheel_loads(self) -> dict[str, float]:
        """Each wheel's load, N: the vertical component of its contact forces
        (`systems.contact`), by wheel name; at rest they sum to the robot's weight."""
        return self.signal("wheel_loads")

    def wheel_slip_ratio(self) -> dict[str, float]:
        """Each wheel's longitudinal slip ratio (`systems.contact`), by wheel name:
        (rim speed - ground speed) / the faster, + traction (the wheel turns faster than it
        travels, forwards or backwards), - braking; 0 at rest."""
        return self.signal("wheel_slip_ratio")

    def wheel_slip_angle(self) -> dict[str, float]:
        """Each wheel's slip angle, deg (`systems.contact`), by wheel name: atan2(its centre's
        speed across the heading (+ left), its speed along it); 0 at rest."""
        return self.signal("wheel_slip_angle")

    def tip_margin_deg(self) -> float:
        """How far (deg) the robot can still roll or pitch before its centre of mass passes
        an edge of the wheels' support polygon (`systems.stability`); upright on level
        ground 37.4 deg (pitch), negative while tipping over."""
        return self.signal("tip_margin")

    def min_tip_margin_deg(self) -> float:
        """The least `tip_margin_deg` so far, deg: over the run log's rows (every 10 ms; with
        `Simulation.run_log_window`, its window) and now."""
        sim = self._sim
        # From the samples' chassis alone: the contact telemetry need not be made.
        raw = sim._run_log_sink(self.name).FindLog(sim.context).data().T
        margins = [chunk[:, self._layout.columns.index("tip_margin")]
                   for chunk in sim._run_log_chunks[self.name]]
        margins.append(tip_margins(raw, self._tip_margin()))
        return float(min(min(m.min(initial=math.inf) for m in margins), self.tip_margin_deg()))

    def enable_requested(self) -> bool:
        """The enable level last commanded (is_enabled() follows it at the next control tick)."""
        source = self._parts.command_source
        return source.get_state(source.GetMyContextFromRoot(self._sim.context)).request.enabled

    def is_enabled(self) -> bool:
        status = self._sim.station.diagram.GetOutputPort(f"{self.name}.drive_status").Eval(
            self._sim.context)
        return bool(DriveStatus(status).enabled)

    def max_tilt_deg(self) -> float:
        """Largest tilt from upright so far, deg: over the run log's samples of the chassis
        (every 10 ms from the start, the whole run: `runlog.max_tilt_deg`), the start's
        included."""
        sim = self._sim
        log = sim._run_log_sink(self.name).FindLog(sim.context)
        return max(sim._max_tilt_moved_out[self.name], max_tilt_deg(log.data().T))

    # --- sensors, of every kind (`sensors.registry.KINDS`) ------------------------------------
    def sensors(self) -> dict[str, dict[str, SensorKind]]:
        """The sensors built, by kind and name: {kind field (`ir_sensors`, `cameras`, ...):
        {sensor name: its `SensorKind`}}, every registered kind (those turned off left out)."""
        return {kind.field: {name: kind for name in self._parts.sensors.get(kind.field, {})}
                for kind in KINDS}

    def _sensor(self, name: str, kind: str | None = None) -> BuiltSensor:
        """The sensor `name` (of the kind whose field or topic stem is `kind`, needed when
        sensors of several kinds share the name); KeyError naming those the robot has."""
        found = [s for field, sensors in self._parts.sensors.items() for n, s in sensors.items()
                 if n == name and kind in (None, field, s.kind.topic)]
        if len(found) == 1:
            return found[0]
        if found:
            raise KeyError(f"robot {self.name!r} has sensors {name!r} of several kinds ("
                           f"{', '.join(s.kind.field for s in found)}); say which: "
                           f"reading({name!r}, kind={found[0].kind.field!r})")
        have = [f"{field}.{n}" for field, sensors in self._parts.sensors.items() for n in sensors]
        raise KeyError(f"robot {self.name!r} has no sensor {name!r}"
                       + (f" of kind {kind!r}" if kind else "")
                       + f"; it has {', '.join(have) or 'none'}")

    def reading(self, name: str, kind: str | None = None):
        """The latest reading of the sensor `name`, of any kind: its kind's reading type
        (`IrReading`, `CameraImage`, ...; the kind's module states its units and frame).
        `kind` (a kind's field, e.g. `cameras`, or topic stem, `camera`) picks among sensors
        of several kinds that share the name (the Corobot's IR sensor and camera are both
        `front`). KeyError naming the robot's sensors for one it lacks."""
        return self._sensor(name, kind).read(self._sim.context)

    def sensor_json(self, name: str, kind: str | None = None) -> dict:
        """The latest reading of the sensor `name` as JSON (`SensorKind.to_json`: what HTTP and
        the summary show)."""
        sensor = self._sensor(name, kind)
        return sensor.kind.read_json(sensor, self._sim.context)

    def sensor_readings(self, summary: bool = False) -> dict[str, dict[str, dict]]:
        """Every sensor's latest reading as JSON, {kind field: {name: JSON}}: as HTTP shows it
        (`SensorKind.to_json`), or with `summary` as the run's summary holds it
        (`SensorKind.summary_json`)."""
        context = self._sim.context
        return {field: {name: s.kind.read_json(s, context, summary) for name, s in sensors.items()}
                for field, sensors in self._parts.sensors.items()}

    def ir(self, name: str) -> IrReading:
        """The latest scan of the named IR sensor (`front`, `rear`, ...): raw distance (m),
        range (m), normalized = raw / range, and the scan's time (s)."""
        try:
            sensor = self._parts.ir_sensors[name]
        except KeyError:
            raise KeyError(f"robot {self.name!r} has no IR sensor {name!r}; it has "
                           f"{', '.join(self._parts.ir_sensors) or 'none'}") from None
        return sensor.reading(sensor.GetMyContextFromRoot(self._sim.context))

    def ir_change_threshold(self, name: str) -> float:
        """m: the reading change the named IR sensor counts as a change (its scenario's
        `change_threshold`)."""
        return self._parts.ir_sensors[name].change_threshold

    @property
    def ir_names(self) -> tuple[str, ...]:
        """The IR sensors' names (`front`, `rear`, ...), in the scenario's order."""
        return tuple(self._parts.ir_sensors)

    def ir_distances(self) -> dict[str, float]:
        """The latest raw reading of every IR sensor, metres, by name."""
        return {name: self.ir(name).raw for name in self._parts.ir_sensors}

    def run_log(self):
        """The run log so far (numpy rows; columns its `runlog.Layout`'s: time, left_power,
        right_power, left_ticks, right_ticks, x, y, yaw), sampled every `runlog.LOG_PERIOD` s;
        with `Simulation.run_log_window`, only its last part."""
        sim = self._sim
        rows = log_rows(sim._run_log_sink(self.name), sim.context, self._tip_margin(),
                        sim._contact_samples, self.name, self._layout)
        chunks = sim._run_log_chunks[self.name]
        return np.concatenate([*chunks, rows]) if chunks else rows

    def _tip_margin(self):
        return self._sim.station.diagram.GetSubsystemByName(f"{self.name}.tip_margin")

    def write_log(self, path: str | Path) -> None:
        """Writes the run log as CSV (columns in docs/tuning.md; read by
        `corobot_drake.tuning.sysid`)."""
        write_csv(self.run_log(), path, self._layout)

    # --- cameras --------------------------------------------------------------------------
    @property
    def camera_names(self) -> tuple[str, ...]:
        """The cameras' names (`front`, ...), in the scenario's order; those turned off
        (`rgb: false`) left out."""
        return tuple(self._parts.cameras)

    @property
    def has_camera(self) -> bool:
        """Whether the robot has its front camera (`config.sensors.FRONT_CAMERA`), the one
        `camera_image()` reads without a name."""
        return FRONT_CAMERA in self._parts.cameras

    def _camera(self, name: str | None):
        name = FRONT_CAMERA if name is None else name
        camera = self._parts.cameras.get(name)
        if camera is None:
            raise KeyError(f"robot {self.name!r} has no camera {name!r} (turned off or not in "
                           f"robots.{self.name}.cameras); it has "
                           f"{', '.join(self._parts.cameras) or 'none'}")
        return camera

    def camera_image(self, name: str | None = None):
        """The latest frame of the camera `name` (default: the front camera): a numpy array
        height x width x 4 (RGBA), uint8, a copy; None before the first. Frames are captured
        at the camera's fps and appear `output_delay` s later (the default camera: 30 Hz,
        0.03 s, so the first appears at 0.03 s); with no delay, the first is rendered at
        initialization. KeyError naming the cameras for one the robot lacks."""
        camera = self._camera(name)
        image = camera.image.Eval(camera.system.GetMyContextFromRoot(self._sim.context))
        if image.width() == 0:
            return None
        return np.array(image.data, dtype=np.uint8, copy=True)

    def camera_image_time(self, name: str | None = None) -> float:
        """Simulated time (s) at which the latest frame of the camera `name` (default: the
        front camera) was captured (NaN before the first)."""
        camera = self._camera(name)
        return float(camera.image_time.Eval(
            camera.system.GetMyContextFromRoot(self._sim.context))[0])

    def camera_frames_saved(self) -> int:
        """How many frames the robot's cameras wrote as PNG (0 unless saving,
        `--save-camera`)."""
        return sum(c.saver.frames_saved for c in self._parts.cameras.values()
                   if c.saver is not None)

    def camera_save_problems(self) -> list[str]:
        """One line for each of the robot's cameras whose frames could not all be written
        where asked (a full disk): the file, why, and where they went instead
        (`CameraFrameSaver.problem`); the run goes on either way."""
        return [problem for c in self._parts.cameras.values()
                if c.saver is not None and (problem := c.saver.problem()) is not None]

    def command_result(self, seq: int) -> CommandResult:
        """How the command with sequence number `seq` has gone so far (its command-log
        record); KeyError if this robot issued no such command."""
        source = self._parts.command_source
        r = source.record(source.GetMyContextFromRoot(self._sim.context), seq)
        if r is None:
            raise KeyError(f"robot {self.name!r} issued no command {seq}")
        return CommandResult(r.seq, r.command, r.status, r.reason, r.start_time, r.end_time)

    def command_log(self) -> list[CommandRecord]:
        """Every command's record, oldest first (the newest `drive.COMMAND_LOG_CAPACITY`)."""
        source = self._parts.command_source
        return list(source.current_state(source.GetMyContextFromRoot(self._sim.context)).log)

    def last_command(self) -> CommandRecord | None:
        """The newest record of the command log (None before any), without copying the log."""
        source = self._parts.command_source
        log = source.current_state(source.GetMyContextFromRoot(self._sim.context)).log
        return log[-1] if log else None

    def telemetry(self) -> dict:
        """The contact telemetry now, as `summary` reports it (`signals.TELEMETRY`: each
        signal at its `summary` place)."""
        out: dict = {}
        for spec in signals.TELEMETRY:
            signals.put_value(out, spec.summary, self.signal(spec.name))
        return out

    def summary(self) -> dict:
        """The robot's figures now: every signal at its `summary` place (`signals.SIGNALS`:
        `wheel_loads_N` (N) and `slip`'s `ratio` and `angle_deg` lists are per wheel in
        `dimensions.WHEEL_NAMES` order), the largest tilt, the frames saved, the least tip
        margin over the run (`min_tip_margin_deg`), each sensor's latest reading
        (`sensor_readings`) and the command log."""
        out: dict = {"max_tilt_deg": self.max_tilt_deg(),
                     "camera_frames": self.camera_frames_saved()}
        for spec in signals.SIGNALS.values():
            if spec.summary:
                signals.put_value(out, spec.summary, self.signal(spec.name))
        return {
            **out,
            "min_tip_margin_deg": self.min_tip_margin_deg(),
            "sensors": self.sensor_readings(summary=True),
            "commands": [
                {"command": r.command, "status": r.status, "reason": r.reason,
                 "start_time": r.start_time, "end_time": r.end_time}
                for r in self.command_log()
            ],
        }


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
                 check: bool = True, extras=()):
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
        topics)."""
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

            extras.append(functools.partial(add_foxglove_topics, context=foxglove))
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
        return {name: Robot(self, parts) for name, parts in self.station.robots.items()}

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
            command = spec.axle_speed_command or spec.wheel_speeds[:2]
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


