"""Benchmark: what one planar lidar scan costs, and what a lidar costs a running simulation.

Run: ``.venv/bin/python tools/bench_lidar.py [--scans 2000] [--seconds 5] [--repeats 3]``.
It prints

1. the CPU time of one scan (median and best of ``--scans`` calls of the Lidar's own
   periodic-update handler: the body pose from the QueryObject, the rays posed, the exact
   cast of every ray, the noise, the state written), for a 360-ray full circle on the
   Corobot's platform in the default scene (scenarios/corobot.yaml: the ground, the giant
   box, the robot itself excluded), then with noise and dropouts, then in the lidar room
   (scenarios/corobot_lidar.yaml: four walls, a crate, a pillar, a step), and at 1080 rays;
   then with a concave mesh that touches with its own surface (`collision: mesh`) in the
   default scene, sliced by the scan plane: a U (28 triangles) open towards the robot, its
   scans interleaved with the same scans cast against the U's convex hull (the cast before
   meshes were sliced), and a bay of 2052 triangles;
2. in place: the default scene standing still for ``--seconds`` simulated s with and
   without the 10 Hz lidar, CPU s per simulated s (median of ``--repeats`` runs each, taken
   in turn), and from them the extra CPU per scan.

The target is a 360-ray scan within 1 ms of CPU.
"""

import copy
import dataclasses as dc
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from corobot_drake.arguments import BENCH_SECONDS, REPEATS, ToolParser, bounded, one_line_errors
from corobot_drake.config.scenario import load_scenario
from corobot_drake.limits import Range
from corobot_drake.resources import DEFAULT_SCENARIO, SCENARIOS_DIR
from corobot_drake.simulation import Simulation, quiet_drake_warnings

NO_CAMERA = "robots: {corobot: {cameras: {front: {rgb: false}}}}"
LIDAR = "robots: {corobot: {lidars: {top: {samples: %d, noise_std: %g, dropout: %g}}}}"
SCANS = Range(10, 1_000_000, why="handler calls, the median kept")


def scan_cost(scenario, samples: int = 360, noise: float = 0.0, dropout: float = 0.0,
              scans: int = 2000) -> tuple[float, float]:
    """(median, best) CPU s of one call of the lidar's periodic-scan handler, in `scenario`
    (a file) with the lidar `top` of `samples` rays, standing at its start."""
    sim = Simulation(load_scenario(scenario, overrides=[NO_CAMERA, LIDAR % (
        samples, noise, dropout)]))
    sim.advance(0.05)
    lidar = sim.station.robots["corobot"].sensors["lidars"]["top"].system
    context = lidar.GetMyContextFromRoot(sim.context)
    state = lidar.AllocateDiscreteVariables()
    state.SetFrom(context.get_discrete_state())
    times = []
    for _ in range(scans):
        start = time.process_time()
        lidar._periodic_scan(context, state)
        times.append(time.process_time() - start)
    return statistics.median(times), min(times)


MESH_BODY = ("world: {bodies: {%s: {shape: !Mesh {filename: %s, collision: mesh}, fixed: true, "
             "hydroelastic_modulus: 0}}}")


def write_obj(path, vertices, faces) -> str:
    """Writes triangles (vertex index triples, counter-clockwise from outside) over `vertices`
    (m) as an OBJ file with a normal per face (the cameras' renderer needs normals); returns
    the path."""
    v = np.asarray(vertices, dtype=float)
    f = np.asarray(faces)
    normals = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in v.tolist()]
    lines += [f"vn {x!r} {y!r} {z!r}" for x, y, z in normals.tolist()]
    lines += [f"f {a + 1}//{k} {b + 1}//{k} {c + 1}//{k}"
              for k, (a, b, c) in enumerate(f.tolist(), start=1)]
    Path(path).write_text("\n".join(lines) + "\n")
    return str(path)


def u_obj(path) -> str:
    """A U of 0.2 m walls, 1 m tall, ahead of the robot's start (the origin), open towards it:
    its hull's near face 0.5 m ahead, its back wall's inner face 2.5 m ahead; 28 triangles."""
    outline = [(0.5, -1.0), (2.7, -1.0), (2.7, 1.0), (0.5, 1.0), (0.5, 0.8), (2.5, 0.8),
               (2.5, -0.8), (0.5, -0.8)]
    caps = [(0, 1, 6), (0, 6, 7), (1, 2, 5), (1, 5, 6), (2, 3, 4), (2, 4, 5)]
    n = len(outline)
    vertices = [(x, y, z) for z in (0.0, 1.0) for x, y in outline]
    faces = [f for i in range(n) for f in ((i, (i + 1) % n, n + (i + 1) % n),
                                           (i, n + (i + 1) % n, n + i))]
    faces += [(a, c, b) for a, b, c in caps] + [(n + a, n + b, n + c) for a, b, c in caps]
    return write_obj(path, vertices, faces)


