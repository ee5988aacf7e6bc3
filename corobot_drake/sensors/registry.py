"""Every kind of sensor a robot may carry, and the one function that adds each.

A robot's sensors are one typed map per kind (`config.sensors.SENSOR_KINDS`: the `Robot`
field and its config type); here each kind's field names its `add_<kind>(site, name, config)`,
which adds one sensor (named by its map key) to the diagram and returns its handle, or None
when the config turns it off. A new kind: its config type and `Robot` field
(`config/sensors.py`, `config/scenario.py`), its `add_<kind>`, and its entry here.
"""

from collections.abc import Callable

from corobot_drake.sensors.camera import add_camera
from corobot_drake.sensors.ir_sensor import add_ir_sensor
from corobot_drake.sensors.site import SensorSite

ADD_SENSOR: dict[str, Callable] = {
    "ir_sensors": add_ir_sensor,
    "cameras": add_camera,
}
"""{`Robot` field (`SENSOR_KINDS`): its `add_<kind>(site, name, config)`}."""


def add_sensors(site: SensorSite, robot) -> dict[str, dict[str, object]]:
    """Adds every sensor of `robot` (a scenario `Robot`) at `site`, kind by kind; returns
    {kind: {name: handle}} of the sensors built (those turned off left out)."""
    built = {}
    for kind, add in ADD_SENSOR.items():
        handles = {name: add(site, name, config) for name, config in getattr(robot, kind).items()}
        built[kind] = {name: h for name, h in handles.items() if h is not None}
    return built
