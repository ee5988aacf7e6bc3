"""The planar lidar alone: its config's checks and angles, its scans against analytic walls,
boxes, cylinders and spheres (a robot that is one welded `chassis` box, world geometry
anchored around it), the REP 117 ranges, the noise's statistics and replay, the dropouts, and
its kind's wire messages."""

import gc
import math

import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.geometry import (
    Box,
    Cylinder,
    ProximityProperties,
    QueryObject,
    SceneGraphInspector,
    Sphere,
)
from pydrake.math import RigidTransform
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.multibody.tree import SpatialInertia
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from corobot_drake.config.poses import mount
from corobot_drake.sensors.lidar import (
    NEAREST,
    NEAREST_BEARING,
    RANGES_START,
    SCAN_INDEX,
    SCAN_TIME,
    LaserScan,
    Lidar,
    LidarConfig,
    LidarKind,
    check_lidar,
    default_mount,
    scan_angles,
)
from corobot_drake.sensors.raycast import model_instance_geometry_ids
from corobot_drake.sensors.site import SensorSite

EXACT = 1e-9
"""m: a ray's closed-form intersection in doubles, a few ulps of metres."""
HEIGHT = 0.5
"""m: the scan plane's height above the robot's origin in these scenes."""
KIND = LidarKind()


def site_with(*bodies: tuple[object, RigidTransform]) -> SensorSite:
    """A site on robot `bot`: a 0.2 m box `chassis` welded at the world origin (its own
    geometry, which its sensors do not see) and each (shape, X_WG) anchored in the world."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.01)
    bot = plant.AddModelInstance("bot")
    chassis = plant.AddRigidBody("chassis", bot, SpatialInertia.SolidBoxWithMass(
        1.0, 0.2, 0.2, 0.2))
    plant.WeldFrames(plant.world_frame(), chassis.body_frame())
    plant.RegisterCollisionGeometry(chassis, RigidTransform(), Box(0.2, 0.2, 0.2), "chassis",
                                    ProximityProperties())
    for i, (shape, X_WG) in enumerate(bodies):
        plant.RegisterCollisionGeometry(plant.world_body(), X_WG, shape, f"body{i}",
                                        ProximityProperties())
    plant.Finalize()
    return SensorSite(builder, plant, scene_graph, "bot", bot)


def config(**changes) -> LidarConfig:
    """A lidar at HEIGHT above the chassis origin, looking along +x, with `changes`."""
    return LidarConfig(**{"X_PB": mount((0.0, 0.0, HEIGHT), (0.0, 0.0, 0.0)), **changes})


def scan(site: SensorSite, lidar_config: LidarConfig):
    """(the BuiltSensor, its Simulator, initialized: the first scan taken)."""
    sensor = KIND.add(site, "top", lidar_config)
    simulator = Simulator(site.builder.Build())
    simulator.Initialize()
    return sensor, simulator


def wall(d: float) -> tuple[object, RigidTransform]:
    """A 0.1 m thick wall, 40 m wide, its near face at x = d."""
    return Box(0.1, 40.0, 4.0), RigidTransform([d + 0.05, 0.0, HEIGHT])


# --- the config ---------------------------------------------------------------------------


def test_the_default_is_a_360_ray_full_circle_on_top_of_the_corobot():
    c = LidarConfig()
    increment, angle_max = scan_angles(c)
    assert c.samples == 360 and c.scan_rate_hz == 10.0 and (c.range_min, c.range_max) == (
        0.15, 12.0)
    assert increment == pytest.approx(math.radians(1.0), abs=1e-15)
    assert angle_max == pytest.approx(math.pi - math.radians(1.0), abs=1e-14)
    assert c.X_PB.base_frame == "chassis"
    np.testing.assert_allclose(default_mount(), (0.0, 0.0, 0.22225 + 0.05), rtol=0, atol=1e-12)
    assert list(c.X_PB.translation) == list(default_mount())
    assert KIND.defaults() == {} and isinstance(KIND.new_sensor("any"), LidarConfig)


def test_a_partial_span_puts_its_last_ray_on_angle_max_and_one_ray_at_angle_min():
    assert scan_angles(LidarConfig(angle_min=-math.pi / 2, angle_max=math.pi / 2,
                                   samples=181)) == pytest.approx((math.pi / 180, math.pi / 2))
    assert scan_angles(LidarConfig(angle_min=0.3, angle_max=0.3, samples=1)) == (0.0, 0.3)
    # YAML's rounded pi is still a full circle: no bearing cast twice.
    assert scan_angles(LidarConfig(angle_min=-3.1416, angle_max=3.1416, samples=4))[0] == \
        pytest.approx(math.pi / 2)


@pytest.mark.parametrize(("changes", "field"), [
    ({"range_min": 5.0, "range_max": 2.0}, "range_min"),
    ({"range_min": 2.0, "range_max": 2.0}, "range_min"),
    ({"angle_min": 1.0, "angle_max": -1.0}, "angle_max"),
    ({"angle_min": -math.pi, "angle_max": math.pi + 0.01}, "angle_max"),
])
def test_check_names_an_inverted_range_or_span(changes, field):
    problems = KIND.check(LidarConfig(**changes))
    assert [f for f, _ in problems] == [field]
    assert check_lidar(LidarConfig()) == []


# --- analytic scenes ------------------------------------------------------------------------


def test_a_wall_reads_its_distance_over_the_cosine_of_each_bearing():
    d = 1.0
    sensor, simulator = scan(site_with(wall(d)), config())
    reading = sensor.read(simulator.get_context())
    assert isinstance(reading, LaserScan) and reading.time == 0.0
    a = reading.bearings()
    expected = np.where(np.cos(a) > 0, d / np.cos(a), np.inf)
    expected[expected > 12.0] = np.inf  # beyond range_max: +inf (REP 117)
    ranges = np.array(reading.ranges)
    assert np.array_equal(np.isinf(ranges), np.isinf(expected))
    hit = np.isfinite(expected)
    assert hit.sum() == 171  # |bearing| < acos(1/12) = 85.2 deg, 1 deg apart
    np.testing.assert_allclose(ranges[hit], expected[hit], rtol=0, atol=EXACT)


def test_a_turned_lidar_reads_in_its_own_frame():
    """Yawed 90 deg left, the wall ahead of the robot is at the lidar's bearing -90 deg."""
    site = site_with(wall(2.0))
    sensor, simulator = scan(site, config(X_PB=mount((0.0, 0.0, HEIGHT), (0.0, 0.0, 90.0)),
                                          angle_min=-math.pi / 2, angle_max=0.0, samples=91))
    ranges = np.array(sensor.read(simulator.get_context()).ranges)
    a = np.linspace(-math.pi / 2, 0.0, 91)
    with np.errstate(divide="ignore"):
        expected = np.where(np.sin(-a) > 2.0 / 12.0, 2.0 / np.sin(-a), np.inf)
    np.testing.assert_allclose(ranges, expected, rtol=0, atol=EXACT)


