"""Meshcat's markers beside the scene: each robot's IR rays and hit points
(`sensors.ir_sensor.IrMeshcatVisualizer`, under `/ir/<robot>/<sensor>`) and its wheels' slip
(`systems.slip_markers`, under `/slip/<robot>`).

A station hook (`station.build_station`'s `extras`): `Simulation` attaches it when it has a
Meshcat, as `functools.partial(add_meshcat_markers, meshcat, record=...)`.
"""

from corobot_drake.sensors.ir_sensor import add_ir_meshcat
from corobot_drake.systems.slip_markers import add_slip_markers


def add_meshcat_markers(meshcat, builder, plant, scene_graph, robots: dict, scenario,
                        record: bool | None = None) -> None:
    """Adds every robot's markers ({name: station.RobotParts}) drawing in `meshcat`;
    `record`: whether it records (`systems.slip_markers.SlipMarkers`)."""
    for name, parts in robots.items():
        add_slip_markers(builder, meshcat, name, parts.chassis_pose,
                         builder.GetSubsystemByName(f"{name}.wheel_contacts"), record)
        add_ir_meshcat(builder, meshcat, name, parts.ir_sensors)
