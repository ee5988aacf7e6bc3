"""The Python API: build a simulation from a scenario, drive its robots, read them back.

    sim = Simulation.from_file("scenarios/corobot.yaml")
    bot = sim.robot()            # the only robot, or sim.robot("name")
    bot.set_power(0.5, 0.5)
    sim.advance(2.0)             # simulated seconds
    print(bot.pose(), sim.summary())

All of a run's memory is in the Drake Context, so two runs of one scenario agree bit for bit.
"""

import dataclasses as dc
import logging
import math
import time
from pathlib import Path

import numpy as np
from pydrake.math import RollPitchYaw
from pydrake.systems.analysis import ApplySimulatorConfig, Simulator

from corobot_drake import dimensions as dim
from corobot_drake import scenario as sc
from corobot_drake.drive import CommandRecord
from corobot_drake.ir_sensor import IrReading
from corobot_drake.runlog import log_rows, write_csv
from corobot_drake.station import RobotParts, Station, build_station


@dc.dataclass(frozen=True)
class BodyPose:
    """Chassis pose in the world: metres and radians (roll, pitch, yaw extrinsic x-y-z)."""

    x: float
    y: float
    z: float
    roll: float
    pitch: float
    yaw: float


@dc.dataclass(frozen=True)
class BodyVelocity:
    """Chassis velocity in its own heading frame: forward, lateral (m/s), yaw_rate (rad/s)."""

    forward: float
    lateral: float
    yaw_rate: float


class Robot:
    """One robot of a running simulation: its commands and measurements."""

    def __init__(self, sim: "Simulation", parts: RobotParts):
        self._sim = sim
        self._parts = parts
        self.name = parts.name

    # --- commands -------------------------------------------------------------------------
    def issue(self, command) -> int:
        """Issues a scenario command dataclass now; returns its sequence number."""
        source = self._parts.command_source
        return source.Issue(source.GetMyMutableContextFromRoot(self._sim.context), command)

    def set_power(self, left: float, right: float) -> int:
        """Power per side in [-1, 1] (clamped): axle speed = power x MotorTorqueScaling."""
        return self.issue(sc.SetPower(float(left), float(right)))

    def set_speed(self, left: float, right: float) -> int:
        """Rim speed per side, m/s (axle speed clamped to the drive's max axle speed)."""
        return self.issue(sc.SetSpeed(float(left), float(right)))

    def all_stop(self) -> int:
        return self.issue(sc.AllStop())

    def enable(self, enabled: bool = True) -> int:
        return self.issue(sc.Enable(bool(enabled)))

    # --- measurements ---------------------------------------------------------------------
    def _plant_context(self):
        return self._sim.station.plant.GetMyContextFromRoot(self._sim.context)

    def pose(self) -> BodyPose:
        X = self._sim.station.plant.EvalBodyPoseInWorld(self._plant_context(),
                                                       self._parts.chassis)
        rpy = RollPitchYaw(X.rotation()).vector()
        return BodyPose(*(float(v) for v in (*X.translation(), *rpy)))

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
        v = self._sim.station.diagram.GetOutputPort(f"{self.name}.axle_speed").Eval(
            self._sim.context)
        return {w: float(x) for w, x in zip(dim.WHEEL_NAMES, v, strict=True)}

    def is_enabled(self) -> bool:
        status = self._sim.station.diagram.GetOutputPort(f"{self.name}.drive_status").Eval(
            self._sim.context)
        return bool(status[0])

    def max_tilt_deg(self) -> float:
        """Largest tilt from upright so far (degrees, sampled at 100 Hz)."""
        monitor = self._parts.tilt_monitor
        return float(monitor.get_output_port().Eval(monitor.GetMyContextFromRoot(
            self._sim.context))[0])

    def ir(self, name: str) -> IrReading:
        """The latest scan of the named IR sensor (`front`, `rear`, ...): raw distance (m),
        range (m), normalized = raw / range, and the scan's time (s)."""
        try:
            sensor = self._parts.ir_sensors[name]
        except KeyError:
            raise KeyError(f"robot {self.name!r} has no IR sensor {name!r}; it has "
                           f"{', '.join(self._parts.ir_sensors) or 'none'}") from None
        return sensor.reading(sensor.GetMyContextFromRoot(self._sim.context))

    def ir_distances(self) -> dict[str, float]:
        """The latest raw reading of every IR sensor, metres, by name."""
        return {name: self.ir(name).raw for name in self._parts.ir_sensors}

    def run_log(self):
        """The run log so far (numpy rows; columns `runlog.COLUMNS`: time, left_power,
        right_power, left_ticks, right_ticks, x, y, yaw), sampled every `runlog.LOG_PERIOD` s."""
        sink = self._sim.station.diagram.GetSubsystemByName(f"{self.name}.run_log")
        return log_rows(sink, self._sim.context)

    def write_log(self, path: str | Path) -> None:
        """Writes the run log as CSV (columns in docs/tuning.md; read by corobot_drake.sysid)."""
        write_csv(self.run_log(), path)

    # --- camera ---------------------------------------------------------------------------
    @property
    def has_camera(self) -> bool:
        return self._parts.camera_hold is not None

    def _camera_port(self, which: str):
        if not self.has_camera:
            raise RuntimeError(f"robot {self.name!r} has no camera "
                               f"(robots.{self.name}.camera.rgb is false)")
        return self._sim.station.diagram.GetOutputPort(f"{self.name}.camera.{which}")

    def camera_image(self):
        """The latest camera frame: a numpy array height x width x 4 (RGBA), uint8, a copy.
        Frames are rendered at the camera's fps (and at initialization)."""
        image = self._camera_port("rgb_image").Eval(self._sim.context)
        return np.array(image.data, dtype=np.uint8, copy=True)

    def camera_image_time(self) -> float:
        """Simulated time (s) at which the latest camera frame was rendered."""
        return float(self._camera_port("image_time").Eval(self._sim.context)[0])

    def camera_frames_saved(self) -> int:
        """How many frames were written as PNG (0 unless saving, `--save-camera`)."""
        saver = self._parts.camera_saver
        return saver.frames_saved if saver is not None else 0

    def command_log(self) -> list[CommandRecord]:
        source = self._parts.command_source
        return list(source.get_state(source.GetMyContextFromRoot(self._sim.context)).log)

    def summary(self) -> dict:
        pose, velocity = self.pose(), self.velocity()
        return {
            "pose": dc.asdict(pose),
            "velocity": dc.asdict(velocity),
            "max_tilt_deg": self.max_tilt_deg(),
            "camera_frames": self.camera_frames_saved(),
            "ir": self.ir_distances(),
            "wheels": self.axle_speeds(),
            "commands": [
                {"command": r.command, "status": r.status, "reason": r.reason,
                 "start_time": r.start_time, "end_time": r.end_time}
                for r in self.command_log()
            ],
        }


