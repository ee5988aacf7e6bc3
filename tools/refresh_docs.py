"""Refreshes the measured figures in README.md and docs/*.md (run: python tools/refresh_docs.py).

Every measured figure in the documentation sits in a generated block,

    <!-- BEGIN generated: NAME (COMMAND) -->
    ...
    <!-- END generated: NAME -->

and COMMAND is what produces it: a tool of tools/ (or examples/, or a test run with -s), or
`python tools/refresh_docs.py --measure NAME` for a few simple measurements this tool makes
itself through the Python API. This tool runs each block's command(s), renders the output as
Markdown and replaces the block's content (and writes the pictures the commands write).
Text outside the markers is never touched (lab/docs_blocks.py).

    python tools/refresh_docs.py                 # every block: deterministic ones first,
                                                 # pictures, timings last (--list: each cost)
    python tools/refresh_docs.py --only NAME ...  # some blocks
    python tools/refresh_docs.py --list          # the blocks, their commands and costs
    python tools/refresh_docs.py --check         # the cheap deterministic blocks: exit 1 on drift

Simulation results are deterministic (same numbers on every run), so `--check` can hold them to
the text; timings (real-time factors, per-frame and per-scan costs) are not: their blocks note
the machine's load average while they were measured, and only a refresh rewrites them.
"""

from __future__ import annotations

import argparse
import dataclasses as dc
import datetime
import difflib
import json
import math
import os
import re
import shlex
import statistics
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace

from corobot_drake.resources import DEFAULT_SCENARIO
from lab.docs_blocks import (
    BlockError,
    find_blocks,
    replace_block,
    wrap_markdown,
)

REPO = Path(__file__).resolve().parent.parent
DOCS = ("README.md", *sorted(f"docs/{p.name}" for p in (REPO / "docs").glob("*.md")))
DETERMINISTIC, PICTURE, TIMING = "deterministic", "picture", "timing"
ORDER = {DETERMINISTIC: 0, PICTURE: 1, TIMING: 2}
CHECK_SECONDS = 30.0
"""`--check` without `--only` re-renders the deterministic blocks estimated to cost this or less."""
NO_CAMERA = "robots: {corobot: {cameras: {front: {rgb: false}}}}"
CENIC_OVERRIDE = ("{plant_config: {time_step: 0}, simulator_config: {integration_scheme: "
                  "cenic, max_step_size: 0.01, use_error_control: false}}")
"""`scenario.CENIC_PLANT` at 10 ms, as the command line writes it."""
OLD_CHECKOUT = "/tmp/corobot-268a52c"
"""The checkout `bench_compare` measures against: `git worktree add /tmp/corobot-268a52c
268a52c` (the commit before CENIC and the lean per-step path)."""


# --- Commands and their outputs ---------------------------------------------------------------

@dc.dataclass
class Output:
    """What one run of a command printed, and the machine's state while it ran."""

    command: str
    stdout: str
    seconds: float
    load: tuple[float, float]
    """Smallest and largest 1-minute load average sampled during the run."""
    started: datetime.datetime


def _argv(command: str) -> list[str]:
    argv = shlex.split(command)
    return [sys.executable, *argv[1:]] if argv[0] == "python" else argv


def run_command(command: str, label: str, ok: tuple[int, ...] = (0,)) -> Output:
    """Runs `command` (as shown in the docs, from the repository's top) and streams its output,
    each line prefixed with `label`, to stderr as progress."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(REPO), *filter(None, [os.environ.get("PYTHONPATH")])]))
    loads = [os.getloadavg()[0]]
    started, start = datetime.datetime.now(), time.perf_counter()
    print(f"[{label}] $ {command}", file=sys.stderr, flush=True)
    proc = subprocess.Popen(_argv(command), cwd=REPO, env=env, stdout=subprocess.PIPE,
                            text=True, bufsize=1)
    done = threading.Event()
    last = [start]

    def sample() -> None:
        """Samples the load; says the command is still running after a minute of silence."""
        while not done.wait(5.0):
            loads.append(os.getloadavg()[0])
            if time.perf_counter() - last[0] > 60.0:
                last[0] = time.perf_counter()
                print(f"[{label} {last[0] - start:5.0f} s] (running; load average "
                      f"{loads[-1]:.1f})", file=sys.stderr, flush=True)

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    lines = []
    for line in proc.stdout:
        lines.append(line)
        last[0] = time.perf_counter()
        print(f"[{label} {time.perf_counter() - start:5.0f} s] {line.rstrip()}",
              file=sys.stderr, flush=True)
    code = proc.wait()
    done.set()
    loads.append(os.getloadavg()[0])
    if code not in ok:
        raise RuntimeError(f"{command}: exit status {code}")
    return Output(command, "".join(lines), time.perf_counter() - start,
                  (min(loads), max(loads)), started)


class Runner:
    """Runs each command once per refresh, however many blocks show its output."""

    def __init__(self):
        self._done: dict[tuple[str, int], Output] = {}

    def outputs(self, block: Spec) -> list[list[Output]]:
        """For each of the block's commands, its `repeats` outputs."""
        result = []
        for cmd in block.commands:
            runs = []
            for i in range(cmd.repeats):
                key = (cmd.text, i)
                if key not in self._done:
                    label = block.name + (f" {i + 1}/{cmd.repeats}" if cmd.repeats > 1 else "")
                    self._done[key] = run_command(cmd.text, label, cmd.ok)
                runs.append(self._done[key])
            result.append(runs)
        return result


@dc.dataclass(frozen=True)
class Command:
    text: str
    """As the docs show it: `python tools/x.py --option value`, run from the repository's top."""
    repeats: int = 1
    """Runs (timings: each run gives one figure, the block shows their range)."""
    ok: tuple[int, ...] = (0,)
    """Exit statuses that still mean the output is good."""


@dc.dataclass(frozen=True)
class Spec:
    name: str
    file: str
    commands: tuple[Command, ...]
    render: Callable[[list[list[Output]]], str]
    kind: str
    seconds: float
    """Rough cost on the project's 2-core machine, all commands and repeats."""

    @property
    def shown(self) -> str:
        return "; ".join(c.text + (f" (x{c.repeats})" if c.repeats > 1 else "")
                         for c in self.commands)


