"""Real-time factors of the default scene, headless (run: python tools/bench.py).

One run prints a markdown table: rows are the stacks (physics only; + 2 IR at 20 Hz; + camera at
30 Hz; full stack = both), columns the plant settings (`lab.bench.PLANTS`: CENIC at 10 ms, the
default, and at 5 and 2 ms; SAP's discrete plant at 10 and 2 ms; SAP with point contact at
10 ms). Each cell simulates
`--seconds` of the robot driving a figure of eight, `--repeats` times, and reports the median
wall-clock real-time factor (the CPU-time one in parentheses: the machine may be shared). Then
the IR cost per scan and the camera cost per frame, both measured in place (the extra wall time
per scan or frame over physics only) and by their micro-benchmarks (tools/bench_ir.py,
tools/bench_raycast.py, tools/bench_camera.py). `--robots 1,2,4,8,16` adds fleets of robots
driving, physics only: robot-seconds per second, flat when nothing grows per robot.
`--layers` adds what physics only is made of: the plant alone (the floor Drake sets), then the
robot's systems added one layer at a time, CPU ms per simulated second
(`lab.bench_layers`). The measurements are
`lab.bench` and the micro-benchmarks' modules beside it.
"""

import statistics
import sys

try:  # without the [study] extra: one line naming it, not a traceback
    from tqdm import tqdm
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/bench.py", "study")

from corobot_drake.arguments import (
    BENCH_SECONDS,
    REPEATS,
    ToolParser,
    bounded,
    bounded_list,
    one_line_errors,
)
from corobot_drake.limits import Range
from corobot_drake.simulation import quiet_drake_warnings
from lab import bench, bench_camera, bench_ir, bench_layers, bench_raycast
from lab.bench import DEFAULT_PLANT, ROBOT


def _table(stacks: dict, plants: dict, seconds: float, repeats: int) -> dict:
    """Prints the table row by row; returns {(stack, plant): (wall, CPU) median RTF}."""
    results = {}
    print("| stack | " + " | ".join(plants) + " |\n" + "|---|" + "---|" * len(plants),
          flush=True)
    for stack, flags in stacks.items():
        cells = []
        for plant, plant_override in plants.items():
            runs = [bench.realtime_factor(
                [plant_override, *bench.sensor_overrides(ROBOT, **flags)], seconds)
                for _ in range(repeats)]
            wall = statistics.median(r[0] for r in runs)
            cpu = statistics.median(r[1] for r in runs)
            results[stack, plant] = (wall, cpu)
            cells.append(f"{wall:.2f}x ({cpu:.2f}x)")
        print(f"| {stack} | " + " | ".join(cells) + " |", flush=True)
    return results


def _in_place(results: dict) -> None:
    base = results.get(("physics only", DEFAULT_PLANT))
    for stack, per_second, unit in bench.IN_PLACE:
        rtf = results.get((stack, DEFAULT_PLANT))
        if base and rtf:
            wall, cpu = bench.in_place_ms(rtf, base, per_second)
            print(f"in place: {wall:.2f} ms wall, {cpu:.2f} ms CPU per {unit} "
                  f"(extra time over physics only, {DEFAULT_PLANT}; noisy on a busy machine)")


def _fleets(counts: list[int], seconds: float, repeats: int) -> None:
    """Prints robot-seconds per second for each fleet size (median of `repeats`)."""
    print("| robots | robot-seconds per second, wall (CPU) | per robot, of one robot's |\n"
          "|---|---|---|", flush=True)
    single = None
    for count in counts:
        runs = [bench.robot_seconds_per_second(count, seconds) for _ in range(repeats)]
        wall = statistics.median(r[0] for r in runs)
        cpu = statistics.median(r[1] for r in runs)
        single = single or (wall, cpu)
        print(f"| {count} | {wall:.1f} ({cpu:.1f}) | {wall / single[0]:.2f} "
              f"({cpu / single[1]:.2f}) |", flush=True)


