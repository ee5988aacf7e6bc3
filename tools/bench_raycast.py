"""Benchmark: the IR sensors' ray cast, 2 sensors x 6 rays, in a scene like the default one.

The scene and the scan are `lab.bench_raycast`'s: the default scenario's
proximity geometry rebuilt from the scenario and robot files (ground, the giant box as a free
body, the robot's own boxes and wheels excluded), the robot at the origin facing +x, so the
rear sensor sees the box face at 0.62865 m and the front sensor sees nothing. Both sensors
cast as the IR sensors do: per sensor, its RayFan posed by the chassis pose and one
``RayCaster.cast_fan``. Prints the readings, then the cast alone and the full scan (median and
best batch, wall clock).

Run: ``.venv/bin/python tools/bench_raycast.py``.
"""

import statistics
import sys

from corobot_drake.arguments import ToolParser, one_line_errors
from lab.bench_raycast import (
    MAXIMUM_RANGE,
    SAMPLES,
    batch_seconds,
    build_scene,
    make_fan_scan,
    sensor_fans,
)


@one_line_errors
def main(argv=None) -> int:
    ToolParser(description=__doc__.splitlines()[0]).parse_args(argv)
    _, context, plant, scene_graph, chassis, robot = build_scene()
    caster, scan = make_fan_scan(plant, scene_graph, chassis, robot, context)
    distances = scan()
    n = 2 * SAMPLES
    inspector = scene_graph.model_inspector()
    print(f"targets: {[inspector.GetName(gid) for gid in caster.geometry_ids]}")
    print(f"front reads {min(distances[:n]):.5f} m (inf = nothing within range), "
          f"rear reads {min(distances[n:]):.5f} m")

    query_object = scene_graph.get_query_output_port().Eval(
        scene_graph.GetMyContextFromRoot(context))
    frame = plant.GetBodyFrameIdOrThrow(chassis.index())
    X_WB = query_object.GetPoseInWorld(frame).GetAsMatrix34().tolist()
    posed = [fan.in_world(X_WB) for fan in sensor_fans()]

    def cast_only():
        for origin, directions, cone in posed:
            caster.cast_fan(query_object, origin, directions, MAXIMUM_RANGE, cone)

    for label, fn in (("cast only, 2 x cast_fan (rays posed once)", cast_only),
                      ("full scan, 2 x cast_fan (as the IR sensors)", scan)):
        samples = batch_seconds(fn, 5000)
        print(f"{label:50s} median {statistics.median(samples) * 1e6:6.1f} us"
              f"   (best batch {min(samples) * 1e6:6.1f} us)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