# --- Helpers for rendering ----------------------------------------------------------------------

def _find(pattern: str, text: str, group: int | str = 1) -> str:
    m = re.search(pattern, text, re.MULTILINE)
    if not m:
        raise ValueError(f"no match for {pattern!r} in:\n{text}")
    return m[group]


def _num(pattern: str, text: str) -> float:
    return float(_find(pattern, text))


def _table(text: str) -> str:
    """The Markdown table lines of a tool's output."""
    return "\n".join(line for line in text.splitlines() if line.startswith("|"))


def _load(outputs: list[Output]) -> str:
    lo = min(o.load[0] for o in outputs)
    hi = max(o.load[1] for o in outputs)
    return f"{lo:.1f}" if f"{lo:.1f}" == f"{hi:.1f}" else f"{lo:.1f}-{hi:.1f}"


def _measured(outputs: list[Output]) -> str:
    """'2025-01-31, load average 1.2-3.4 on 2 cores' for a timing block."""
    day = min(o.started for o in outputs).strftime("%Y-%m-%d")
    return f"{day}, load average {_load(outputs)} on {os.cpu_count()} cores"


def _flat(outs: list[list[Output]]) -> list[Output]:
    return [o for runs in outs for o in runs]


def _range(values: list[float], fmt: str = "{:.1f}") -> str:
    lo, hi = fmt.format(min(values)), fmt.format(max(values))
    return lo if lo == hi else f"{lo}-{hi}"


def _as_markdown(text: str) -> str:
    """A tool's output as Markdown: its tables kept, every other line a list item."""
    out, previous = [], ""
    for line in text.strip().splitlines():
        line = line.rstrip()
        if not line:
            continue
        kind = "table" if line.startswith("|") else "item"
        if out and kind != previous:
            out.append("")
        out.append(line if kind == "table" else f"- {line.strip()}")
        previous = kind
    return "\n".join(out)


def _picture(alt: str, path: str, command: str) -> Callable:
    def render(outs):
        return f"![{alt}]({path})\n\n    {command}"
    return render


# --- Measurements this tool makes itself (--measure NAME) -------------------------------------

def _sim(*overrides: str):
    from corobot_drake.simulation import Simulation, quiet_drake_warnings

    quiet_drake_warnings()
    return Simulation.from_file(DEFAULT_SCENARIO, overrides=[NO_CAMERA, *overrides])


def measure_ir_at_start() -> dict:
    """The default scene's IR readings at t = 0."""
    robot = _sim().robot()
    return {"rear": dc.asdict(robot.ir("rear")), "distances": robot.ir_distances()}


def measure_saved_mid_drive() -> dict:
    """Saved while a DriveDistance runs (the scene of tests/simulation/test_motion.py),
    reloaded, both run on: the robots' distance apart (m) after 0.2 s and after 3.2 s."""
    from corobot_drake.simulation import Simulation

    script = ("robots: {corobot: {commands: [!DriveDistance {distance: -0.45, power: 1}, "
              "!RotateDegrees {degrees: 30, power: 0.5}, !Wait {seconds: 1.0}, "
              "!SetPower {left: 0.3, right: 0.3}]}}")
    sim = _sim(script)
    sim.advance(2.0)
    again = Simulation(sim.saved_scenario())

    def gap() -> float:
        a, b = sim.robot().position(), again.robot().position()
        return sum((p - q) ** 2 for p, q in zip(a, b, strict=True)) ** 0.5

    out = {}
    for label, seconds in (("after_0_2_s", 0.2), ("after_3_2_s", 3.0)):
        sim.advance(seconds)
        again.advance(seconds)
        out[label] = gap()
    return out


def measure_wheel_turn() -> dict:
    """Driving straight at 0.3 m/s for 1.5 s: front wheel rotation (encoders) over
    distance / R."""
    import math

    from corobot_drake.model import dimensions as dim

    sim = _sim()
    robot = sim.robot()
    sim.advance(0.3)
    robot.set_speed(0.3, 0.3)
    x0, y0, _ = robot.position()
    ticks0 = robot.encoders()
    sim.advance(1.5)
    x, y, _ = robot.position()
    distance = math.hypot(x - x0, y - y0)
    ticks = {k: v - ticks0[k] for k, v in robot.encoders().items()}
    turned = {k: v * 2 * math.pi / dim.ENCODER_TICKS_PER_REVOLUTION for k, v in ticks.items()}
    return {"distance": distance, "ratio": {k: t / (distance / dim.WHEEL_RADIUS)
                                            for k, t in turned.items()}}


def _event_cases() -> dict[str, list[str]]:
    """The default scene's overrides, physics only unless the case adds IR, with the periodic
    events on and between the plant's 10 ms steps."""
    from lab.bench import physics_only_overrides

    def ir(rate: float) -> list[str]:
        return [NO_CAMERA, f"robots: {{corobot: {{ir_sensors: {{front: {{scan_rate_hz: "
                           f"{rate}}}, rear: {{scan_rate_hz: {rate}}}}}}}}}"]

    physics = physics_only_overrides()
    return {
        "shipped": physics,
        "control_60_hz": [*physics, f"robots: {{corobot: {{drive: {{control_period: "
                                    f"{1 / 60!r}}}}}}}"],
        "control_50_hz": [*physics, "robots: {corobot: {drive: {control_period: 0.02}}}"],
        "ir_20_hz": ir(20.0),
        "ir_19_9_hz": ir(19.9),
        "ir_200_hz": ir(200.0),
    }


def _driving(overrides: list[str]):
    from corobot_drake.config.scenario import load_scenario
    from corobot_drake.simulation import Simulation, quiet_drake_warnings
    from lab.bench import DRIVING

    quiet_drake_warnings()
    return Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[DRIVING, *overrides]))


