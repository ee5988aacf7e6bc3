"""Benchmark: the IR sensors' ray cast, 2 sensors x 6 rays, in a scene like the default one.

Scene: the default scenario's proximity geometry, rebuilt here from dimensions.py so that the
benchmark doesn't depend on the station code: the ground HalfSpace (anchored), the 2 m giant box
(a free 100 kg body, so it is posed through ``QueryObject.GetPoseInWorld`` at every scan) and the
robot's chassis and platform boxes and four wheel cylinders, which are excluded as the robot's
own. The robot sits at the origin facing +x, so the rear sensor sees the box face at 0.62865 m
and the front sensor sees nothing (SPEC, Sensors).

Two ways to cast the same 12 rays: ``RayCaster.cast`` (numpy, one batch of 12) and
``RayCaster.cast_fan`` (plain floats, one call per sensor's fan of 6, what the IR sensors use).

Run: ``.venv/bin/python tools/bench_raycast.py``. Importable: ``scan_cost_seconds()`` returns the
median cost of one scan of both sensors in seconds, the sensors' way (for tools/bench.py).
"""

from __future__ import annotations

import statistics
import time

import numpy as np
from pydrake.geometry import Box, Cylinder, HalfSpace
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, CoulombFriction
from pydrake.multibody.tree import SpatialInertia
from pydrake.systems.framework import DiagramBuilder

from corobot_drake.model import dimensions as dim
from corobot_drake.sensors.raycast import (
    BodyFixedRays,
    RayCaster,
    RayFan,
    model_instance_geometry_ids,
)

SAMPLES = 3
MAXIMUM_RANGE = 30 * dim.INCH


