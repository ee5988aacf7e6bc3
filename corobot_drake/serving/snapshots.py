"""What the simulation thread publishes for the HTTP side: each robot's services' state as
JSON-ready dicts (`snapshot`), and what does not change while serving (`RobotInfo`).

Called in the simulation thread (they read the Context through the Python API). The dicts they
return are never mutated afterwards, so any thread, or the HTTP process, may read them.
"""

from __future__ import annotations

import dataclasses as dc
import math
from typing import Any

from corobot_drake import commands, signals
from corobot_drake.config.sensors import FRONT_CAMERA
from corobot_drake.readings import IrReading


def jsonable(value: Any) -> Any:
    """Dataclasses, numpy scalars/arrays and non-finite floats (None) made JSON-safe."""
    if type(value) is float:  # the most common, first
        return value if math.isfinite(value) else None
    if dc.is_dataclass(value) and not isinstance(value, type):
        return {f.name: jsonable(getattr(value, f.name)) for f in dc.fields(value)}
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if isinstance(value, bool | int | str) or value is None:
        return value
    if hasattr(value, "tolist"):  # numpy
        return jsonable(value.tolist())
    f = float(value)
    return f if math.isfinite(f) else None


@dc.dataclass(frozen=True)
class RobotInfo:
    """One robot's services that are fixed once the simulation is built."""

    name: str
    ir_services: tuple[str, ...]
    """Its IR sensors' service names (`front_ir`, `rear_ir`, ...)."""
    cameras: tuple[str, ...]
    """Its cameras' names (`front`, ...; those turned off left out)."""
    ir_change_thresholds: tuple[tuple[str, float], ...] = ()
    """(service name, m): the reading change each IR sensor counts as a change."""
    sensors: tuple[tuple[str, tuple[str, ...]], ...] = ()
    """(kind field, its sensors' names) of every registered kind (`Robot.sensors`)."""

    @classmethod
    def of(cls, robot) -> RobotInfo:
        """The info of a `simulation.Robot`."""
        return cls(robot.name, tuple(f"{name}_ir" for name in robot.ir_names),
                   robot.camera_names,
                   tuple((f"{name}_ir", robot.ir_change_threshold(name))
                         for name in robot.ir_names),
                   tuple((field, tuple(names)) for field, names in robot.sensors().items()))

    @property
    def has_camera(self) -> bool:
        """Whether it has the front camera (the webcam at `/robots/<robot>/camera`)."""
        return FRONT_CAMERA in self.cameras

    @property
    def capabilities(self) -> dict[str, bool]:
        """The HTTP contract's `capabilities`: every robot has the whole drive API; the IR API
        and the camera are offered to a robot that has them (its scenario and robot file)."""
        completing = {spec.method: True for spec in commands.ISSUABLE if spec.completing}
        return {**completing, "drive_state": True, "ir": bool(self.ir_services),
                "camera": self.has_camera}


def command_json(record) -> dict:
    """A command's life as the drive state reports it (`command`), from its command-log
    record (`systems.drive.CommandRecord`) or the Python API's `CommandResult`."""
    return {"seq": record.seq, "command": record.command, "status": record.status,
            "reason": record.reason, "start_time": record.start_time,
            "end_time": record.end_time}


def drive_state(robot, time: float) -> dict:
    """The drive contract's state (MRDS DriveDifferentialFourWheelState in SI units, for
    the robot's wheels, each with its `side`) without its signals: the drive's fixed figures,
    whether it is enabled and the latest command; `robot_snapshot` puts the signals in
    (`signals.Signal.http`: the wheels' power, axle speed, ticks and contact telemetry,
    position, heading, pose, velocity and tip margin)."""
    native = robot.drive_state()
    last = robot.last_command()
    spec = robot.spec
    return {
        "time_stamp": time,
        "is_enabled": bool(native.is_enabled),
        "power_scaling_factor": float(native.power_scaling_factor),
        "distance_between_wheels": float(native.distance_between_wheels),
        "wheel_radius": spec.wheel_radius,
        "encoder_ticks_per_revolution": spec.encoder_ticks_per_revolution,
        "wheels": {w.short: {"side": "left" if w.side > 0 else "right"} for w in spec.wheels},
        "command": command_json(last) if last is not None else None,
    }


def two_wheel_view(state: dict) -> dict:
    """The generic differential-drive view of `drive_state`: left and right are each side's
    wheel with an encoder (the Corobot's front left and front right)."""
    w = state["wheels"]
    left, right = (next(wheel for wheel in w.values() if wheel["side"] == side
                        and wheel.get("encoder_ticks") is not None) for side in ("left", "right"))
    return {
        "time_stamp": state["time_stamp"],
        "is_enabled": state["is_enabled"],
        "distance_between_wheels": state["distance_between_wheels"],
        "left": left,
        "right": right,
        "position": state["position"],
        "heading": state["heading"],
        "command": state["command"],
    }


def analog_sensor(reading: IrReading) -> dict:
    """The analog-sensor contract's state of one IR scan: raw (m), range (m), normalized,
    time_stamp (s, the scan's time)."""
    return jsonable({"raw": float(reading.raw), "range": float(reading.range),
                     "normalized": float(reading.normalized),
                     "time_stamp": float(reading.time)})


def robot_snapshot(robot, time: float) -> dict:
    """Every service's state of one robot: drive, ir (by service name), encoders, compass,
    gps; each signal at its places (`signals.Signal.http`); and every sensor's latest reading
    by kind and name (`sensors`: {kind field: {name: `SensorKind.to_json`}}). A per-wheel
    field that some wheels lack (the rear wheels' encoder ticks) is null."""
    stamp = {"time_stamp": time}
    state = {
        "drive": drive_state(robot, time),
        "ir": {f"{name}_ir": analog_sensor(robot.ir(name)) for name in robot.ir_names},
        "encoders": {**stamp, "ticks_per_revolution": robot.spec.encoder_ticks_per_revolution},
        "compass": dict(stamp),
        "gps": dict(stamp),
        "sensors": robot.sensor_readings(),
    }
    for spec in signals.SIGNALS.values():  # the names: each robot's keys are its own
        if spec.http:
            value = robot.signal(spec.name)
            for place in spec.http:
                signals.put_value(state, place, value)
    wheels = state["drive"]["wheels"].values()
    for field in {f for wheel in wheels for f in wheel}:
        for wheel in wheels:
            wheel.setdefault(field, None)
    return jsonable(state)


def snapshot(sim) -> dict:
    """The whole published state: simulated time and every robot's `robot_snapshot`."""
    return {"time": sim.time,
            "robots": {name: robot_snapshot(robot, sim.time)
                       for name, robot in sim.robots.items()}}