def box_range(a: np.ndarray, face: float, half_width: float) -> np.ndarray:
    """Distance along bearing a to the face x = face (|y| <= half_width), inf off it."""
    with np.errstate(divide="ignore"):
        t = np.where(np.cos(a) > 0, face / np.cos(a), np.inf)
    return np.where(np.abs(t * np.sin(a)) <= half_width, t, np.inf)


def circle_range(a: np.ndarray, c: np.ndarray, r: float) -> np.ndarray:
    """Distance along bearing a to a circle of centre c (2,) and radius r, inf for a miss."""
    d = np.column_stack([np.cos(a), np.sin(a)])
    b = d @ c
    disc = b * b - (c @ c - r * r)
    t = b - np.sqrt(np.maximum(disc, 0.0))
    return np.where((disc >= 0) & (t >= 0), t, np.inf)


def fixed_lidar(lidar_config: LidarConfig, *bodies):
    """The Lidar alone: a LeafSystem whose query_object input is fixed to the scene graph's
    value in a small diagram of `bodies`; (lidar, its context, initialized)."""
    site = site_with(*bodies)
    diagram = site.builder.Build()
    root = diagram.CreateDefaultContext()
    query = site.scene_graph.get_query_output_port().Eval(
        site.scene_graph.GetMyContextFromRoot(root))
    plant = site.plant
    chassis = plant.GetBodyByName("chassis", site.model_instance)
    lidar = Lidar(lidar_config, plant.GetBodyFrameIdOrThrow(chassis.index()),
                  model_instance_geometry_ids(plant, site.model_instance))
    context = lidar.CreateDefaultContext()
    lidar.get_input_port(0).FixValue(context, AbstractValue.Make(query))
    lidar.ExecuteInitializationEvents(context)
    return lidar, context