def measure_event_times(repeats: int = 5, seconds: float = 10.0) -> dict:
    """Real-time factors (wall, median of `repeats`) of the default scene driving, physics
    only, with the periodic events on and between the plant's 10 ms steps (`_event_cases`)."""
    cases = _event_cases()
    runs: dict[str, list[float]] = {name: [] for name in cases}
    for _ in range(repeats):  # in turn: a slow drift of the load spreads over all
        for name, overrides in cases.items():
            sim = _driving(overrides)
            start = time.perf_counter()
            sim.advance(seconds)
            runs[name].append(seconds / (time.perf_counter() - start))
            print(f"{name}: {runs[name][-1]:.2f}x", file=sys.stderr, flush=True)
    return {name: {"rtf": statistics.median(r), "rtf_min": min(r), "rtf_max": max(r)}
            for name, r in runs.items()}


def measure_step_counts(seconds: float = 3.0) -> dict:
    """Simulator steps per simulated second of the default scene driving (`_event_cases`):
    the same on every machine."""
    counts = {}
    for name, overrides in _event_cases().items():
        sim = _driving(overrides)
        sim.advance(seconds)
        counts[name] = sim.simulator.get_num_steps_taken() / seconds
    return counts


def measure_continuous_sensors(seconds: float = 9.0) -> dict:
    """What the sensors see under CENIC's continuous plant against SAP's discrete one, over
    the figure of eight (both IR sensors at 20 Hz): each scan's raw reading and the chassis
    position at that scan, the largest differences (m) and how many readings differ by more
    than 1 mm; then, under CENIC, the camera on against off: simulator steps per simulated
    second and the chassis' distance apart (m) at the end."""
    from corobot_drake.config.scenario import CENIC_PLANT, load_scenario
    from corobot_drake.simulation import Simulation, quiet_drake_warnings
    from lab.bench import DRIVING, sensor_overrides

    quiet_drake_warnings()

    def scans(*overrides: str, camera: bool = False):
        sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[
            DRIVING, *sensor_overrides(ir=True, camera=camera), *overrides]))
        robot, out = sim.robot(), []
        for k in range(1, round(seconds * 20) + 1):  # at the scans' own times, k / 20 s
            sim.advance_to(k * 0.05)
            out.append((robot.ir_distances(), robot.position()))
        return out, sim.simulator.get_num_steps_taken() / seconds

    cenic, steps = scans(CENIC_PLANT % 0.01)
    sap, _ = scans()
    reading = [abs(a[0][n] - b[0][n]) for a, b in zip(cenic, sap, strict=True) for n in a[0]]
    moved = [math.dist(a[1], b[1]) for a, b in zip(cenic, sap, strict=True)]
    with_camera, camera_steps = scans(CENIC_PLANT % 0.01, camera=True)
    return {"readings": len(reading), "max_reading_m": max(reading),
            "over_1_mm": sum(d > 1e-3 for d in reading), "max_position_m": max(moved),
            "steps_per_second": steps, "camera_steps_per_second": camera_steps,
            "camera_position_m": math.dist(with_camera[-1][1], cenic[-1][1])}


MEASUREMENTS = {
    "continuous-sensors": measure_continuous_sensors,
    "ir-at-start": measure_ir_at_start,
    "saved-mid-drive": measure_saved_mid_drive,
    "wheel-turn": measure_wheel_turn,
    "event-times": measure_event_times,
    "step-counts": measure_step_counts,
}


def _measure(name: str, repeats: int = 1) -> Command:
    return Command(f"python tools/refresh_docs.py --measure {name}", repeats)


def _json(outs: list[list[Output]], index: int = 0) -> dict:
    return json.loads(outs[index][0].stdout)


# --- The blocks ---------------------------------------------------------------------------------
# Renderers take, for each of the block's commands, the list of its runs' outputs.

def _shipped_scaling() -> float:
    from corobot_drake.config.scenario import load_scenario

    return load_scenario(DEFAULT_SCENARIO).robots["corobot"].drive.motor_torque_scaling


def _top_speed(text: str) -> tuple[float, float]:
    """(scaling, top speed) of a tuning run's first iteration."""
    pattern = r"iteration 1: scaling ([\d.]+) -> top speed ([\d.]+) m/s"
    return float(_find(pattern, text, 1)), float(_find(pattern, text, 2))


def _ir_code(m: dict) -> str:
    rear, d = m["rear"], m["distances"]
    reading = (f"IrReading(raw={rear['raw']:.5g}, range={rear['range']:.5g}, "
               f"normalized={rear['normalized']:.3g}, time={rear['time']:.1f})")
    distances = "{" + ", ".join(f"'{k}': {v:.5g}" for k, v in d.items()) + "}"
    return "\n".join(["```python", "robot = sim.robot()",
                      "robot.ir(\"rear\")".ljust(24) + f"# {reading}",
                      "robot.ir_distances()".ljust(24) + f"# {distances}", "```"])


def render_ir_start_sensors(outs) -> str:
    return _ir_code(_json(outs))


def render_looks_triangles(outs) -> str:
    text = outs[0][0].stdout
    counts = [line for line in text.splitlines() if " triangles" in line]
    total = int(_find(r"robot total\s+(\d+)", text))
    wheel = int(_find(r"wheel\.obj\s+(\d+)", text))
    wheels = int(_find(r"wheel\.obj\s+\d+ triangles\s+\(x(\d+)", text)) * wheel
    return ("\n".join(f"    {line}" for line in counts) +
            f"\n\nThe {wheels // wheel} wheels are {wheels:,} of the robot's {total:,} triangles "
            f"({100 * wheels / total:.0f}%).")


def render_wheel_turn(outs) -> str:
    ratios = _json(outs)["ratio"].values()
    return f"measured with the front encoders: {_range([100 * (r - 1) for r in ratios])}% more"


def render_saved_mid_drive(outs) -> str:
    m = _json(outs)
    return (f"{m['after_0_2_s'] * 1000:.2f} mm apart after 0.2 s, "
            f"{m['after_3_2_s'] * 1000:.1f} mm after 3.2 s")


def render_resume_landing(outs) -> str:
    o = outs[0][0]
    first = o.stdout.strip().splitlines()[0]
    return f"`{o.command}`: {first}\n\n{_table(o.stdout)}"


def render_landing_errors(outs) -> str:
    text = outs[0][0].stdout.strip()
    failed = re.search(r"\| [+-][\d.]+ \(\w+\) \|", text)  # an error cell with its status
    return text + ("\n\nAll commands succeeded." if not failed else
                   "\n\nSome commands did not succeed: their status follows the error.")