def build_scene():
    """Returns (diagram, context, plant, scene_graph, chassis body, robot model instance)."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.001)
    friction = CoulombFriction(dim.GROUND_FRICTION, dim.GROUND_FRICTION)
    world = plant.world_body()
    plant.RegisterCollisionGeometry(world, RigidTransform(), HalfSpace(), "ground", friction)
    size = dim.GIANT_BOX_SIZE
    box_model = plant.AddModelInstance("giant_box")
    giant_box = plant.AddRigidBody(
        "giant_box",
        box_model,
        SpatialInertia.SolidBoxWithMass(dim.GIANT_BOX_MASS, size, size, size),
    )
    plant.RegisterCollisionGeometry(
        giant_box, RigidTransform(), Box(size, size, size), "giant_box", friction
    )
    robot = plant.AddModelInstance("corobot")
    chassis = plant.AddRigidBody(
        "chassis", robot, SpatialInertia.SolidBoxWithMass(dim.TOTAL_BODY_MASS, *dim.CHASSIS.size)
    )
    for name, part in (("chassis", dim.CHASSIS), ("platform", dim.PLATFORM)):
        plant.RegisterCollisionGeometry(
            chassis, RigidTransform(part.center), Box(*part.size), name, friction
        )
    R_axle_y = RotationMatrix.MakeXRotation(np.pi / 2)  # cylinder axis z -> y
    for wheel in dim.WHEEL_NAMES:
        plant.RegisterCollisionGeometry(
            chassis,
            RigidTransform(R_axle_y, dim.wheel_center(wheel)),
            Cylinder(dim.WHEEL_RADIUS, dim.WHEEL_WIDTH),
            wheel,
            friction,
        )
    plant.Finalize()
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    plant.SetFreeBodyPose(
        plant.GetMyMutableContextFromRoot(context), giant_box, RigidTransform(dim.GIANT_BOX_CENTER)
    )
    return diagram, context, plant, scene_graph, chassis, robot


def sensor_poses_in_body():
    """X_BS of the front and rear IR sensors (sensor looks along its +x)."""
    return [
        RigidTransform(RotationMatrix.MakeZRotation(m.yaw), m.position)
        for m in (dim.FRONT_IR, dim.REAR_IR)
    ]


def make_scan(plant, scene_graph, chassis, robot, context):
    """Returns (caster, scan): scan() does one full 2-sensor scan as a sensor system would
    (evaluate the QueryObject and the chassis pose, pose the 12 rays, cast) and returns RayHits."""
    exclude = model_instance_geometry_ids(plant, robot)
    caster = RayCaster(scene_graph.model_inspector(), exclude=exclude)
    plant_context = plant.GetMyContextFromRoot(context)
    sg_context = scene_graph.GetMyContextFromRoot(context)
    query_port = scene_graph.get_query_output_port()
    rays = BodyFixedRays.cross_of_rays(sensor_poses_in_body(), SAMPLES)

    def scan():
        query_object = query_port.Eval(sg_context)
        X_WB = plant.EvalBodyPoseInWorld(plant_context, chassis)
        origins, directions = rays.in_world(X_WB)
        return caster.cast(query_object, origins, directions, MAXIMUM_RANGE)

    return caster, scan


def make_fan_scan(plant, scene_graph, chassis, robot, context):
    """Returns (caster, scan): scan() does the same 2-sensor scan as the IR sensors do (the
    QueryObject, the chassis pose, then per sensor: pose its fan of 6 rays, cast_fan) and
    returns the 12 distances (front's 6, then rear's)."""
    exclude = model_instance_geometry_ids(plant, robot)
    caster = RayCaster(scene_graph.model_inspector(), exclude=exclude)
    sg_context = scene_graph.GetMyContextFromRoot(context)
    query_port = scene_graph.get_query_output_port()
    fans = [RayFan.cross_of_rays(X_BS, SAMPLES) for X_BS in sensor_poses_in_body()]
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


def _batch_seconds(fn, repeats: int, batch: int = 50) -> list[float]:
    """Mean seconds per call of each batch of `batch` calls."""
    fn()  # warm up
    samples = []
    for _ in range(max(1, repeats // batch)):
        start = time.perf_counter()
        for _ in range(batch):
            fn()
        samples.append((time.perf_counter() - start) / batch)
    return samples


def _median_seconds(fn, repeats: int, batch: int = 50) -> float:
    return statistics.median(_batch_seconds(fn, repeats, batch))


def scan_cost_seconds(repeats: int = 5000, fan: bool = True) -> float:
    """Median wall time of one full scan of both sensors (posing the rays and casting them):
    two cast_fan calls as the IR sensors do, or (fan=False) one 12-ray numpy cast."""
    _, context, plant, scene_graph, chassis, robot = build_scene()
    _, scan = (make_fan_scan if fan else make_scan)(plant, scene_graph, chassis, robot, context)
    return _median_seconds(scan, repeats)


def main() -> None:
    _, context, plant, scene_graph, chassis, robot = build_scene()
    caster, scan = make_scan(plant, scene_graph, chassis, robot, context)
    hits = scan()
    n = 2 * SAMPLES
    front, rear = hits.distance[:n].min(), hits.distance[n:].min()
    print(f"targets: {[caster.geometry_name(i) for i in range(len(caster.geometry_ids))]}")
    print(f"front reads {front:.5f} m (inf = nothing within range), rear reads {rear:.5f} m")

    query_object = scene_graph.get_query_output_port().Eval(
        scene_graph.GetMyContextFromRoot(context)
    )
    origins, directions = hits.origins, hits.directions
    _, fan_scan = make_fan_scan(plant, scene_graph, chassis, robot, context)
    np.testing.assert_allclose(fan_scan(), hits.distance, rtol=0, atol=1e-12)  # same reading
    for label, fn in (
        (
            "cast only (12 rays, numpy)",
            lambda: caster.cast(query_object, origins, directions, MAXIMUM_RANGE),
        ),
        ("full scan, numpy cast (query, pose, rays, cast)", scan),
        ("full scan, 2 x cast_fan (as the IR sensors)", fan_scan),
    ):
        samples = _batch_seconds(fn, 5000)
        print(
            f"{label:50s} median {statistics.median(samples) * 1e6:6.1f} us"
            f"   (best batch {min(samples) * 1e6:6.1f} us)"
        )


if __name__ == "__main__":
    main()