def test_the_leaf_system_alone_reads_a_box_a_cylinder_and_a_sphere_exactly():
    """A 1 x 1 box ahead (near face at x = 1.5), an upright cylinder of radius 0.4 on the left
    at (0, 2), a sphere of radius 0.3 centred in the scan plane at (-1, -1): every ray's range
    is the nearest closed form, inf elsewhere (nothing behind them within range_max)."""
    cylinder_at, sphere_at = np.array([0.0, 2.0]), np.array([-1.0, -1.0])
    lidar, context = fixed_lidar(
        config(range_max=5.0),
        (Box(1.0, 1.0, 1.0), RigidTransform([2.0, 0.0, HEIGHT])),
        (Cylinder(0.4, 2.0), RigidTransform([*cylinder_at, HEIGHT])),
        (Sphere(0.3), RigidTransform([*sphere_at, HEIGHT])))
    ranges = lidar.GetOutputPort("ranges").Eval(context)
    a = lidar.GetOutputPort("reading").Eval(context).bearings()
    expected = np.minimum.reduce([box_range(a, 1.5, 0.5), circle_range(a, cylinder_at, 0.4),
                                  circle_range(a, sphere_at, 0.3)])
    assert np.array_equal(np.isinf(ranges), np.isinf(expected))
    assert 3 * 10 < np.isfinite(expected).sum() < 90  # each shape hit by several rays
    np.testing.assert_allclose(ranges[np.isfinite(expected)],
                               expected[np.isfinite(expected)], rtol=0, atol=EXACT)


def test_the_leaf_system_scans_at_its_rate_and_keeps_its_state_in_the_context():
    lidar, context = fixed_lidar(config(scan_rate_hz=20.0), wall(1.0))
    first = lidar.GetOutputPort("scan_state").Eval(context).copy()
    assert (first[SCAN_INDEX], first[SCAN_TIME]) == (0.0, 0.0)
    simulator = Simulator(lidar, context)
    simulator.AdvanceTo(0.12)
    state = lidar.GetOutputPort("scan_state").Eval(context)
    assert (state[SCAN_INDEX], state[SCAN_TIME]) == (2.0, 0.1)  # scans at 0, 0.05, 0.1
    np.testing.assert_array_equal(state[RANGES_START:], first[RANGES_START:])  # a still scene
    assert lidar.GetOutputPort("reading").Eval(context).time == 0.1


def test_the_state_keeps_the_nearest_range_and_its_bearing_for_the_run_log():
    """A wall 1 m ahead: the nearest range is the ray straight ahead's (bearing 0: the 360 rays
    from -pi put one there), 1 m; with nothing within range_max, (inf, NaN)."""
    lidar, context = fixed_lidar(config(range_max=5.0), wall(1.0))
    state = lidar.GetOutputPort("scan_state").Eval(context)
    assert (state[NEAREST], state[NEAREST_BEARING]) == pytest.approx((1.0, 0.0), abs=EXACT)
    assert state[NEAREST] == np.nanmin(state[RANGES_START:])
    lidar, context = fixed_lidar(config(range_max=0.5), wall(1.0))
    state = lidar.GetOutputPort("scan_state").Eval(context)
    assert state[NEAREST] == math.inf and math.isnan(state[NEAREST_BEARING])
    assert lidar.nearest(np.array([-math.inf, math.nan, 2.0, 0.7, math.inf])) == (
        0.7, pytest.approx(lidar.config.angle_min + 3 * lidar.increment))


