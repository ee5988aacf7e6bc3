"""The IR sensors' ray cast, 2 sensors x 6 rays, in a scene like the default one
(`tools/bench_raycast.py`).

Scene: the default scenario's proximity geometry, rebuilt here from the scenario file and the
Corobot's robot file (its measured collision shapes) so that the benchmark doesn't depend on the
station code: the ground HalfSpace (anchored), the 2 m giant box (a free 100 kg body, so it is
posed through ``QueryObject.GetPoseInWorld`` at every scan) and the robot's chassis and platform
boxes and four wheel cylinders, which are excluded as the robot's own. The robot sits at the
origin facing +x, so the rear sensor sees the box face at 0.62865 m and the front sensor sees
nothing.

A scan casts the 12 rays as the IR sensors do: per sensor, its ``RayFan`` posed by the chassis
pose and one ``RayCaster.cast_fan``. :func:`scan_cost_seconds` is the median cost of one scan of
both sensors in seconds.
"""

from __future__ import annotations

import statistics
import time

from pydrake.geometry import Box, HalfSpace
from pydrake.math import RigidTransform
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, CoulombFriction
from pydrake.multibody.tree import SpatialInertia
from pydrake.systems.framework import DiagramBuilder

from corobot_drake.config.scenario import load_scenario
from corobot_drake.config.sensors import default_ir_sensors
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.robots import robot_spec
from corobot_drake.sensors.raycast import RayCaster, RayFan, model_instance_geometry_ids

IR = default_ir_sensors()
"""The Corobot's IR sensors, as its robot file mounts them."""
SAMPLES = IR["front"].samples
MAXIMUM_RANGE = IR["front"].maximum_range


def build_scene():
    """Returns (diagram, context, plant, scene_graph, chassis body, robot model instance)."""
    world_config = load_scenario(DEFAULT_SCENARIO).world
    giant = world_config.bodies["giant_box"]
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.001)
    mu = world_config.ground.friction
    friction = CoulombFriction(mu, mu)
    world = plant.world_body()
    plant.RegisterCollisionGeometry(world, RigidTransform(), HalfSpace(), "ground", friction)
    size = giant.shape.size
    box_model = plant.AddModelInstance("giant_box")
    giant_box = plant.AddRigidBody(
        "giant_box", box_model, SpatialInertia.SolidBoxWithMass(giant.mass, *size))
    plant.RegisterCollisionGeometry(giant_box, RigidTransform(), Box(*size), "giant_box", friction)
    spec = robot_spec()
    robot = plant.AddModelInstance("corobot")
    chassis = plant.AddRigidBody(
        "chassis", robot, SpatialInertia.SolidBoxWithMass(spec.mass, 0.2, 0.15, 0.06))
    for name, shape, X_BG in spec.shapes:  # every collision shape, fixed at its start pose
        plant.RegisterCollisionGeometry(chassis, X_BG, shape, name.replace("/", "_"), friction)
    plant.Finalize()
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    plant.SetFreeBodyPose(plant.GetMyMutableContextFromRoot(context), giant_box,
                          giant.pose.GetDeterministicValue())
    return diagram, context, plant, scene_graph, chassis, robot


def sensor_poses_in_body():
    """X_BS of the front and rear IR sensors (sensor looks along its +x)."""
    return [IR[name].X_PB.GetDeterministicValue() for name in ("front", "rear")]


def sensor_fans() -> list[RayFan]:
    """The front and rear sensors' cross of rays (SAMPLES per fan) in the chassis frame."""
    return [RayFan.cross_of_rays(X_BS, SAMPLES) for X_BS in sensor_poses_in_body()]


def make_fan_scan(plant, scene_graph, chassis, robot, context):
    """Returns (caster, scan): scan() does the same 2-sensor scan as the IR sensors do (the
    QueryObject, the chassis pose, then per sensor: pose its fan of 6 rays, cast_fan) and
    returns the 12 distances (front's 6, then rear's)."""
    exclude = model_instance_geometry_ids(plant, robot)
    caster = RayCaster(scene_graph.model_inspector(), exclude=exclude)
    sg_context = scene_graph.GetMyContextFromRoot(context)
    query_port = scene_graph.get_query_output_port()
    fans = sensor_fans()
    frame = plant.GetBodyFrameIdOrThrow(chassis.index())

    def scan():
        query_object = query_port.Eval(sg_context)
        distances = []
        for fan in fans:
            X_WB = query_object.GetPoseInWorld(frame).GetAsMatrix34().tolist()
            origin, directions, cone = fan.in_world(X_WB)
            distances += caster.cast_fan(query_object, origin, directions, MAXIMUM_RANGE, cone)
        return distances

    return caster, scan


def batch_seconds(fn, repeats: int, batch: int = 50) -> list[float]:
    """Mean seconds per call of each batch of `batch` calls."""
    fn()  # warm up
    samples = []
    for _ in range(max(1, repeats // batch)):
        start = time.perf_counter()
        for _ in range(batch):
            fn()
        samples.append((time.perf_counter() - start) / batch)
    return samples


def scan_cost_seconds(repeats: int = 5000) -> float:
    """Median wall time of one full scan of both sensors (posing the rays and casting them):
    two cast_fan calls as the IR sensors do."""
    _, context, plant, scene_graph, chassis, robot = build_scene()
    _, scan = make_fan_scan(plant, scene_graph, chassis, robot, context)
    return statistics.median(batch_seconds(scan, repeats))
