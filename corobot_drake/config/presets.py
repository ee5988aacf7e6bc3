"""Scenario overrides that switch a robot's sensors, shared by the tuning tools and the lab.

Each is YAML text for `load_scenario(..., overrides=[...])`.
"""

import json

from corobot_drake.config import scenario as sc
from corobot_drake.sensors.registry import KINDS

IR_RATE_HZ = 20.0
"""Hz: the IR scan rate `sensor_overrides` sets (the Corobot's: 20 Hz)."""
CAMERA_FPS = 30.0
"""Hz: the camera frame rate `sensor_overrides` sets (the Corobot's: 30 Hz)."""


def sensor_overrides(robot: str = "corobot", ir: bool = False, camera: bool = False
                     ) -> list[str]:
    """Overrides that turn the robot's IR sensors and its camera on (at `IR_RATE_HZ` and
    `CAMERA_FPS`) or off."""
    sensors = ", ".join(f"{n}: {{enabled: {str(ir).lower()}, scan_rate_hz: {IR_RATE_HZ}}}"
                        for n in sc.Robot().ir_sensors)
    cameras = ", ".join(f"{n}: {{rgb: {str(camera).lower()}, fps: {CAMERA_FPS}}}"
                        for n in sc.Robot().cameras)
    return [f"robots: {{{robot}: {{ir_sensors: {{{sensors}}}}}}}",
            f"robots: {{{robot}: {{cameras: {{{cameras}}}}}}}"]


def physics_only_overrides(robot: str = "corobot") -> list[str]:
    """No sensor of any kind (each of the robot's default sensors turned off by its kind's
    `SensorKind.off`; a kind whose sensors must stay is left as it is): the physics and the
    drive alone."""
    out = []
    for kind in KINDS:
        if kind.off is None or not kind.defaults():
            continue
        off = ", ".join(f"{field}: {json.dumps(value)}" for field, value in kind.off.items())
        sensors = ", ".join(f"{name}: {{{off}}}" for name in kind.defaults())
        out.append(f"robots: {{{robot}: {{{kind.field}: {{{sensors}}}}}}}")
    return out