def _layers(seconds: float, repeats: int) -> None:
    """Prints the physics-only stack layer by layer (median CPU ms per simulated second)."""
    rows = len(bench_layers.LAYERS) + 1 + len(bench_layers.VARIANTS) + len(bench_layers.FLOORS)
    with tqdm(total=rows * repeats, desc="layers", leave=False) as bar:
        costs = bench_layers.layer_costs(seconds, repeats, progress=bar.update)
    print("| layers (cumulative) | CPU ms per simulated s, median (least) | added (least) | "
          "CPU-time RTF, median (best) |\n|---|---|---|---|", flush=True)
    previous = None
    for name, (median, least) in costs.items():
        if name in bench_layers.LAYERS[1:]:
            added = f"{median - previous[0]:+.1f} ({least - previous[1]:+.1f})"
        elif name in bench_layers.FLOORS:
            plant = costs[bench_layers.LAYERS[0]]
            added = f"{median - plant[0]:+.1f} ({least - plant[1]:+.1f}) over the plant alone"
        elif name in bench_layers.VARIANTS:
            station = costs[bench_layers.STATION]
            added = (f"{median / station[0]:.2f} ({least / station[1]:.2f}) of the "
                     "station's")
        else:
            added = ""
        print(f"| {name} | {median:.1f} ({least:.1f}) | {added} | {1000 / median:.2f}x "
              f"({1000 / least:.2f}x) |", flush=True)
        previous = median, least


def _micro_benchmarks() -> None:
    print(f"micro-benchmark: IR scan of both default sensors (2 x 6 rays) in the station: "
          f"{bench_ir.station_scan_cost_seconds() * 1000:.4f} ms (tools/bench_ir.py)", flush=True)
    print(f"micro-benchmark: IR scan, 2 sensors x 6 rays: "
          f"{bench_raycast.scan_cost_seconds() * 1000:.4f} ms (tools/bench_raycast.py)", flush=True)
    print(f"micro-benchmark: the robot's camera, one 320x240 frame: "
          f"{bench_camera.camera_frame_ms():.2f} ms (tools/bench_camera.py)", flush=True)


FLEET = Range(1, 256, why="robots in a fleet")


def _parser() -> ToolParser:
    parser = ToolParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=bounded(BENCH_SECONDS), default=10.0,
                        help="simulated s per run")
    parser.add_argument("--repeats", type=bounded(REPEATS, int), default=3,
                        help="runs of each; the median")
    parser.add_argument("--stacks", help="only stacks containing this text (None: all)")
    parser.add_argument("--plants", help="only plant settings containing this text (None: all)")
    parser.add_argument("--no-micro", action="store_true",
                        help="skip the IR and camera micro-benchmarks")
    parser.add_argument("--robots", type=bounded_list(FLEET), default=None,
                        help="also fleets of these sizes, e.g. 1,2,4,8,16: robot-seconds per "
                             "second, physics only (None: no fleets)")
    parser.add_argument("--layers", action="store_true",
                        help="also the physics-only stack layer by layer, from the plant "
                             "alone (CPU time, the layers interleaved)")
    parser.add_argument("--no-table", action="store_true",
                        help="skip the stacks x plants table")
    return parser


def _chosen(parser: ToolParser, flag: str, text: str | None, names: dict) -> dict:
    """The entries of `names` whose name contains `text` (all for None); at least one."""
    chosen = {k: v for k, v in names.items() if not text or text in k}
    if not chosen:
        parser.error(f"argument {flag}: {text!r} is in none of: {', '.join(names)}")
    return chosen


@one_line_errors
def main(argv=None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    stacks = _chosen(parser, "--stacks", args.stacks, bench.STACKS)
    plants = _chosen(parser, "--plants", args.plants, bench.PLANTS)
    quiet_drake_warnings()
    print(f"machine: {bench.machine()}", flush=True)
    print(f"{args.seconds:g} s of driving per run, median of {args.repeats}; wall real-time "
          "factor (CPU-time one in parentheses)\n", flush=True)
    if not args.no_table:
        results = _table(stacks, plants, args.seconds, args.repeats)
        print()
        _in_place(results)
    if args.robots:
        _fleets(args.robots, args.seconds, args.repeats)
        print()
    if args.layers:
        _layers(args.seconds, args.repeats)
        print()
    if not args.no_micro:
        _micro_benchmarks()
    return 0


if __name__ == "__main__":
    sys.exit(main())