def test_a_lidar_keeps_no_view_of_a_context_that_is_gone():
    """As the IR sensors: once its Simulator is gone, no QueryObject or inspector of that
    Context stays alive through the lidar (its caster keeps a copy of the geometry version)."""
    sensor, simulator = scan(site_with(wall(1.0)), config())
    simulator.AdvanceTo(0.15)
    del simulator
    gc.collect()
    assert [type(o).__name__ for o in gc.get_objects()
            if isinstance(o, (QueryObject, SceneGraphInspector))] == []
    assert sensor.system._casters.current is not None  # the caster itself lives on


def test_too_near_reads_minus_inf_and_the_robot_never_sees_itself():
    """A box 0.1 m from the scan's centre (under range_min) reads -inf (REP 117); the lidar at
    the chassis box's centre, inside its own robot, still reads the wall."""
    lidar, context = fixed_lidar(config(range_min=0.15),
                                 (Box(0.02, 0.02, 0.02), RigidTransform([0.1, 0.0, HEIGHT])))
    assert lidar.GetOutputPort("ranges").Eval(context)[180] == -math.inf  # bearing 0
    lidar, context = fixed_lidar(config(X_PB=mount((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))),
                                 (Box(0.1, 40.0, 4.0), RigidTransform([1.05, 0.0, 0.0])))
    assert lidar.GetOutputPort("ranges").Eval(context)[180] == pytest.approx(1.0, abs=EXACT)


# --- noise and dropouts -------------------------------------------------------------------


def test_range_noise_is_gaussian_with_its_std_and_unbiased():
    """36 000 draws (100 scans x 360 rays of a 2 m truth): the mean is 0 within 5 standard
    errors (5 x 0.02 / 190 = 0.5 mm), the std within 2% (its standard error is 0.4%), and 68.3%
    fall within one sigma (+-1.2%, 5 standard errors)."""
    lidar = Lidar(config(noise_std=0.02), None, ())
    truth = np.full(360, 2.0)
    errors = np.concatenate([lidar.measured(truth, 1234, k) - truth for k in range(100)])
    assert abs(errors.mean()) < 5 * 0.02 / math.sqrt(len(errors))
    assert errors.std() == pytest.approx(0.02, rel=0.02)
    assert np.mean(np.abs(errors) < 0.02) == pytest.approx(0.6827, abs=0.012)


def test_dropouts_are_nan_at_their_probability_and_the_rest_keep_their_noise():
    """dropout 0.1 over 36 000 rays: NaN in 10% (+-0.8%, 5 standard errors); a ray's noise
    is the same with and without dropouts (both drawn from the same counter)."""
    truth = np.full(360, 2.0)
    dropping = Lidar(config(noise_std=0.02, dropout=0.1), None, ())
    keeping = Lidar(config(noise_std=0.02), None, ())
    scans = [(dropping.measured(truth, 7, k), keeping.measured(truth, 7, k))
             for k in range(100)]
    dropped = np.concatenate([d for d, _ in scans])
    assert np.isnan(dropped).mean() == pytest.approx(0.1, abs=0.008)
    for d, k in scans:
        np.testing.assert_array_equal(d[~np.isnan(d)], k[~np.isnan(d)])


def test_noise_is_a_function_of_key_and_scan_and_misses_stay_inf():
    lidar = Lidar(config(noise_std=0.05, dropout=0.2, range_max=3.0), None, ())
    truth = np.array([1.0, 2.999, np.inf] * 100)
    a, b = lidar.measured(truth, 99, 5), lidar.measured(truth, 99, 5)
    np.testing.assert_array_equal(a, b)  # NaNs in the same places too
    assert not np.array_equal(a, lidar.measured(truth, 99, 6), equal_nan=True)
    assert not np.array_equal(a, lidar.measured(truth, 98, 5), equal_nan=True)
    misses = a[2::3]
    assert np.all(np.isnan(misses) | (misses == np.inf))
    near_max = a[1::3]  # noise takes about half of the 2.999 m hits beyond range_max
    assert 0.25 < np.mean(near_max == np.inf) < 0.75


