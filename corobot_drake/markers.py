"""Meshcat's markers beside the scene: what each robot's sensors draw (their kind's
`add_meshcat`: rays, hits, ...) and its wheels' slip
(`systems.slip_markers`, under `/slip/<robot>`).

A station hook (`station.build_station`'s `extras`): `Simulation` attaches it when it has a
Meshcat, as `functools.partial(add_meshcat_markers, meshcat, record=...)`.
"""

from corobot_drake.robots import robot_spec
from corobot_drake.systems.slip_markers import add_slip_markers


def add_meshcat_markers(meshcat, builder, plant, scene_graph, robots: dict, scenario,
                        record: bool | None = None) -> None:
    """Adds every robot's markers ({name: station.RobotParts}) drawing in `meshcat`;
    `record`: whether it records (`systems.slip_markers.SlipMarkers`)."""
    for name, parts in robots.items():
        spec = robot_spec(scenario.robots[name].robot)
        add_slip_markers(builder, meshcat, name, parts.chassis_pose,
                         builder.GetSubsystemByName(f"{name}.wheel_contacts"), record,
                         None if spec.generated else spec)  # the Corobot's: its figures
        for sensors in parts.sensors.values():
            for sensor in sensors.values():
                sensor.kind.add_meshcat(builder, meshcat, sensor)