def render_drive_drift(outs) -> str:
    rows, seeds = [], ""
    for runs in outs:
        text = runs[0].stdout
        m = re.search(r"summary: profile (\S+), seeds (\d+)\.\.(\d+), (\d+) loops: mean drift "
                      r"after each loop \(mm\) ([\d. ]+); drift per loop ([\d.]+) mm mean, "
                      r"([\d.]+) max; (\d+) failed commands", text)
        seeds = f"{m[2]}-{m[3]}"
        after = m[5].split()
        rows.append(f"| {m[1]} | " + " | ".join(after) + f" | {m[6]}, {m[7]} | {m[8]} |")
    loops = len(after)
    head = ("| profile | " + " | ".join(f"after loop {i}" for i in range(1, loops + 1))
            + " | drift per loop (mean, max over seeds) | failed commands |")
    return (f"Drift from the start, mm, mean over seeds {seeds} (default scene, camera off, "
            f"10 ms):\n\n{head}\n|" + "---|" * (loops + 3) + "\n" + "\n".join(rows) +
            "\n\nCommands: " + ", ".join(f"`{runs[0].command}`" for runs in outs) + ".")


def render_tune(outs) -> str:
    from corobot_drake.model import dimensions as dim

    text = outs[0][0].stdout
    lines = [re.sub(r"\s+\[[\d.]+ s\]$", "", line) for line in text.splitlines()
             if not line.startswith(("plot:", "tuning "))]
    tuned = _num(r"^motor_torque_scaling: ([\d.]+)", text)
    no_slip = dim.TARGET_TOP_SPEED / dim.WHEEL_RADIUS
    shipped, speed = _top_speed(outs[1][0].stdout)
    return ("\n".join(f"    {line}" for line in lines) +
            f"\n\n{tuned:.2f} is {100 * (tuned / no_slip - 1):.1f}% above the no-slip "
            f"{no_slip:.3f} ({dim.TARGET_TOP_SPEED:g} m/s / {dim.WHEEL_RADIUS:g} m): the tyres "
            f"creep under the servo. The shipped {shipped:g} gives {speed:.4f} m/s "
            f"(`{outs[1][0].command}`).")


def render_tune_sweep(outs) -> str:
    text = outs[0][0].stdout
    pairs = re.findall(r"^scaling ([\d.]+): steady speed ([\d.]+) m/s", text, re.M)
    tuned = _num(r"^motor_torque_scaling: ([\d.]+)", text)
    return ("| MotorTorqueScaling | steady speed at power 1 (m/s) |\n|---|---|\n"
            + "\n".join(f"| {a} | {b} |" for a, b in pairs)
            + f"\n\nInterpolated for the target: {tuned:.3f}.")


def render_fit(outs) -> str:
    text = outs[0][0].stdout
    scaling = re.search(r"^motor_torque_scaling: ([\d.]+) \(\+- ([\d.]+)\)", text, re.M)
    slew = re.search(r"^slew_rate: ([\d.]+) rad/s\^2 \(\+- ([\d.]+)\)", text, re.M)
    residual = _num(r"^residual: ([\d.]+) rad/s RMS", text)
    return (f"scaling {float(scaling[1]):.3f} (+- {float(scaling[2]):.3f}), slew "
            f"{float(slew[1]):.3f} rad/s^2 (+- {float(slew[2]):.3f}), residual {residual:.2f} "
            f"rad/s RMS")


def render_fit_stall(outs) -> str:
    text = outs[0][0].stdout
    stall = _find(r"([\d.]+-[\d.]+ s) stall", text)
    scaling = _num(r"^motor_torque_scaling: ([\d.]+) \(", text)
    slew = _num(r"^slew_rate: ([\d.]+) rad/s\^2", text)
    dropped = _num(r"^dropped (\d+) stretch", text)
    return (f"scaling {scaling:.3f}, slew {slew:.2f} rad/s^2, with {dropped:.0f} stretches "
            f"dropped (the stall {stall} and the outliers at its edges)")


def render_calibrate_odometry(outs) -> str:
    text = outs[0][0].stdout
    lines = [line for line in text.splitlines() if line.startswith((
        "effective_", "residuals", "end position error", "drive test", "with the calibrated"))]
    return "\n".join(f"    {line}" for line in lines)


def render_tire_grip(outs) -> str:
    """The table and the pick (deterministic; the sweep's wall time is in the prose)."""
    o = outs[0][0]
    runs = _find(r"^tire grip: (\d+) runs", o.stdout)
    picked = _find(r"^picked: (.+)$", o.stdout)
    return (f"`{o.command}` ({runs} runs; worst tilt: the largest over both directions, both "
            f"angles and both powers at that step; spin against b u / (a^2 + b^2) at full "
            f"power):\n\n{_table(o.stdout)}\n\nPicked: {picked}.")


def render_bench_full(outs) -> str:
    o = outs[0][0]
    machine = _find(r"^machine: (.+)$", o.stdout)
    rest = [line for line in o.stdout.splitlines()
            if line.startswith(("in place:", "micro-benchmark:"))]
    return (f"Measured {o.started:%Y-%m-%d}, load average {_load([o])} (`{o.command}`), on "
            f"{machine}:\n\n{_table(o.stdout)}\n\n" + "\n".join(f"- {line}" for line in rest))


def render_bench_robots(outs) -> str:
    o = outs[0][0]
    return (f"Measured {o.started:%Y-%m-%d}, load average {_load([o])} (`{o.command}`):\n\n"
            f"{_table(o.stdout)}")


def render_continuous_sensors(outs) -> str:
    o = outs[0][0]
    m = _json(outs)
    return wrap_markdown(
        f"`{o.command}`: over the figure of eight (9 s), the {m['readings']} readings of both "
        f"IR sensors at 20 Hz differ between CENIC and SAP by at most "
        f"{1000 * m['max_reading_m']:.2f} mm ({m['over_1_mm']} by more than 1 mm), while the "
        f"robot's position at the scans differs by up to {1000 * m['max_position_m']:.1f} mm "
        f"(the two integrators' trajectories). Under CENIC the simulator takes "
        f"{m['steps_per_second']:.0f} steps per simulated second without the camera and "
        f"{m['camera_steps_per_second']:.0f} with it at 30 Hz; with the camera the robot ends "
        f"{1000 * m['camera_position_m']:.1f} mm from where it ends without.")


