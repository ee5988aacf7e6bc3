"""The bumper kind alone (`sensors/bumper.py`), on a small plant: a 1 kg box resting on an
upward-facing bumper (its weight presses it), and a 1 kg cart standing on the ground on a
downward-facing bumper (the ground alone, which must not press it); then the `Bumper` system
on its own, its inputs fixed to that plant's contact results, and its wire formats."""

import math

import msgpack  # Meshcat's wire format (installed with Ray)
import numpy as np
import pytest
from pydrake.common.yaml import yaml_dump_typed, yaml_load_typed
from pydrake.geometry import (
    AddCompliantHydroelasticProperties,
    AddContactMaterial,
    AddRigidHydroelasticProperties,
    Box,
    HalfSpace,
    Meshcat,
    ProximityProperties,
    Sphere,
)
from pydrake.math import RigidTransform
from pydrake.multibody.plant import AddMultibodyPlant, CoulombFriction, MultibodyPlantConfig
from pydrake.multibody.tree import SpatialInertia
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.visualization import ApplyVisualizationConfig

from corobot_drake.config.poses import mount
from corobot_drake.config.scenario import ScenarioError, load_scenario
from corobot_drake.config.sensors import default_camera_config
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.robots import robot_spec
from corobot_drake.ros2.messages import Messages
from corobot_drake.sensors.bumper import (
    BUMPER,
    Bumper,
    BumperConfig,
    BumperMeshcat,
    BumperState,
    ground_geometries,
)
from corobot_drake.sensors.site import SensorSite
from corobot_drake.station import visualization_config

G = 9.81  # m/s^2, Drake's default gravity
LOAD = 1.0  # kg: the box resting on the upward bumper, and the cart on the downward one
SETTLE = 0.5  # s: the load has come to rest (the SAP step's damping; measured < 0.2 s)
LOAD_TOP = 0.66  # m: the upward bumper's face, in the world
WEIGHT_TOLERANCE = 1e-3  # relative: a discrete plant at rest carries the weight to rounding


def _compliant(props=None):
    props = props or ProximityProperties()
    AddContactMaterial(friction=CoulombFriction(0.5, 0.5), properties=props)
    AddCompliantHydroelasticProperties(resolution_hint=0.05, hydroelastic_modulus=1e7,
                                       properties=props)
    return props


