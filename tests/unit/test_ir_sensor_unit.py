"""IrSensor on its own: a diagram of SceneGraph and the sensor, with (or without) one box
registered straight in SceneGraph; the reading is compared with the analytic distance.

The sensor rides on SceneGraph's world frame (its "chassis" is the world), so its pose is its
configured pose; the test reads the rays' origin and directions from the sensor's own
`ray_origin` / `ray_end` outputs with nothing to hit, then puts a box face across them.
"""

import numpy as np
import pytest
from pydrake.geometry import Box, GeometryInstance, ProximityProperties, SceneGraph
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from corobot_drake.config.sensors import IrSensorConfig
from corobot_drake.sensors.ir_sensor import IrSensor

FACE_DISTANCE = 0.3  # m from the sensor to the box face, along its look direction
THICKNESS = 0.1  # m: the box's extent along the look direction
EXACT = 1e-9  # m: a ray-box intersection in doubles


def scan(box_pose: RigidTransform | None = None, exclude_box: bool = False,
         config: IrSensorConfig | None = None, until: float = 0.0):
    """(sensor, its context after `until` s) in a scene of at most one 0.1 x 2 x 2 m box."""
    builder = DiagramBuilder()
    scene_graph = builder.AddSystem(SceneGraph())
    source = scene_graph.RegisterSource("test")
    exclude = []
    if box_pose is not None:
        box = scene_graph.RegisterAnchoredGeometry(
            source, GeometryInstance(box_pose, Box(THICKNESS, 2.0, 2.0), "box"))
        scene_graph.AssignRole(source, box, ProximityProperties())
        if exclude_box:
            exclude.append(box)
    sensor = builder.AddSystem(IrSensor(config or IrSensorConfig(),
                                        scene_graph.world_frame_id(), exclude, name="front"))
    builder.Connect(scene_graph.get_query_output_port(), sensor.GetInputPort("query_object"))
    simulator = Simulator(builder.Build())
    simulator.AdvanceTo(until)  # initializes: the first scan is taken at initialization
    return sensor, sensor.GetMyContextFromRoot(simulator.get_context())


def out(sensor, context, port: str) -> np.ndarray:
    return sensor.GetOutputPort(port).Eval(context)


@pytest.fixture(scope="module")
def rays():
    """(origin, unit directions N x 3, look direction, range) of the default sensor."""
    sensor, context = scan()
    rng = out(sensor, context, "range")[0]
    origin = out(sensor, context, "ray_origin")
    directions = (out(sensor, context, "ray_end").reshape(-1, 3) - origin) / rng
    look = directions.sum(axis=0)
    return origin, directions, look / np.linalg.norm(look), rng


def box_across(rays) -> RigidTransform:
    """A box whose near face is FACE_DISTANCE ahead of the sensor, square to its look."""
    origin, _, look, _ = rays
    return RigidTransform(RotationMatrix.MakeFromOneVector(look, 0),
                          origin + (FACE_DISTANCE + THICKNESS / 2) * look)


def test_nothing_to_hit_reads_the_maximum_range(rays):
    _, directions, _, rng = rays
    sensor, context = scan()
    assert out(sensor, context, "distance")[0] == rng == IrSensorConfig().maximum_range
    assert out(sensor, context, "normalized")[0] == 1.0
    assert out(sensor, context, "true_distance")[0] == rng
    assert np.isnan(out(sensor, context, "hit_points")).all()
    np.testing.assert_array_equal(out(sensor, context, "ray_hit"), 0.0)
    np.testing.assert_allclose(np.linalg.norm(directions, axis=1), 1.0, atol=1e-12)
    assert len(directions) == 2 * IrSensorConfig().samples


def test_reading_is_the_analytic_distance_to_a_box_face(rays):
    origin, directions, look, rng = rays
    sensor, context = scan(box_across(rays))
    along = FACE_DISTANCE / (directions @ look)  # each ray's distance to the face plane
    assert along.max() < rng  # every ray hits (the face is 2 m wide, the fans 8 deg)
    reading = out(sensor, context, "reading")
    expected = along.min()  # the centre ray: 0.3 m exactly (3 samples per fan)
    assert expected == pytest.approx(FACE_DISTANCE, abs=1e-12)
    np.testing.assert_allclose(reading, [expected, rng, expected / rng, 0.0], atol=EXACT)
    assert out(sensor, context, "true_distance")[0] == pytest.approx(expected, abs=EXACT)
    np.testing.assert_array_equal(out(sensor, context, "ray_hit"), 1.0)
    hits = out(sensor, context, "hit_points").reshape(-1, 3)
    np.testing.assert_allclose(hits, origin + along[:, None] * directions, atol=EXACT)


def test_excluded_geometry_is_never_hit(rays):
    sensor, context = scan(box_across(rays), exclude_box=True)
    assert out(sensor, context, "distance")[0] == rays[3]


def test_scans_at_the_scan_rate(rays):
    config = IrSensorConfig()
    period = 1.0 / config.scan_rate_hz
    sensor, context = scan(box_across(rays), until=2.5 * period)
    assert out(sensor, context, "scan_time")[0] == pytest.approx(2 * period, abs=1e-12)
    assert out(sensor, context, "changed")[0] == 0.0  # nothing moved since the last scan
    assert out(sensor, context, "distance")[0] == pytest.approx(FACE_DISTANCE, abs=EXACT)