def _default_column(outs) -> tuple[list[str], list[list[float]], list[Output]]:
    """(stacks, wall RTF per stack per run, outputs) of the default-column runs."""
    runs = outs[0]
    stacks, values = [], []
    for o in runs:
        rows = [line for line in _table(o.stdout).splitlines()[2:]]
        stacks = [r.split("|")[1].strip() for r in rows]
        values.append([float(_find(r"\| ([\d.]+)x \(", r)) for r in rows])
    return stacks, values, runs


def render_default_runs(outs) -> str:
    stacks, _, runs = _default_column(outs)
    head = "| stack | " + " | ".join(
        f"run {i} ({o.started:%H:%M}, load {_load([o])})" for i, o in enumerate(runs, 1)) + " |"
    lines = [head, "|---|" + "---|" * len(runs)]
    cells = [[r.split("|")[2].strip() for r in _table(o.stdout).splitlines()[2:]] for o in runs]
    for i, stack in enumerate(stacks):
        lines.append(f"| {stack} | " + " | ".join(c[i] for c in cells) + " |")
    return (f"The default column alone, {len(runs)} runs ({_measured(runs)}; "
            f"`{runs[0].command}`):\n\n" + "\n".join(lines))


def render_unit_costs(outs) -> str:
    ir, raycast, camera = (runs[0].stdout for runs in outs)
    direct = re.search(r"called directly: ([\d.]+) us CPU \(median batch\), ([\d.]+) us CPU "
                       r"\(best batch\)", ir)
    in_place = _num(r"in place \(called by the Simulator.*?\): ([\d.]+) us CPU", ir)
    fan = _num(r"full scan, 2 x cast_fan.*median\s+([\d.]+) us", raycast)

    def row(prefix: str, clock: str) -> list[str]:
        for line in _table(camera).splitlines()[2:]:
            cells = [c.strip() for c in line.strip("|").split("|")]
            if cells[0].startswith(prefix) and cells[0].endswith(clock):
                return cells[1:]
        raise ValueError(prefix)

    render = row("render (the sensor", "wall clock")
    sync = row("added to a simulation at 30 Hz, in the simulation's thread", "wall clock")
    async_wall = row("added to a simulation at 30 Hz, on a worker thread", "wall clock")
    async_cpu = row("added to a simulation at 30 Hz, on a worker thread", "CPU time")
    lines = [
        "| what | cost | how |", "|---|---|---|",
        f"| IR scan of both sensors, the two update handlers called directly (CPU, median "
        f"batch; best batch) | {float(direct[1]) / 1000:.3f} ms; {float(direct[2]) / 1000:.3f} "
        f"ms | `tools/bench_ir.py` |",
        f"| IR scan, the ray cast alone (2 sensors x 6 rays, wall, median) | "
        f"{fan / 1000:.3f} ms | `tools/bench_raycast.py` |",
        f"| IR scan of both sensors, in place (timed inside the running simulation; cold "
        f"caches; CPU, median) | {in_place / 1000:.3f} ms | `tools/bench_ir.py` |",
        f"| camera frame, 320 x 240, render only, GL / VTK | {render[0]} / {render[1]} ms | "
        f"`tools/bench_camera.py` |",
        f"| camera frame at 30 Hz, added wall time in the simulation, asynchronous GL "
        f"(default) | {async_wall[0]} ms | `tools/bench_camera.py` |",
        f"| camera frame at 30 Hz, added CPU time, asynchronous GL (default) | {async_cpu[0]} "
        f"ms | `tools/bench_camera.py` |",
        f"| camera frame at 30 Hz, synchronous (`output_delay: 0`), GL / VTK, added wall time "
        f"| {sync[0]} / {sync[1]} ms | `tools/bench_camera.py` |",
    ]
    return f"Measured {_measured(_flat(outs))}:\n\n" + "\n".join(lines)


EVENT_CASES = (
    ("shipped", "as shipped (drive, command source and motion every 10 ms: on the plant's "
                "steps)"),
    ("control_60_hz", "the same systems at the book's 60 Hz (`drive.control_period: 1/60`: 40 "
                      "of their 60 event times a second fall between steps)"),
    ("control_50_hz", "the same systems at 50 Hz (`drive.control_period: 0.02`: every event on "
                      "a step, half as many)"),
    ("ir_20_hz", "+ 2 IR sensors at 20 Hz (on steps)"),
    ("ir_19_9_hz", "+ 2 IR sensors at 19.9 Hz (between steps)"),
    ("ir_200_hz", "+ 2 IR sensors at 200 Hz (half of them between steps)"),
)
"""`_event_cases`' rows as the docs name them."""


def render_event_times(outs) -> str:
    runs = outs[0]
    m = json.loads(runs[0].stdout)
    lines = ["| change | real-time factor, median (min-max) |", "|---|---|"]
    for key, label in EVENT_CASES:
        r = m[key]
        lines.append(f"| {label} | {r['rtf']:.1f}x ({r['rtf_min']:.1f}-{r['rtf_max']:.1f}) |")
    return (f"Measured {_measured(runs)} (`{runs[0].command}`; physics only unless a row adds "
            f"IR, camera off, 5 runs of 10 simulated s each in turn, wall clock):\n\n"
            + "\n".join(lines))


def render_step_counts(outs) -> str:
    """Steps per simulated second: deterministic, so `--check` holds the text to them."""
    o = outs[0][0]
    m = json.loads(o.stdout)
    lines = ["| change | simulator steps per simulated s |", "|---|---|"]
    lines += [f"| {label} | {m[key]:.1f} |" for key, label in EVENT_CASES]
    return (f"`{o.command}` (the default scene driving its figure of eight for 3 s, physics only "
            f"unless a row adds IR):\n\n" + "\n".join(lines))


def render_bench_ir(outs) -> str:
    o = outs[0][0]
    text = "\n".join(line for line in o.stdout.splitlines() if not line.startswith(
        ("load average", "(the median")))
    return f"Measured {_measured([o])} (`{o.command}`):\n\n{_as_markdown(text)}"