def arc_obj(path, sides: int = 256) -> str:
    """A bay: 0.2 m walls 1 m tall on an arc of 1.5 m inner radius about (3, 0), 270 degrees
    of it, open towards the robot's start (the origin); `sides` segments, 8 triangles each
    and 4 for its two ends (2052 for 256)."""
    angles = np.linspace(np.pi / 4 - 2 * np.pi, -np.pi / 4, sides + 1)
    ring = np.column_stack([np.cos(angles), np.sin(angles)])
    vertices = [(3.0 + r * x, r * y, z) for z in (0.0, 1.0) for r in (1.5, 1.7) for x, y in ring]
    m, faces = sides + 1, []  # vertex k of ring r (0 inner) at height z is (2 z + r) m + k
    for i in range(sides):
        j = i + 1
        faces += [(i, 2 * m + j, j), (i, 2 * m + i, 2 * m + j)]  # the inner wall, facing in
        faces += [(m + i, m + j, 3 * m + j), (m + i, 3 * m + j, 3 * m + i)]
        faces += [(i, m + j, j), (i, m + i, m + j)]  # the bottom, facing down
        faces += [(2 * m + i, 2 * m + j, 3 * m + j), (2 * m + i, 3 * m + j, 3 * m + i)]
    for k, flip in ((0, False), (sides, True)):  # the two ends
        end = [(k, m + k, 3 * m + k), (k, 3 * m + k, 2 * m + k)]
        faces += [f[::-1] for f in end] if flip else end
    return write_obj(path, vertices, faces)


def _handler_cost(lidar, context, state, scans: int) -> list[float]:
    times = []
    for _ in range(scans):
        start = time.process_time()
        lidar._periodic_scan(context, state)
        times.append(time.process_time() - start)
    return times


def mesh_scan_costs(directory, scans: int, rounds: int = 5) -> None:
    """Prints the CPU of one 360-ray scan in the default scene with the U, sliced and (its
    scans interleaved, `rounds` blocks each) cast against its hull, then with the bay."""
    for label, obj in (("a concave U (28 triangles, collision: mesh)", u_obj),
                       ("a bay (2052 triangles, collision: mesh)", arc_obj)):
        filename = obj(Path(directory) / f"{obj.__name__}.obj")
        sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[
            NO_CAMERA, LIDAR % (360, 0.0, 0.0), MESH_BODY % ("walls", filename)]))
        sim.advance(0.05)
        lidar = sim.station.robots["corobot"].sensors["lidars"]["top"].system
        context = lidar.GetMyContextFromRoot(sim.context)
        state = lidar.AllocateDiscreteVariables()
        state.SetFrom(context.get_discrete_state())
        lidar._periodic_scan(context, state)  # builds the caster
        sliced = lidar._casters.current
        hulled = copy.copy(sliced)  # the same targets without their surfaces: the hull cast
        hulled._targets = tuple(dc.replace(t, surface=None) for t in sliced._targets)
        times = {"sliced": [], "hull": []}
        for _ in range(rounds if obj is u_obj else 1):
            for name, caster in (("sliced", sliced), ("hull", hulled)):
                if obj is u_obj or name == "sliced":
                    lidar._casters.current = caster
                    times[name] += _handler_cost(lidar, context, state, scans // rounds)
        lidar._casters.current = sliced
        for name, ts in times.items():
            if ts:
                print(f"one scan, 360 rays, default scene and {label}, {name}: "
                      f"{statistics.median(ts) * 1e6:.0f} us CPU (median of {len(ts)}), "
                      f"{min(ts) * 1e6:.0f} us (best)", flush=True)


def cpu_per_second(with_lidar: bool, seconds: float) -> float:
    """CPU s per simulated s of the default scene standing still (camera off)."""
    overrides = [NO_CAMERA] + ([LIDAR % (360, 0.0, 0.0)] if with_lidar else [])
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=overrides))
    sim.advance(0.1)
    start = time.process_time()
    sim.advance(seconds)
    return (time.process_time() - start) / seconds


def _print_scan_costs(scans: int) -> None:
    room = SCENARIOS_DIR / "corobot_lidar.yaml"
    for label, scenario, args in (
            ("360 rays, default scene", DEFAULT_SCENARIO, (360,)),
            ("360 rays, default scene, noise 0.01 m and 5% dropouts", DEFAULT_SCENARIO,
             (360, 0.01, 0.05)),
            ("360 rays, the lidar room (7 bodies)", room, (360,)),
            ("1080 rays, the lidar room", room, (1080,))):
        median, best = scan_cost(scenario, *args, scans=scans)
        print(f"one scan, {label}: {median * 1e6:.0f} us CPU (median of {scans}), "
              f"{best * 1e6:.0f} us (best)", flush=True)


@one_line_errors
def main(argv=None) -> int:
    parser = ToolParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scans", type=bounded(SCANS, int), default=2000,
                        help="handler calls per scan figure; the median")
    parser.add_argument("--seconds", type=bounded(BENCH_SECONDS), default=5.0,
                        help="simulated s per in-place run")
    parser.add_argument("--repeats", type=bounded(REPEATS, int), default=3,
                        help="in-place runs of each; the median")
    args = parser.parse_args(argv)
    quiet_drake_warnings()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    _print_scan_costs(args.scans)
    with tempfile.TemporaryDirectory() as directory:
        mesh_scan_costs(directory, args.scans)
    runs = {False: [], True: []}
    for _ in range(args.repeats):
        for with_lidar in runs:
            runs[with_lidar].append(cpu_per_second(with_lidar, args.seconds))
    without, with_ = (statistics.median(runs[k]) for k in (False, True))
    print(f"in place, default scene standing: {without * 1e3:.1f} ms CPU per simulated s "
          f"without a lidar, {with_ * 1e3:.1f} ms with a 10 Hz 360-ray lidar: "
          f"{(with_ - without) / 10 * 1e3:.3f} ms per scan (median of {args.repeats} runs of "
          f"{args.seconds:g} s; load average now {os.getloadavg()[0]:.1f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
