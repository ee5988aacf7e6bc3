"""Benchmark: what the IR sensors cost, per scan and inside the running default scene.

Run: ``.venv/bin/python tools/bench_ir.py [--seconds 10] [--repeats 5]``. It prints

1. the cost of one scan of both default sensors (2 sensors x 6 rays) in the built station:
   each IrSensor's own periodic-update handler (chassis pose from the QueryObject, posing the
   rays, the exact cast, the output model, writing the state), called directly in a loop
   (median and best batch, CPU and wall);
2. the same handlers timed in place: called by the Simulator in the default scene driving
   (caches cold after each physics step), median per scan of both sensors, CPU;
3. the ray cast alone (``tools/bench_raycast.py``'s stand-alone scene);
4. the default scene driving (tools/bench.py's figure of eight, camera off) with no IR, and
   at 20 Hz and 200 Hz with two *no-op* IR sensors (the same events, state and ports, a
   handler that does nothing: what Drake's event machinery and the extra simulator steps at
   scan times cost) and with the 2 default sensors: the real-time factor, CPU ms per
   simulated second and simulator steps per simulated second, medians of ``--repeats`` runs
   taken in turn; and from those the in-place cost of one scan of both sensors (extra CPU per
   simulated second / scans per second), split into Drake's part (no-op minus no IR) and the
   handlers' (IR minus no-op). At 20 Hz that cost is a few percent of the physics, within
   the run-to-run noise of a shared machine; 200 Hz multiplies it by ten.

The measurements (and the no-op sensor) are `lab.bench_ir`.
"""

import os
import sys
import time

from corobot_drake.arguments import (
    BENCH_SECONDS,
    REPEATS,
    ToolParser,
    bounded,
    one_line_errors,
)
from corobot_drake.simulation import quiet_drake_warnings
from lab import bench_ir
from lab.bench_ir import (
    NO_OP,
    NO_OP_200,
    WITH_IR_20,
    WITH_IR_200,
    WITHOUT_IR,
    Run,
)
from lab.bench_raycast import scan_cost_seconds


def _print_scan_costs(seconds: float) -> None:
    cost = bench_ir.station_scan_cost_seconds
    print(f"IR scan, 2 sensors x 6 rays, both handlers called directly: "
          f"{cost() * 1e6:.1f} us CPU (median batch), "
          f"{cost(best=True) * 1e6:.1f} us CPU (best batch), "
          f"{cost(timer=time.perf_counter) * 1e6:.1f} us wall (median)")
    both, each = bench_ir.in_place_scan_cost_seconds(seconds)
    print(f"the same handlers in place (called by the Simulator, default scene driving): "
          f"{both * 1e6:.1f} us CPU (median per scan; "
          + ", ".join(f"{name} {cost * 1e6:.1f} us" for name, cost in each.items()) + ")")
    hit, update = bench_ir.pose_update_probe_seconds()
    print(f"SceneGraph pose query probed after a step: {hit * 1e6:.1f} us after a step that "
          f"took a scan (cache hit: the next plant step reuses the scan's pose update), "
          f"{update * 1e6:.1f} us after a plant step without one (the pose update itself)")
    print(f"the ray cast alone, both sensors (tools/bench_raycast.py): "
          f"{scan_cost_seconds() * 1e6:.1f} us wall (median)", flush=True)


def _print_table(runs: dict[str, list[Run]]) -> dict[str, Run]:
    """The real-time factor table; returns the median run of each configuration."""
    print("| configuration | real-time factor | CPU ms per simulated s (min-max) "
          "| steps per simulated s |")
    print("|---|---|---|---|")
    med = {}
    for name, rs in runs.items():
        m = med[name] = bench_ir.median_run(rs)
        cpu = [r.cpu_per_second * 1e3 for r in rs]
        print(f"| {name} | {m.realtime_factor:.2f}x | {m.cpu_per_second * 1e3:.1f} "
              f"({min(cpu):.0f}-{max(cpu):.0f}) | {m.steps_per_second:.1f} |")
    return med


def _print_in_place(med: dict[str, Run]) -> None:
    base = med[WITHOUT_IR]
    for rate, noop, ir in ((20, med[NO_OP], med[WITH_IR_20]),
                           (200, med[NO_OP_200], med[WITH_IR_200])):

        def per_scan(a: Run, b: Run, rate=rate) -> str:
            return f"{(a.cpu_per_second - b.cpu_per_second) / rate * 1e3:.3f} ms"

        print(f"in place at {rate} Hz, per scan of both sensors (CPU per simulated s): "
              f"{per_scan(ir, base)} (IR - no IR) = {per_scan(noop, base)} Drake's events and "
              f"the {noop.steps_per_second - base.steps_per_second:.1f} extra simulator steps "
              f"per simulated s (no-op - no IR) + {per_scan(ir, noop)} the handlers (IR - no-op); "
              f"from the real-time factors (wall): "
              f"{(1 / ir.realtime_factor - 1 / base.realtime_factor) / rate * 1e3:.3f} ms")


@one_line_errors
def main(argv=None) -> int:
    parser = ToolParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=bounded(BENCH_SECONDS), default=10.0,
                        help="simulated s per RTF run")
    parser.add_argument("--repeats", type=bounded(REPEATS, int), default=5,
                        help="runs of each; the median")
    args = parser.parse_args(argv)
    quiet_drake_warnings()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    _print_scan_costs(args.seconds)
    med = _print_table(bench_ir.configuration_runs(args.repeats, args.seconds))
    _print_in_place(med)
    print(f"(the median of {args.repeats} runs of {args.seconds:g} simulated s each; "
          f"load average now {os.getloadavg()[0]:.1f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