def small_scene(meshcat=None, point: bool = False):
    """(diagram, plant, [bumper `top`, bumper `bottom`] as built): robot `bot` a body welded
    0.5 m up with bumper `top` facing up under a free 1 kg box `load` (compliant
    hydroelastic; with `point` a ball of 5 cm radius without hydroelastic properties, which
    touches by point contact: a box would, by one corner, and spin there); robot `cart` a
    free 1 kg box standing on the ground on bumper `bottom` facing down; the ground a rigid
    half-space."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(MultibodyPlantConfig(
        time_step=0.001, contact_model="hydroelastic_with_fallback"), builder)
    ground = ProximityProperties()
    AddContactMaterial(friction=CoulombFriction(0.5, 0.5), properties=ground)
    AddRigidHydroelasticProperties(properties=ground)
    plant.RegisterCollisionGeometry(plant.world_body(), RigidTransform(), HalfSpace(), "ground",
                                    ground)
    bot = plant.AddModelInstance("bot")
    chassis = plant.AddRigidBody("chassis", bot, SpatialInertia.SolidBoxWithMass(
        1.0, 0.2, 0.2, 0.2))
    plant.WeldFrames(plant.world_frame(), chassis.body_frame(), RigidTransform([0, 0, 0.5]))
    top = BumperConfig(X_PB=mount((0.0, 0.0, 0.15), (0.0, -90.0, 0.0)), size=[0.02, 0.2, 0.2])
    BUMPER.add_geometry(plant, bot, "bot", "top", top)
    load = plant.AddRigidBody("load", plant.AddModelInstance("load"),
                              SpatialInertia.SolidBoxWithMass(LOAD, 0.1, 0.1, 0.1))
    friction_only = ProximityProperties()
    AddContactMaterial(friction=CoulombFriction(0.5, 0.5), properties=friction_only)
    plant.RegisterCollisionGeometry(load, RigidTransform(),
                                    Sphere(0.05) if point else Box(0.1, 0.1, 0.1), "load",
                                    friction_only if point else _compliant())
    plant.SetDefaultFloatingBaseBodyPose(load, RigidTransform([0.0, 0.0, LOAD_TOP + 0.0505]))
    cart_instance = plant.AddModelInstance("cart")
    cart = plant.AddRigidBody("chassis", cart_instance, SpatialInertia.SolidBoxWithMass(
        LOAD, 0.1, 0.1, 0.1))
    bottom = BumperConfig(X_PB=mount((0.0, 0.0, -0.06), (0.0, 90.0, 0.0)),
                          size=[0.02, 0.1, 0.1])
    BUMPER.add_geometry(plant, cart_instance, "cart", "bottom", bottom)
    plant.SetDefaultFloatingBaseBodyPose(cart, RigidTransform([1.0, 0.0, 0.0705]))
    plant.Finalize()
    sites = [SensorSite(builder, plant, scene_graph, name, instance)
             for name, instance in (("bot", bot), ("cart", cart_instance))]
    built = [BUMPER.add(sites[0], "top", top), BUMPER.add(sites[1], "bottom", bottom)]
    if meshcat is not None:
        ApplyVisualizationConfig(visualization_config(), builder, plant=plant,
                                 scene_graph=scene_graph, meshcat=meshcat)
        for sensor in built:
            BUMPER.add_meshcat(builder, meshcat, sensor)
    diagram = builder.Build()
    return diagram, plant, built


@pytest.fixture(scope="module")
def settled():
    """The small scene simulated for SETTLE s: (diagram, its context, plant, [top, bottom])."""
    diagram, plant, built = small_scene()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(SETTLE)
    return diagram, simulator.get_context(), plant, built


def test_a_resting_load_presses_the_bumper_with_its_weight(settled):
    _, context, _, (top, _) = settled
    reading = top.read(context)
    assert isinstance(reading, BumperState)
    assert reading.pressed
    assert reading.force == pytest.approx(LOAD * G, rel=WEIGHT_TOLERANCE)
    # S's +x is up (out of the face): the load pushes the bumper down, along -x.
    np.testing.assert_allclose(reading.force_vector, (-LOAD * G, 0.0, 0.0),
                               atol=WEIGHT_TOLERANCE * LOAD * G)
    # The last sample at 50 Hz: the one due at SETTLE (a sample due at t is taken when the
    # simulator steps away from t, so right after AdvanceTo(t) it is the one before).
    assert reading.time == pytest.approx(SETTLE - 0.02)


def test_a_load_in_point_contact_presses_it_alike():
    """`hydroelastic_with_fallback` touches a body without hydroelastic properties by point
    contact: the same weight, from the point pairs (a ball resting on the bumper)."""
    diagram, plant, (top, _) = small_scene(point=True)
    simulator = Simulator(diagram)
    simulator.AdvanceTo(SETTLE)
    context = simulator.get_context()
    results = plant.get_contact_results_output_port().Eval(plant.GetMyContextFromRoot(context))
    assert results.num_point_pair_contacts() > 0
    reading = top.read(context)
    assert reading.pressed
    np.testing.assert_allclose(reading.force_vector, (-LOAD * G, 0.0, 0.0),
                               atol=WEIGHT_TOLERANCE * LOAD * G)


def test_the_ground_does_not_press_a_bumper_it_carries(settled):
    _, context, plant, (_, bottom) = settled
    reading = bottom.read(context)
    assert (reading.pressed, reading.force, reading.force_vector) == (False, 0.0,
                                                                      (0.0, 0.0, 0.0))
    # Yet the cart stands on it: the contact results carry its weight through the bumper.
    results = plant.get_contact_results_output_port().Eval(plant.GetMyContextFromRoot(context))
    cart = plant.GetBodyByName("chassis", plant.GetModelInstanceByName("cart"))
    cart_geometry = plant.GetCollisionGeometriesForBody(cart)[0]
    lift = 0.0
    for i in range(results.num_hydroelastic_contacts()):
        info = results.hydroelastic_contact_info(i)
        surface = info.contact_surface()
        if cart_geometry in (surface.id_M(), surface.id_N()):
            sign = 1.0 if surface.id_M() == cart_geometry else -1.0
            lift += sign * info.F_Ac_W().translational()[2]
    assert lift == pytest.approx(LOAD * G, rel=WEIGHT_TOLERANCE)


def test_the_ground_is_the_worlds_half_space(settled):
    diagram, _, plant, _ = settled
    scene_graph = diagram.GetSubsystemByName("scene_graph")
    (ground,) = ground_geometries(plant, scene_graph)
    assert scene_graph.model_inspector().GetName(ground) == "ground"


def standalone(config: BumperConfig, settled, step: float = 0.0):
    """A Bumper alone (the `top` bumper's geometry and mount), its inputs fixed to the settled
    scene's queries, contact results and body poses: (bumper, its simulator)."""
    diagram, context, plant, (top, _) = settled
    plant_context = plant.GetMyContextFromRoot(context)
    original = top.system
    body = plant.GetBodyByName("chassis", plant.GetModelInstanceByName("bot"))
    bumper = Bumper(config, original._geometries, original._ground, body.index(),
                    config.X_PB.GetDeterministicValue(), step)
    simulator = Simulator(bumper)
    own = simulator.get_mutable_context()
    scene_graph = diagram.GetSubsystemByName("scene_graph")
    bumper.GetInputPort("query_object").FixValue(own, scene_graph.get_query_output_port().Eval(
        scene_graph.GetMyContextFromRoot(context)))
    bumper.GetInputPort("contact_results").FixValue(
        own, plant.get_contact_results_output_port().Eval(plant_context))
    bumper.GetInputPort("body_poses").FixValue(
        own, plant.get_body_poses_output_port().Eval(plant_context))
    return bumper, simulator


TOP = dict(X_PB=mount((0.0, 0.0, 0.15), (0.0, -90.0, 0.0)), size=[0.02, 0.2, 0.2])


@pytest.mark.parametrize("step", [0.0, 0.01])
def test_the_system_samples_at_its_rate_only(settled, step):
    """At 50 Hz: one sample at initialization, then one per 20 ms (with a continuous plant's
    10 ms step, on every second step), whatever the steps between."""
    bumper, simulator = standalone(BumperConfig(**TOP), settled, step)
    assert bumper.events == ((0.01, 0.0) if step else (0.02, 0.02))  # what publishers look on
    simulator.Initialize()
    context = simulator.get_context()
    first = bumper.GetOutputPort("reading").Eval(context)
    assert (first.pressed, first.time) == (True, 0.0)
    simulator.AdvanceTo(0.101)
    x = bumper.GetOutputPort("sample_state").Eval(context)
    assert (x[-1], x[-2]) == pytest.approx((5, 0.1))  # sample index, time
    assert bumper.GetOutputPort("pressed").Eval(context)[0] == 1.0
    assert bumper.GetOutputPort("force").Eval(context)[0] == pytest.approx(
        LOAD * G, rel=WEIGHT_TOLERANCE)


def test_under_its_threshold_it_is_not_pressed(settled):
    bumper, simulator = standalone(BumperConfig(**TOP, force_threshold=2 * LOAD * G), settled)
    simulator.Initialize()
    reading = bumper.GetOutputPort("reading").Eval(simulator.get_context())
    assert not reading.pressed
    assert reading.force == pytest.approx(LOAD * G, rel=WEIGHT_TOLERANCE)


def test_before_its_first_sample_it_reads_nothing(settled):
    bumper, simulator = standalone(BumperConfig(**TOP), settled)
    reading = bumper.GetOutputPort("reading").Eval(simulator.get_context())
    assert (reading.pressed, reading.force) == (False, 0.0)
    assert math.isnan(reading.time)


def test_default_bumper_is_ahead_of_the_front_tyres_and_out_of_the_cameras_view():
    config = BumperConfig()
    thickness, width, height = config.size
    x, y, z = config.X_PB.GetDeterministicValue().translation()
    assert config.X_PB.base_frame == "chassis"
    spec, camera = robot_spec("corobot"), default_camera_config()
    assert x - thickness / 2 > spec.wheelbase / 2 + spec.wheel_radius  # the tyres' reach
    assert z - height / 2 > 0.01  # m: clear of the ground
    assert y == 0.0 and width == pytest.approx(spec.track + spec.wheels[0].width)
    # The front camera's lowest ray (level, half its vertical field of view down) passes
    # over the bumper's top front edge: the camera's frames are those of a Corobot without.
    cx, _, cz = camera.X_PB.GetDeterministicValue().translation()
    lowest = cz - (x + thickness / 2 - cx) * math.tan(math.radians(camera.focal.y / 2))
    assert z + height / 2 < lowest


def test_the_config_reads_back_from_its_yaml():
    """A scenario's sensors are dumped (a saved scene, the diagram's cache key) and loaded."""
    config = BumperConfig(size=[0.03, 0.2, 0.05], force_threshold=2.5, rate_hz=100.0)
    text = yaml_dump_typed(config)
    again = yaml_load_typed(schema=BumperConfig, data=text)
    assert (again.size, again.force_threshold, again.rate_hz) == ([0.03, 0.2, 0.05], 2.5, 100.0)
    assert again.X_PB.GetDeterministicValue().IsExactlyEqualTo(
        config.X_PB.GetDeterministicValue())


def test_wire_formats():
    reading = BumperState(True, 5.0, (-3.0, 4.0, 0.0), 1.25)
    assert BUMPER.to_json(reading) == {"pressed": True, "force": 5.0,
                                       "force_vector": [-3.0, 4.0, 0.0], "time": 1.25}
    fox = BUMPER.foxglove_message(reading, "bumper_front_bumper")
    assert fox["timestamp"] == {"sec": 1, "nsec": 250_000_000}
    assert fox["force_vector"] == {"x": -3.0, "y": 4.0, "z": 0.0}
    assert set(fox) == set(BUMPER.foxglove_schema["properties"])
    messages = BUMPER.ros2_message(Messages(), reading, "bumper_front_bumper")
    assert BUMPER.ros2_channels() == {"": ("geometry_msgs/msg/WrenchStamped", "reliable"),
                                      "pressed": ("std_msgs/msg/Bool", "reliable")}
    assert {sub: m.__msgtype__ for sub, m in messages.items()} == {
        sub: msgtype for sub, (msgtype, _) in BUMPER.ros2_channels().items()}
    msg = messages[""]
    assert (msg.header.frame_id, msg.header.stamp.sec, msg.header.stamp.nanosec) == (
        "bumper_front_bumper", 1, 250_000_000)
    assert (msg.wrench.force.x, msg.wrench.force.y, msg.wrench.torque.z) == (-3.0, 4.0, 0.0)
    assert messages["pressed"].data is True
    assert BUMPER.ros2_message(Messages(), BumperState(False, 0.5, (-0.5, 0.0, 0.0), 1.25),
                               "bumper_front_bumper")["pressed"].data is False
    assert (BUMPER.topic_name("front_bumper"), BUMPER.frame_name("front_bumper")) == (
        "bumper/front_bumper", "bumper_front_bumper")
    assert repr(reading) == ("BumperState(pressed=True, force=5.000 N, "
                             "force_vector=(-3.000, 4.000, 0.000) N, time=1.250 s)")


def test_meshcat_draws_the_pressed_bumper_red():
    meshcat = Meshcat()
    diagram, _, (top, bottom) = small_scene(meshcat)
    simulator = Simulator(diagram)
    simulator.AdvanceTo(0.05)
    for sensor in (top, bottom):
        assert meshcat.HasPath(sensor.extra["meshcat_path"])  # the box Drake's visualizer drew
    assert diagram.GetSubsystemByName("bot.bumper.top.meshcat").shown is True
    assert diagram.GetSubsystemByName("cart.bumper.bottom.meshcat").shown is None  # never


@pytest.mark.parametrize(("bumper", "problem"), [
    ("{geometry: wheel}", "geometry: 'wheel' is not one of box, link"),
    ("{geometry: link, X_PB: {base_frame: world}}",
     "geometry: link needs X_PB.base_frame to be a link of the robot; got world"),
])
def test_a_bad_geometry_is_one_line(bumper, problem):
    with pytest.raises(ScenarioError) as e:
        load_scenario(DEFAULT_SCENARIO,
                      overrides=[f"robots: {{corobot: {{bumpers: {{b: {bumper}}}}}}}"])
    assert str(e.value) == f"--override:1: robots.corobot.bumpers.b.{problem}"


@pytest.mark.parametrize("shell", [False, True])
def test_bumper_meshcat_alone_shows_a_press_and_its_release(shell):
    """Its input fixed: pressed at the end of the first step shows the press (the box red, or
    the shell visible), released the release; unchanged, it sends nothing more."""
    meshcat = Meshcat()
    viz = BumperMeshcat(meshcat, "/bumper/bot/top", shell)
    simulator = Simulator(viz)
    context = simulator.get_mutable_context()
    prop = "visible" if shell else "color"
    for pressed, t in ((1.0, 0.1), (1.0, 0.2), (0.0, 0.3)):
        viz.get_input_port().FixValue(context, [pressed])
        before = meshcat._GetPackedProperty(viz.path, prop)
        simulator.AdvanceTo(t)
        assert viz.shown is bool(pressed)
        sent = meshcat._GetPackedProperty(viz.path, prop)
        assert (sent != before) is (t != 0.2)  # nothing sent while it stays pressed
        assert msgpack.unpackb(sent)["value"] == viz.looks(bool(pressed))[1]