class Simulation:
    """A scenario built into a Drake diagram with its Simulator and Context."""

    def __init__(self, scenario: sc.Scenario, meshcat=None, save_camera=None):
        """`save_camera`: a directory; each robot's camera frames go to `<dir>/<robot>/`."""
        self.scenario = scenario
        self.station: Station = build_station(scenario, meshcat, save_camera)
        self.simulator = Simulator(self.station.diagram)
        ApplySimulatorConfig(scenario.simulator_config, self.simulator)
        self.context = self.simulator.get_mutable_context()
        self.robots = {name: Robot(self, parts) for name, parts in self.station.robots.items()}
        self.simulator.Initialize()
        self._wall_seconds = 0.0

    @classmethod
    def from_file(cls, filename: str | Path, overrides: list[str] = (), meshcat=None,
                  save_camera=None):
        return cls(sc.load_scenario(filename, overrides=overrides), meshcat, save_camera)

    @property
    def time(self) -> float:
        return self.context.get_time()

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
            raise KeyError(f"no robot named {name!r}; robots: {', '.join(self.robots)}") from None

    def advance_to(self, t: float) -> None:
        start = time.perf_counter()
        self.simulator.AdvanceTo(t)
        self._wall_seconds += time.perf_counter() - start

    def advance(self, seconds: float) -> None:
        self.advance_to(self.time + seconds)

    def run(self, duration: float, progress=None, chunk: float = 0.5) -> None:
        """Advances by `duration` s in chunks, calling `progress(sim)` after each."""
        end = self.time + duration
        while self.time < end - 1e-12:
            self.advance_to(min(end, self.time + chunk))
            if progress is not None:
                progress(self)

    @property
    def realtime_factor(self) -> float:
        """Simulated seconds per wall-clock second spent in advance calls so far."""
        elapsed = self.time - self.scenario.simulator_config.start_time
        return elapsed / self._wall_seconds if self._wall_seconds > 0 else math.nan

    def summary(self) -> dict:
        """The run's figures; only `realtime_factor` and `wall_seconds` depend on the clock."""
        return {
            "time": self.time,
            "realtime_factor": self.realtime_factor,
            "wall_seconds": self._wall_seconds,
            "robots": {name: robot.summary() for name, robot in self.robots.items()},
        }


def quiet_drake_warnings() -> None:
    """Drake warns that half-spaces take no part in deformable contact (we have none)."""
    logging.getLogger("drake").setLevel(logging.ERROR)


