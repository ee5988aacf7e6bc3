"""Each kind of sensor's `add_<kind>` alone, on a small plant: a robot that is one welded
`chassis` box, and (or not) a red wall ahead of it; the sensor's exported ports evaluated after
initialization. Then the registry: every kind of `Robot` is a registered kind, and each built
sensor reads its kind's reading."""

import dataclasses as dc
import gc
import typing

import numpy as np
import pytest
from pydrake.geometry import Box, ProximityProperties, QueryObject, SceneGraphInspector
from pydrake.math import RigidTransform
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.multibody.tree import SpatialInertia
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from corobot_drake.config import scenario as sc
from corobot_drake.config.sensors import IrSensorConfig, default_camera_config
from corobot_drake.sensors.camera import add_camera
from corobot_drake.sensors.ir_sensor import add_ir_sensor
from corobot_drake.sensors.registry import KINDS, add_sensors
from corobot_drake.sensors.site import SensorSite

WALL_X = 0.5
"""m: the wall's near face, at x in the world (the chassis frame is the world's)."""
RED = np.array([0.9, 0.1, 0.1, 1.0])
EXACT = 1e-9  # m: a ray-box intersection in doubles


def small_site(wall: bool) -> SensorSite:
    """A site on robot `bot`: a 0.2 m box `chassis` welded at the world origin (its own
    geometry, which its sensors do not see), and with `wall` a red 0.1 x 4 x 4 m wall
    whose near face is at x = WALL_X."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.01)
    bot = plant.AddModelInstance("bot")
    chassis = plant.AddRigidBody("chassis", bot, SpatialInertia.SolidBoxWithMass(
        1.0, 0.2, 0.2, 0.2))
    plant.WeldFrames(plant.world_frame(), chassis.body_frame())
    plant.RegisterCollisionGeometry(chassis, RigidTransform(), Box(0.2, 0.2, 0.2), "chassis",
                                    ProximityProperties())
    if wall:
        X_WW = RigidTransform([WALL_X + 0.05, 0.0, 0.0])
        plant.RegisterCollisionGeometry(plant.world_body(), X_WW, Box(0.1, 4.0, 4.0), "wall",
                                        ProximityProperties())
        plant.RegisterVisualGeometry(plant.world_body(), X_WW, Box(0.1, 4.0, 4.0), "wall", RED)
    plant.Finalize()
    return SensorSite(builder, plant, scene_graph, "bot", bot)


def initialized(site: SensorSite):
    """The built diagram and its context, initialized (the sensors' first readings)."""
    diagram = site.builder.Build()
    simulator = Simulator(diagram)
    simulator.Initialize()
    return diagram, simulator.get_context()


@pytest.mark.parametrize("wall", [True, False])
def test_add_ir_sensor_alone_reads_the_wall(wall):
    site = small_site(wall)
    config = IrSensorConfig()  # on the chassis, looking along +x
    sensor = add_ir_sensor(site, "front", config)
    diagram, context = initialized(site)
    assert sensor is diagram.GetSubsystemByName("bot.ir.front")
    distance = diagram.GetOutputPort("bot.front.distance").Eval(context)[0]
    origin_x = config.X_PB.GetDeterministicValue().translation()[0]
    # 3 rays per fan: the centre ray looks straight at the wall, through the robot's own box.
    expected = WALL_X - origin_x if wall else config.maximum_range
    assert distance == pytest.approx(expected, abs=EXACT)
    assert diagram.GetOutputPort("bot.front.scan_time").Eval(context)[0] == 0.0


def test_an_ir_sensor_keeps_no_view_of_a_context_that_is_gone():
    """The sensor outlives the Contexts it scans (a diagram is simulated again and again):
    once its Simulator is gone, no Python view of that Context's geometry (a QueryObject,
    its inspector) may stay alive through the sensor. Such a view points at freed memory,
    and its wrapper, still registered at that address, is what the bindings hand back for
    whatever is allocated there next (an output's value, seen as a QueryObject's)."""
    site = small_site(wall=True)
    sensor = add_ir_sensor(site, "front", IrSensorConfig())
    diagram, context = initialized(site)
    assert sensor.GetOutputPort("distance").Eval(sensor.GetMyContextFromRoot(context))[0] < 1
    del context
    gc.collect()
    views = [type(o).__name__ for o in gc.get_objects()
             if isinstance(o, (QueryObject, SceneGraphInspector))]
    assert views == []
    assert diagram.GetSubsystemByName("bot.ir.front") is sensor  # the sensor itself lives on


def test_add_ir_sensor_turned_off_adds_nothing():
    site = small_site(wall=True)
    assert add_ir_sensor(site, "front", IrSensorConfig(enabled=False)) is None
    assert len(site.builder.GetSystems()) == 2  # the plant and the scene graph alone


def small_camera(**changes):
    """The SPEC camera, 32 x 24 (cheap to render), frames from initialization (no delay)."""
    config = default_camera_config()
    for field, value in dict(width=32, height=24, output_delay=0.0, **changes).items():
        setattr(config, field, value)
    return config


@pytest.mark.parametrize("wall", [True, False])
def test_add_camera_alone_renders_the_wall_or_the_sky(wall):
    site = small_site(wall)
    camera = add_camera(site, "front", small_camera())
    diagram, context = initialized(site)
    assert camera.system is diagram.GetSubsystemByName("bot.camera.front.hold")
    image = diagram.GetOutputPort("bot.camera.front.rgb_image").Eval(context).data
    assert image.shape == (24, 32, 4)
    assert diagram.GetOutputPort("bot.camera.front.image_time").Eval(context)[0] == 0.0
    rgb = image[:, :, :3].astype(int)
    if wall:  # the wall fills the view (at 0.39 m a 30 deg fov spans 0.2 m): lit red
        assert (rgb[:, :, 0] > 2 * rgb[:, :, 1]).all() and (rgb[:, :, 0] > 2 * rgb[:, :, 2]).all()
    else:  # the sky: the render engine's clear colour, to within rounding
        sky = np.round(np.asarray(sc.World().sky_color[:3]) * 255)
        np.testing.assert_allclose(rgb.reshape(-1, 3), np.tile(sky, (32 * 24, 1)), atol=1)


def test_add_camera_turned_off_adds_nothing():
    site = small_site(wall=True)
    assert add_camera(site, "front", small_camera(rgb=False)) is None
    assert not site.scene_graph.HasRenderer(default_camera_config().renderer_name)


def test_add_camera_saves_another_camera_in_its_own_folder(tmp_path):
    site = small_site(wall=True)
    site.save_dir = tmp_path
    front = add_camera(site, "front", small_camera())
    rear = add_camera(site, "rear", small_camera())
    assert front.saver.directory == tmp_path / "bot"
    assert rear.saver.directory == tmp_path / "bot" / "rear"


def test_every_kind_of_sensor_is_registered():
    """Each typed map of `Robot` (a dict of sensor configs) is a registered kind."""
    hints = typing.get_type_hints(sc.Robot)
    maps = {f.name: typing.get_args(hints[f.name])[1] for f in dc.fields(sc.Robot)
            if typing.get_origin(hints[f.name]) is dict}
    assert maps == {k.field: k.config_type for k in KINDS}


def test_add_sensors_adds_every_kind_and_leaves_out_those_turned_off():
    site = small_site(wall=True)
    robot = sc.Robot(cameras={"front": small_camera(), "rear": small_camera(rgb=False)})
    robot.ir_sensors["rear"].enabled = False
    built = add_sensors(site, robot)
    assert {kind: list(sensors) for kind, sensors in built.items()} == {
        **{k.field: [] for k in KINDS}, "ir_sensors": ["front"], "cameras": ["front"]}


def test_each_built_sensor_reads_its_kind_reading():
    """A `BuiltSensor` of each kind reads its kind's reading type from the root context: the
    IR sensor the wall's distance, the camera a frame of its size (rendered at init)."""
    site = small_site(wall=True)
    config = IrSensorConfig()
    built = add_sensors(site, sc.Robot(cameras={"front": small_camera()},
                                       ir_sensors={"front": config}))
    _, context = initialized(site)
    for k in KINDS:
        for sensor in built[k.field].values():
            assert isinstance(sensor.read(context), k.reading_type)
    ir = built["ir_sensors"]["front"].read(context)
    origin_x = config.X_PB.GetDeterministicValue().translation()[0]
    assert ir.raw == pytest.approx(WALL_X - origin_x, abs=EXACT)
    image = built["cameras"]["front"].read(context)
    assert image.data.shape == (image.height, image.width, 4) == (24, 32, 4)
    assert built["cameras"]["front"].kind.to_json(image) == {
        "width": 32, "height": 24, "encoding": "rgba8", "time": 0.0}
