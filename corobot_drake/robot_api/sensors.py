"""A robot's sensors: every kind's readings by name (`RobotSensors`, every `Robot`'s), and the
IR sensors' and cameras' own accessors (`IrSensors`, `Cameras`), which only a robot with such a
part has (`simulation.robot_type`). A robot without a kind's sensors has none of its names
(`ir_names`, `camera_names` are empty).
"""


import numpy as np

from corobot_drake.config.sensors import FRONT_CAMERA
from corobot_drake.readings import IrReading
from corobot_drake.sensors.kind import BuiltSensor, SensorKind
from corobot_drake.sensors.registry import KINDS


class RobotSensors:
    """Every kind's sensors by name (`sensors.registry.KINDS`)."""

    def sensors(self) -> dict[str, dict[str, SensorKind]]:
        """The sensors built, by kind and name: {kind field (`ir_sensors`, `cameras`, ...):
        {sensor name: its `SensorKind`}}, every registered kind (those turned off left out)."""
        return {kind.field: {name: kind for name in self._parts.sensors.get(kind.field, {})}
                for kind in KINDS}

    @property
    def ir_names(self) -> tuple[str, ...]:
        """The IR sensors' names (`front`, `rear`, ...), in the scenario's order."""
        return tuple(self._parts.ir_sensors)

    def ir_distances(self) -> dict[str, float]:
        """The latest raw reading of every IR sensor, metres, by name ({} without any: the
        `ir_distances` signal of every robot)."""
        context = self._sim.context
        return {name: sensor.reading(sensor.GetMyContextFromRoot(context)).raw
                for name, sensor in self._parts.ir_sensors.items()}

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

    def _sensor(self, name: str, kind: str | None = None) -> BuiltSensor:
        """The sensor `name` (of the kind whose field or topic stem is `kind`; without it, a
        name sensors of several kinds share is the first kind's in `KINDS`' order: the
        Corobot's `front` is its IR sensor, `kind="cameras"` its camera); KeyError naming
        those the robot has."""
        order = {k.field: i for i, k in enumerate(KINDS)}
        found = sorted((s for field, sensors in self._parts.sensors.items()
                        for n, s in sensors.items()
                        if n == name and kind in (None, field, s.kind.topic)),
                       key=lambda s: order.get(s.kind.field, len(order)))
        if found:
            return found[0]
        have = [f"{field}.{n}" for field, sensors in self._parts.sensors.items() for n in sensors]
        raise KeyError(f"robot {self.name!r} has no sensor {name!r}"
                       + (f" of kind {kind!r}" if kind else "")
                       + f"; it has {', '.join(have) or 'none'}")

    def reading(self, name: str, kind: str | None = None):
        """The latest reading of the sensor `name`, of any kind: its kind's reading type
        (`IrReading`, `CameraImage`, ...; the kind's module states its units and frame).
        `kind` (a kind's field, e.g. `cameras`, or topic stem, `camera`) picks among sensors
        of several kinds that share the name; without it, the first kind's in the registry's
        order (`sensors.registry.KINDS`: IR sensors first, so the Corobot's `front`, which
        its IR sensor and its camera share, is the IR sensor's). KeyError naming the robot's
        sensors for one it lacks."""
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


class IrSensors:
    """The IR sensors' own accessors (distances by sensor name): a robot with IR sensors
    has them (`Simulation.robots`), one without has none of them."""

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


class Cameras:
    """The cameras' own accessors (images by camera name): a robot with a camera has them
    (`Simulation.robots`), one without has none of them."""

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