def render_bench_study(outs) -> str:
    o = outs[0][0]
    return f"Measured {_measured([o])} (`{o.command}`):\n\n{_as_markdown(o.stdout.strip())}"


def render_command_table(outs) -> str:
    """The command and the table it printed (a deterministic block: no load, no date)."""
    o = outs[0][0]
    return f"`{o.command}`:\n\n{_table(o.stdout)}"


def render_gym_evaluation(outs) -> str:
    """The held-out table and the trained policy's margin over its hand-written start."""
    o = outs[0][0]
    margin = _find(r"^(Success, trained minus hand-written: .*)$", o.stdout)
    return f"`{o.command}`:\n\n{_table(o.stdout)}\n\n{margin}"


def render_gym_training(outs) -> str:
    o = outs[0][0]
    trained = _find(r"^(Trained on .*)$", o.stdout)
    curve = _table(o.stdout.split("Held-out seeds")[0])
    return (f"Measured {_measured([o])} (`{o.command}`): {trained}\n\n{curve}\n\n"
            f"![GoToGoal learning curve](images/gym_learning_curve.png)")


def render_table_with_load(outs) -> str:
    o = outs[0][0]
    return f"Measured {_measured([o])} (`{o.command}`):\n\n{_table(o.stdout)}"


def render_tables_with_load(outs) -> str:
    """Several tables of one command, each kept apart."""
    o = outs[0][0]
    tables = [_table(part) for part in o.stdout.split("\n\n")]
    return f"Measured {_measured([o])} (`{o.command}`):\n\n" + "\n\n".join(t for t in tables
                                                                            if t)


def render_camera_cost(outs) -> str:
    o = outs[0][0]
    ratios = {r.split("|")[1].strip(): r.split("|")[4].strip()
              for r in _table(o.stdout).splitlines()[2:]}
    return (f"Measured {_measured([o])} (`{o.command}`):\n\n{_table(o.stdout)}\n\n"
            f"Meshes over boxes: {ratios['robot-camera']} for the robot's own camera, "
            f"{ratios['chase']} for the chase view.")


def render_creep(outs) -> str:
    o = outs[0][0]
    return f"`{o.command}`:\n\n{o.stdout.strip()}"


def render_hostile_inputs(outs) -> str:
    o = outs[0][0]
    defects = [line for line in o.stdout.splitlines() if line.startswith("defect:")]
    return (f"Measured {_measured([o])} (`{o.command}`; CPU time per input, pydrake's import "
            f"aside):\n\n{_table(o.stdout)}"
            + (f"\n\n{len(defects)} defects: see the command's output." if defects else ""))


def render_drive_legs(outs) -> str:
    o = outs[0][0]
    loops = int(_find(r"^(\d+) loops: final drift", o.stdout))
    drift = _num(r"final drift ([\d.]+) mm", o.stdout)
    return (f"seed 1, {loops} loop through the server: {drift:.1f} mm; {o.seconds:.0f} s of wall "
            f"time, the server's start included, at load average {_load([o])}")


def render_server_flood(outs) -> str:
    o = outs[0][0]
    rtf = _num(r"real-time factor ([\d.]+) \(without the load", o.stdout)
    base = _num(r"\(without the load: ([\d.]+)\)", o.stdout)
    passed = re.search(r"\b1 passed\b", o.stdout) is not None
    return (f"Measured {_measured([o])} (`{o.command}`): real-time factor {rtf:.2f} under the "
            f"load (without it: {base:.2f}); the test {'passed' if passed else 'FAILED'}.")


def render_server_memory(outs) -> str:
    o = outs[0][0]
    paragraph = next(line for line in o.stdout.splitlines() if line.startswith("`--serve`"))
    return wrap_markdown(f"Measured {_measured([o])}: {paragraph}")


def blocks() -> list[Spec]:
    """Every generated block of the docs, in the order a full refresh runs them."""
    c = _shared_commands()
    specs = [*_model_and_command_specs(c), *_front_end_specs(c), *_performance_specs(c)]
    return sorted(specs, key=lambda s: ORDER[s.kind])


def _shared_commands() -> SimpleNamespace:
    """The commands (and pictures) several blocks read."""
    shipped = _shipped_scaling()
    top_speed = Command(f"python tools/tune_motor_torque_scaling.py --scaling {shipped:g} "
                        f"--max-iterations 1", ok=(0, 1))
    meshes = Command("python tools/make_meshes.py --check", ok=(0, 1))
    ir_start = _measure("ir-at-start")
    landing = Command("python tools/landing_errors.py --plot docs/images/landing_errors.png")
    bench_ir = Command("python tools/bench_ir.py")
    bench_raycast = Command("python tools/bench_raycast.py")
    bench_camera = Command("python tools/bench_camera.py")
    default_column = Command('python tools/bench.py --plants "hydroelastic 10 ms" --seconds 5 '
                             '--repeats 5 --no-micro', repeats=3)
    pictures = [
        ("readme-picture-drive-test", "Drive test path", "drive_test.png",
         "python tools/drive_test.py --loops 3 --seed 1 --plot docs/images/drive_test.png", 25),
        ("readme-picture-beside-box", "The Corobot beside the giant box", "beside_box.png",
         "python tools/snapshot.py --eye 1.1,-0.9,0.55 --target=-0.45,0.1,0.3 "
         "--output docs/images/beside_box.png", 8),
        ("readme-picture-camera-view", "The robot's camera view", "camera_view.png",
         "python tools/snapshot.py --view robot-camera --pose 1.6,1.2,205 "
         "--output docs/images/camera_view.png", 8),
        ("readme-picture-chase", "Chase view", "chase.png",
         "python tools/snapshot.py --view chase --drive 0.7,0.45 --time 3 "
         "--output docs/images/chase.png", 8),
        ("readme-picture-collision-boxes", "Collision shapes", "collision_boxes.png",
         "python tools/snapshot.py --eye 1.1,-0.9,0.55 --target=-0.45,0.1,0.3 --visual boxes "
         "--output docs/images/collision_boxes.png", 8),
    ]
    return SimpleNamespace(
        top_speed=top_speed, meshes=meshes, ir_start=ir_start, landing=landing,
        bench_ir=bench_ir, bench_raycast=bench_raycast, bench_camera=bench_camera,
        default_column=default_column, pictures=pictures)


