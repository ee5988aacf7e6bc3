"""Cost of the robot's camera per frame (run: python tools/bench_camera.py).

Figures for the Corobot's camera (320 x 240, 30 deg vertical fov, sun + fill light, no shadows)
with each renderer (GL through an X display or a private Xvfb, the default here; VTK, through
GLX when a display is available), in the default scene with the robot driving a circle: the
render itself (`camera_frame_ms`), and what the camera adds to a simulation at 30 Hz
(`camera_overhead_ms`) under CENIC (the default: taken on its steps) and under SAP, rendering
in the simulation's thread or on a worker thread; both in `lab.bench_camera`. Prints a markdown
table, medians of `--repeats` runs. Each row and renderer is measured in a process of its own,
as a user's simulation would run: a camera on a render worker sets Mesa's thread count for the
whole process (`camera.llvmpipe_threads`), at its first engine.
"""

import argparse
import json
import statistics
import subprocess
import sys

from corobot_drake.arguments import (
    BENCH_SECONDS,
    REPEATS,
    ToolParser,
    bounded,
    one_line_errors,
)
from corobot_drake.config.scenario import SAP_PLANT
from corobot_drake.limits import Range
from lab.bench_camera import RENDERERS, camera_frame_ms, camera_overhead_ms

FRAMES = Range(1, 100_000, why="frames rendered per run")


@one_line_errors
def main(argv=None) -> int:
    parser = ToolParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=bounded(FRAMES, int), default=90,
                        help="frames rendered per run")
    parser.add_argument("--seconds", type=bounded(BENCH_SECONDS), default=3.0,
                        help="simulated s per run")
    parser.add_argument("--repeats", type=bounded(REPEATS, int), default=3,
                        help="median of this many runs")
    parser.add_argument("--renderers", nargs="+", default=list(RENDERERS), choices=RENDERERS,
                        help="renderers to measure")
    parser.add_argument("--cell", nargs=2, metavar=("RENDERER", "ROW"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.cell:
        print(json.dumps(_cell(args, args.cell[0], int(args.cell[1]))))
        return 0
    print(f"| camera, 320x240, ms per frame (median of {args.repeats}) | "
          + " | ".join(args.renderers) + " |")
    print("|---|" + "---|" * len(args.renderers))
    for k, (label, *_rest) in enumerate(_rows(args)):
        cells = [_measured_apart(args, r, k) for r in args.renderers]
        print(f"| {label} | " + " | ".join(cells) + " |", flush=True)
    return 0


def _measured_apart(args, renderer: str, row: int) -> str:
    """`renderer`'s cell of `_rows` row `row`, measured in a child process of this tool."""
    done = subprocess.run([sys.executable, __file__, "--cell", renderer, str(row), "--frames",
                           str(args.frames), "--seconds", str(args.seconds), "--repeats",
                           str(args.repeats)], capture_output=True, text=True)
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["no output"])[-1]
        raise RuntimeError(f"bench_camera: measuring {renderer} failed: {last}")
    return json.loads(done.stdout.splitlines()[-1])


def _cell(args, renderer: str, row: int) -> str:
    """`renderer`'s cell of `_rows` row `row` ("-": not measured)."""
    _, fn, kwargs, renderers = _rows(args)[row]
    if renderer not in renderers:
        return "-"
    return f"{statistics.median(fn(renderer=renderer, **kwargs) for _ in range(args.repeats)):.2f}"


def _rows(args) -> list[tuple]:
    """(label, function, its arguments, the renderers it applies to) of each row."""
    frames, seconds = {"frames": args.frames}, {"seconds": args.seconds}
    rows = [("render (the sensor's colour image), wall clock", camera_frame_ms,
             dict(clock="wall", **frames), RENDERERS),
            ("render, CPU time (all threads)", camera_frame_ms, dict(clock="cpu", **frames),
             RENDERERS)]
    sap = (SAP_PLANT % 0.01,)
    for plant, delay, read, label, renderers in (
            ((), None, False, "CENIC (the default, output_delay 0.03): taken on its steps, GL "
             "rendered on a worker thread (VTK in the simulation's thread), no frame read",
             RENDERERS),
            ((), None, True, "CENIC (the default), every frame read as it comes out",
             RENDERERS),
            ((), 0.0, False, "CENIC with output_delay 0: taken and rendered on its steps, in "
             "the simulation's thread", RENDERERS),
            (sap, 0.0, False, "SAP: in the simulation's thread (output_delay 0)", RENDERERS),
            (sap, None, False, "SAP: on a worker thread (output_delay 0.03)",
             ("RenderEngineGl",))):
        for clock in ("wall", "cpu"):
            rows.append((f"added to a simulation at 30 Hz, {label}, "
                         f"{'wall clock' if clock == 'wall' else 'CPU time'}",
                         camera_overhead_ms,
                         dict(clock=clock, delay=delay, overrides=plant, read=read,
                              **seconds), renderers))
    return rows


if __name__ == "__main__":
    sys.exit(main())