def test_a_reset_simulation_replays_its_noise_bit_for_bit_and_another_seed_differs():
    site = site_with(wall(1.0))
    sensor, simulator = scan(site, config(noise_std=0.01, dropout=0.05))
    context = simulator.get_mutable_context()
    start = context.Clone()

    def run():
        ranges = []
        for k in range(4):
            simulator.AdvanceTo(0.1 * k + 0.01)
            ranges.append(np.array(sensor.read(context).ranges))
        return np.array(ranges)

    first = run()
    context.SetTimeStateAndParametersFrom(start)
    simulator.Initialize()
    again = run()
    assert first.shape == (4, 360) and np.array_equal(first, again, equal_nan=True)
    assert not np.array_equal(first[0], first[1], equal_nan=True)  # each scan its own noise
    context.SetTimeStateAndParametersFrom(start)
    sensor.system.SetNoiseKey(sensor.system.GetMyMutableContextFromRoot(context), 1)
    simulator.Initialize()
    assert not np.array_equal(run(), first, equal_nan=True)


# --- the kind's messages ----------------------------------------------------------------


def a_scan() -> LaserScan:
    return LaserScan(angle_min=-1.0, angle_max=1.0, angle_increment=1.0, time_increment=0.0,
                     scan_time=0.1, range_min=0.15, range_max=12.0,
                     ranges=(1.5, math.inf, math.nan), time=2.25)


def test_the_kind_names_its_topic_frame_and_json():
    assert (KIND.field, KIND.topic_name("top"), KIND.frame_name("top")) == (
        "lidars", "scan/top", "lidar_top")
    assert KIND.to_json(a_scan())["ranges"] == [1.5, None, None]
    assert "3 rays" in repr(a_scan()) and "1 dropped" in repr(a_scan())


def test_the_foxglove_message_is_a_laser_scan_in_the_sensor_frame():
    pytest.importorskip("foxglove")
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    message = KIND.foxglove_message(a_scan(), "lidar_top")
    assert type(message).__name__ == KIND.foxglove_schema == "LaserScan"
    schema = message.get_schema()  # decoded as a recording's reader does
    pool = descriptor_pool.DescriptorPool()
    for fd in descriptor_pb2.FileDescriptorSet.FromString(schema.data).file:
        pool.Add(fd)
    m = message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name)).FromString(
        message.encode())
    assert (m.frame_id, m.start_angle, m.end_angle) == ("lidar_top", -1.0, 1.0)
    assert (m.timestamp.seconds, m.timestamp.nanos) == (2, 250_000_000)
    assert m.ranges[0] == 1.5 and m.ranges[1] == math.inf and math.isnan(m.ranges[2])
    assert m.pose.orientation.w == 1.0 and list(m.intensities) == []


def test_the_ros2_message_is_a_sensor_msgs_laser_scan_that_serializes():
    pytest.importorskip("rosbags")
    from corobot_drake.ros2.messages import Messages, typestore

    store = typestore()
    m = KIND.ros2_message(Messages(store), a_scan(), "lidar_top")
    assert m.__msgtype__ == KIND.ros2_type == "sensor_msgs/msg/LaserScan"
    assert (m.header.stamp.sec, m.header.stamp.nanosec, m.header.frame_id) == (
        2, 250_000_000, "lidar_top")
    assert (m.angle_min, m.angle_max, m.angle_increment, m.scan_time, m.range_min,
            m.range_max) == (-1.0, 1.0, 1.0, 0.1, 0.15, 12.0)
    assert m.ranges.dtype == np.float32 and m.ranges[0] == 1.5 and m.intensities.size == 0
    back = store.deserialize_cdr(store.serialize_cdr(m, m.__msgtype__), m.__msgtype__)
    assert back.ranges[1] == math.inf and math.isnan(back.ranges[2])