def _model_and_command_specs(c: SimpleNamespace) -> list[Spec]:
    """The model, tuning, commands and README's pictures."""
    return [
        Spec("looks-triangles", "docs/looks.md", (c.meshes,), render_looks_triangles,
             DETERMINISTIC, 3),
        Spec("sensors-ir-at-start", "docs/sensors.md", (c.ir_start,), render_ir_start_sensors,
             DETERMINISTIC, 8),
        Spec("tune-motor-torque-scaling", "docs/tuning.md",
             (Command("python tools/tune_motor_torque_scaling.py --scaling 20"), c.top_speed),
             render_tune, DETERMINISTIC, 10),
        Spec("tune-motor-torque-scaling-sweep", "docs/tuning.md",
             (Command("python tools/tune_motor_torque_scaling.py --sweep"),), render_tune_sweep,
             DETERMINISTIC, 40),
        Spec("fit-drive-log", "docs/tuning.md",
             (Command("python tools/fit_drive_log.py --simulate 12 20"),), render_fit,
             DETERMINISTIC, 5),
        Spec("step-limit", "docs/tuning.md", (Command("python tools/step_limit.py"),),
             render_command_table, DETERMINISTIC, 40),
        Spec("creep-isolate", "docs/tuning.md", (Command("python tools/creep.py --isolate"),),
             render_creep, DETERMINISTIC, 60),
        Spec("creep", "docs/tuning.md", (Command("python tools/creep.py"),), render_creep,
             DETERMINISTIC, 90),
        Spec("fit-drive-log-stall", "docs/tuning.md",
             (Command("python tools/fit_drive_log.py --simulate 12 20 --stall"),),
             render_fit_stall, DETERMINISTIC, 40),
        Spec("calibrate-odometry", "docs/tuning.md",
             (Command("python tools/calibrate_odometry.py --simulate --drive-test"),),
             render_calibrate_odometry, DETERMINISTIC, 300),
        Spec("wheel-turn", "docs/looks.md", (_measure("wheel-turn"),), render_wheel_turn,
             DETERMINISTIC, 5),
        Spec("saved-mid-drive", "docs/commands.md", (_measure("saved-mid-drive"),),
             render_saved_mid_drive, DETERMINISTIC, 10),
        Spec("resume-landing", "docs/commands.md",
             (Command("python tools/resume_landing.py"),), render_resume_landing,
             DETERMINISTIC, 300),
        Spec("landing-errors", "docs/commands.md", (c.landing,), render_landing_errors,
             DETERMINISTIC, 90),
        Spec("drive-test-drift", "docs/commands.md", tuple(
            Command(f"python tools/drive_test.py --loops 3 --seeds 20 --workers 1 --profile {p} "
                    f"--out out/drive_test_{p}")
            for p in ("closed_loop", "seed")), render_drive_drift, DETERMINISTIC, 820),
        *(Spec(name, "README.md", (Command(cmd),), _picture(alt, f"docs/images/{png}", cmd),
               PICTURE, seconds) for name, alt, png, cmd, seconds in c.pictures),
    ]


def _front_end_specs(c: SimpleNamespace) -> list[Spec]:
    """The services, sensors, recording, gym and studies."""
    return [
        Spec("drive-legs-server", "docs/services.md",
             (Command("python examples/drive_legs.py --loops 1 --seed 1"),), render_drive_legs,
             TIMING, 45),
        Spec("server-flood", "docs/services.md",
             (Command("python -m pytest -s -q tests/service/test_server.py -k flood", ok=(0, 1)),),
             render_server_flood, TIMING, 30),
        Spec("server-memory", "docs/services.md",
             (Command("python tools/bench_memory.py --sim-minutes 60 --warmup-minutes 1 "
                      "--sample-every 60"),), render_server_memory, TIMING, 2200),
        Spec("camera-cost", "docs/looks.md", (Command("python tools/camera_cost.py"),),
             render_camera_cost, TIMING, 70),
        Spec("bench-camera", "docs/sensors.md", (c.bench_camera,), render_table_with_load,
             TIMING, 90),
        Spec("bench-ir", "docs/sensors.md", (c.bench_ir,), render_bench_ir, TIMING, 50),
        Spec("bench-recording", "docs/recording.md",
             (Command("python tools/bench_recording.py"),), render_table_with_load, TIMING, 300),
        Spec("bench-ros2", "README.md", (Command("python tools/bench_ros2.py"),),
             render_tables_with_load, TIMING, 400),
        Spec("gym-evaluation", "docs/gym.md",
             (Command("python tools/train_policy.py --evaluate"),), render_gym_evaluation,
             DETERMINISTIC, 900),
        Spec("gym-training", "docs/gym.md", (Command("python tools/train_policy.py"),),
             render_gym_training, PICTURE, 1200),
        Spec("bench-gym", "docs/gym.md", (Command("python tools/bench_gym.py"),),
             render_bench_study, TIMING, 150),
        Spec("bench-study", "docs/studies.md",
             (Command("python tools/bench_study.py --seeds 24 --duration 8"),),
             render_bench_study, TIMING, 150),
    ]


