"""Every kind of sensor a robot may carry: `KINDS`, one line a kind.

A kind is one module under `corobot_drake/sensors/` with its `SensorKind` subclass
(`sensors/kind.py`); registering it here is all the rest of the project needs: the scenario's
`Robot` gets its map (`robots.<robot>.<kind.field>.<sensor>`), the loader its checks, the
station its two build phases, and every front end its readings by sensor name.
"""

from __future__ import annotations

from corobot_drake.sensors.bumper import BumperKind
from corobot_drake.sensors.camera import CameraKind
from corobot_drake.sensors.imu import ImuKind
from corobot_drake.sensors.ir_sensor import IrSensorKind
from corobot_drake.sensors.kind import BuiltSensor, SensorKind
from corobot_drake.sensors.lidar import LidarKind
from corobot_drake.sensors.site import SensorSite

KINDS: tuple[SensorKind, ...] = (
    IrSensorKind(),
    CameraKind(),
    LidarKind(),
    ImuKind(),
    BumperKind(),
)
"""The registered kinds, in the order the scenario's maps and the front ends list them."""


def kind(field: str) -> SensorKind:
    """The registered kind whose `Robot` map is `field` (KeyError naming the kinds)."""
    for k in KINDS:
        if k.field == field:
            return k
    raise KeyError(f"no sensor kind {field!r}; the kinds are "
                   f"{', '.join(k.field for k in KINDS)}")


def add_geometry(plant, model_instance, robot_name: str, robot) -> None:
    """Before the plant is finalized: each sensor's own geometry and frames (`robot` a
    scenario `Robot`), kind by kind; sensors turned off add none."""
    for k in KINDS:
        for name, config in getattr(robot, k.field).items():
            if k.enabled(config):
                k.add_geometry(plant, model_instance, robot_name, name, config)


def add_sensors(site: SensorSite, robot) -> dict[str, dict[str, BuiltSensor]]:
    """After the plant is finalized: adds every sensor of `robot` (a scenario `Robot`) at
    `site`, kind by kind; returns {kind field: {name: BuiltSensor}} of the sensors built
    (those turned off left out)."""
    built = {}
    for k in KINDS:
        sensors = {name: k.add(site, name, config)
                   for name, config in getattr(robot, k.field).items()}
        built[k.field] = {name: s for name, s in sensors.items() if s is not None}
    return built