def _performance_specs(c: SimpleNamespace) -> list[Spec]:
    """docs/performance.md's and the README's costs."""
    return [
        Spec("unit-costs", "docs/performance.md", (c.bench_ir, c.bench_raycast, c.bench_camera),
             render_unit_costs, TIMING, 150),
        Spec("event-times", "docs/performance.md", (_measure("event-times"),),
             render_event_times, TIMING, 70),
        Spec("step-counts", "docs/performance.md", (_measure("step-counts"),),
             render_step_counts, DETERMINISTIC, 15),
        Spec("tire-grip", "docs/tuning.md",
             (Command("python tools/tune_tire_grip.py --plot docs/images/tire_grip.png",
                      ok=(0, 1)),),
             render_tire_grip, DETERMINISTIC, 2500),
        Spec("default-column-runs", "docs/performance.md", (c.default_column,),
             render_default_runs, TIMING, 110),
        Spec("readme-hostile-inputs", "README.md",
             (Command("python tools/hostile_inputs.py", ok=(0, 1)),), render_hostile_inputs,
             TIMING, 90),
        Spec("bench-robots", "docs/performance.md",
             (Command("python tools/bench.py --robots 1,2,4,8,16 --no-table --no-micro "
                      "--seconds 5 --repeats 1"),), render_bench_robots, TIMING, 300),
        Spec("bench-layers", "docs/performance.md",
             (Command("python tools/bench.py --layers --no-table --no-micro --seconds 4 "
                      "--repeats 5"),), render_bench_robots, TIMING, 300),
        Spec("count-instructions", "docs/performance.md",
             (Command('python tools/count_instructions.py --cache-sim '
                      '--override "plant_config: {discrete_contact_approximation: similar}" '
                      '--override "plant_config: {use_sampled_output_ports: false}" '
                      '--override "robots: {corobot: {contact: {resolution_hint: 0.007}}}" '
                      '--override "world: {bodies: {giant_box: {fixed: true}}}" '
                      '--override "robots: {corobot: {drive: {control_period: 0.02}}}"'),),
             render_command_table, TIMING, 450),
        Spec("bench-compare", "docs/performance.md",
             (Command(f"python tools/bench_compare.py --old {OLD_CHECKOUT} --rounds 3 "
                      f"--new-override {shlex.quote(CENIC_OVERRIDE)}"),),
             render_bench_robots, TIMING, 600),
        Spec("continuous-sensors", "docs/performance.md", (_measure("continuous-sensors"),),
             render_continuous_sensors, DETERMINISTIC, 60),
        Spec("bench-full", "docs/performance.md",
             (Command("python tools/bench.py --seconds 5 --repeats 3"),), render_bench_full,
             TIMING, 200),
    ]


# --- The command line ---------------------------------------------------------------------------

def check_markers(specs: list[Spec]) -> list[str]:
    """Problems: a registered block without its markers, a marker no block owns, bad markers."""
    problems = []
    owned = {(s.file, s.name) for s in specs}
    for doc in DOCS:
        try:
            found = find_blocks((REPO / doc).read_text(), doc)
        except BlockError as e:
            problems.append(str(e))
            continue
        problems += [f"{doc}:{b.line}: block {n!r} is not one refresh_docs.py knows"
                     for n, b in found.items() if (doc, n) not in owned]
        problems += [f"{doc}: no block {s.name!r}" for s in specs
                     if s.file == doc and s.name not in found]
    return problems


def _list(specs: list[Spec]) -> None:
    for s in specs:
        line = find_blocks((REPO / s.file).read_text(), s.file)[s.name].line
        cheap = " (--check)" if s.kind == DETERMINISTIC and s.seconds <= CHECK_SECONDS else ""
        print(f"{s.name:32s} {s.file}:{line}  {s.kind}{cheap}, ~{s.seconds:.0f} s\n"
              f"{'':32s} {s.shown}")


def refresh(specs: list[Spec], check: bool) -> int:
    """Renders each block; writes it (or, with `check`, reports a difference). 1 on drift or
    when a block's command failed (the other blocks are still refreshed)."""
    runner, status = Runner(), 0
    start = time.perf_counter()
    for i, spec in enumerate(specs, 1):
        print(f"== [{i}/{len(specs)}] {spec.name} ({spec.kind}, ~{spec.seconds:.0f} s; "
              f"{time.perf_counter() - start:.0f} s so far)", file=sys.stderr, flush=True)
        path = REPO / spec.file
        try:
            content = spec.render(runner.outputs(spec))
            if find_blocks(path.read_text(), spec.file)[spec.name].multiline:
                content = wrap_markdown(content)
        except Exception as e:  # one block's failure leaves the others to refresh
            print(f"{spec.name}: FAILED, left as it was: {type(e).__name__}: {e}", flush=True)
            status = 1
            continue
        text = path.read_text()
        new = replace_block(text, spec.name, content, spec.shown, spec.file)
        if new == text:
            print(f"{spec.name}: unchanged", flush=True)
            continue
        if check:
            status = 1
            old = find_blocks(text, spec.file)[spec.name].content(text)
            print(f"{spec.file}: block {spec.name} differs from what its command prints now:")
            sys.stdout.writelines(difflib.unified_diff(
                (old + "\n").splitlines(True), (content + "\n").splitlines(True),
                "in the file", "now"))
        else:
            path.write_text(new)
            print(f"{spec.name}: rewrote {spec.file}", flush=True)
    return status


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--only", nargs="+", metavar="NAME", help="these blocks only (None: all)")
    p.add_argument("--list", action="store_true", help="list the blocks, their commands, costs")
    p.add_argument("--check", action="store_true",
                   help="re-render deterministic blocks (without --only: the cheap ones) and "
                        "exit 1 if any differs from the file; writes nothing")
    p.add_argument("--measure", choices=sorted(MEASUREMENTS),
                   help="make one of this tool's own measurements and print it (JSON; None: "
                   "refresh instead)")
    args = p.parse_args(argv)
    if args.measure:
        print(json.dumps(MEASUREMENTS[args.measure](), indent=1))
        return 0
    specs = blocks()
    problems = check_markers(specs)
    for problem in problems:
        print(f"error: {problem}", file=sys.stderr)
    if problems:
        return 2
    if args.only:
        unknown = set(args.only) - {s.name for s in specs}
        if unknown:
            print(f"error: no block {', '.join(sorted(unknown))} (see --list)", file=sys.stderr)
            return 2
        specs = [s for s in specs if s.name in args.only]
    if args.list:
        _list(specs)
        return 0
    if args.check:
        chosen = [s for s in specs if s.kind == DETERMINISTIC
                  and (args.only or s.seconds <= CHECK_SECONDS)]
        skipped = [s.name for s in specs if s not in chosen]
        if args.only and skipped:
            print(f"note: not checked (their figures vary run to run): {', '.join(skipped)}",
                  file=sys.stderr)
        return refresh(chosen, check=True)
    return refresh(specs, check=False)


if __name__ == "__main__":
    sys.exit(main())
