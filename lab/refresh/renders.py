"""Renderers: for each block, its commands' outputs (a list of runs per command) -> the block's
Markdown."""

from __future__ import annotations

import json
import re

from corobot_drake.readings import IrReading
from corobot_drake.resources import DEFAULT_SCENARIO
from lab.docs_blocks import wrap_markdown
from lab.refresh.measures import json_output
from lab.refresh.runner import Output
from lab.refresh.text import (
    as_markdown,
    find,
    flat,
    load_line,
    measured_line,
    number,
    table,
    value_range,
)

# Renderers take, for each of the block's commands, the list of its runs' outputs.

def shipped_scaling() -> float:
    from corobot_drake.config.scenario import load_scenario

    return load_scenario(DEFAULT_SCENARIO).robots["corobot"].drive.motor_torque_scaling


def _top_speed(text: str) -> tuple[float, float]:
    """(scaling, top speed) of a tuning run's first iteration."""
    pattern = r"iteration 1: scaling ([\d.]+) -> top speed ([\d.]+) m/s"
    return float(find(pattern, text, 1)), float(find(pattern, text, 2))


def _ir_code(m: dict) -> str:
    rear, d = m["rear"], m["distances"]
    reading = repr(IrReading(**rear))  # as Python prints it
    distances = "{" + ", ".join(f"'{k}': {v:.5g}" for k, v in d.items()) + "}"
    return "\n".join(["```python", "robot = sim.robot()",
                      "robot.ir(\"rear\")".ljust(24) + f"# {reading}",
                      "robot.ir_distances()".ljust(24) + f"# {distances}", "```"])


def render_ir_start_sensors(outs) -> str:
    return _ir_code(json_output(outs))


def render_samples_error(outs) -> str:
    """The CLI's line for a bad `samples`, inline (exactly one line, exit status 2)."""
    m = json_output(outs)
    (line,) = m["stderr"].splitlines()
    assert m["status"] == 2, m
    return f"`{line}`"


def render_looks_triangles(outs) -> str:
    text = outs[0][0].stdout
    counts = [line for line in text.splitlines() if " triangles" in line]
    total = int(find(r"robot total\s+(\d+)", text))
    wheel = int(find(r"wheel\.obj\s+(\d+)", text))
    wheels = int(find(r"wheel\.obj\s+\d+ triangles\s+\(x(\d+)", text)) * wheel
    return ("\n".join(f"    {line}" for line in counts) +
            f"\n\nThe {wheels // wheel} wheels are {wheels:,} of the robot's {total:,} triangles "
            f"({100 * wheels / total:.0f}%).")


def render_wheel_turn(outs) -> str:
    ratios = json_output(outs)["ratio"].values()
    return f"measured with the front encoders: {value_range([100 * (r - 1) for r in ratios])}% more"


def render_saved_mid_drive(outs) -> str:
    m = json_output(outs)
    return (f"{m['after_0_2_s'] * 1000:.2f} mm apart after 0.2 s, "
            f"{m['after_3_2_s'] * 1000:.1f} mm after 3.2 s")


def render_resume_landing(outs) -> str:
    o = outs[0][0]
    first = o.stdout.strip().splitlines()[0]
    return f"`{o.command}`: {first}\n\n{table(o.stdout)}"


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
    from corobot_drake.robots import robot_spec
    from corobot_drake.tuning.drive_tuning import COROBOT_TOP_SPEED

    text = outs[0][0].stdout
    lines = [re.sub(r"\s+\[[\d.]+ s\]$", "", line) for line in text.splitlines()
             if not line.startswith(("plot:", "tuning "))]
    tuned = number(r"^motor_torque_scaling: ([\d.]+)", text)
    radius = robot_spec().wheel_radius
    no_slip = COROBOT_TOP_SPEED / radius
    shipped, speed = _top_speed(outs[1][0].stdout)
    return ("\n".join(f"    {line}" for line in lines) +
            f"\n\n{tuned:.2f} is {100 * (tuned / no_slip - 1):.1f}% above the no-slip "
            f"{no_slip:.3f} ({COROBOT_TOP_SPEED:g} m/s / {radius:g} m): the tyres "
            f"creep under the servo. The shipped {shipped:g} gives {speed:.4f} m/s "
            f"(`{outs[1][0].command}`).")


def render_tune_sweep(outs) -> str:
    text = outs[0][0].stdout
    pairs = re.findall(r"^scaling ([\d.]+): steady speed ([\d.]+) m/s", text, re.M)
    tuned = number(r"^motor_torque_scaling: ([\d.]+)", text)
    return ("| MotorTorqueScaling | steady speed at power 1 (m/s) |\n|---|---|\n"
            + "\n".join(f"| {a} | {b} |" for a, b in pairs)
            + f"\n\nInterpolated for the target: {tuned:.3f}.")


def render_fit(outs) -> str:
    text = outs[0][0].stdout
    scaling = re.search(r"^motor_torque_scaling: ([\d.]+) \(\+- ([\d.]+)\)", text, re.M)
    slew = re.search(r"^slew_rate: ([\d.]+) rad/s\^2 \(\+- ([\d.]+)\)", text, re.M)
    residual = number(r"^residual: ([\d.]+) rad/s RMS", text)
    return (f"scaling {float(scaling[1]):.3f} (+- {float(scaling[2]):.3f}), slew "
            f"{float(slew[1]):.3f} rad/s^2 (+- {float(slew[2]):.3f}), residual {residual:.2f} "
            f"rad/s RMS")


def render_fit_stall(outs) -> str:
    text = outs[0][0].stdout
    stall = find(r"([\d.]+-[\d.]+ s) stall", text)
    scaling = number(r"^motor_torque_scaling: ([\d.]+) \(", text)
    slew = number(r"^slew_rate: ([\d.]+) rad/s\^2", text)
    dropped = number(r"^dropped (\d+) stretch", text)
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
    runs = find(r"^tire grip: (\d+) runs", o.stdout)
    picked = find(r"^picked: (.+)$", o.stdout)
    return (f"`{o.command}` ({runs} runs; worst tilt: the largest over both directions, both "
            f"angles and both powers at that step; spin against b u / (a^2 + b^2) at full "
            f"power):\n\n{table(o.stdout)}\n\nPicked: {picked}.")


def render_bench_full(outs) -> str:
    o = outs[0][0]
    machine = find(r"^machine: (.+)$", o.stdout)
    rest = [line for line in o.stdout.splitlines()
            if line.startswith(("in place:", "micro-benchmark:"))]
    return (f"Measured {o.started:%Y-%m-%d}, load average {load_line([o])} (`{o.command}`), on "
            f"{machine}:\n\n{table(o.stdout)}\n\n" + "\n".join(f"- {line}" for line in rest))


def render_bench_robots(outs) -> str:
    o = outs[0][0]
    return (f"Measured {o.started:%Y-%m-%d}, load average {load_line([o])} (`{o.command}`):\n\n"
            f"{table(o.stdout)}")


def render_profile_step(outs) -> str:
    o = outs[0][0]
    summary = next(line for line in o.stdout.splitlines() if line.startswith("The robot's"))
    return (f"Measured {o.started:%Y-%m-%d}, load average {load_line([o])} (`{o.command}`):\n\n"
            f"{table(o.stdout)}\n\n{summary}")


def render_continuous_sensors(outs) -> str:
    o = outs[0][0]
    m = json_output(outs)
    return wrap_markdown(
        f"`{o.command}`: over the figure of eight (9 s), the {m['readings']} readings of both "
        f"IR sensors at 20 Hz differ between CENIC and SAP by at most "
        f"{1000 * m['max_reading_m']:.2f} mm ({m['over_1_mm']} by more than 1 mm), while the "
        f"robot's position at the scans differs by up to {1000 * m['max_position_m']:.1f} mm "
        f"(the two integrators' trajectories). Under CENIC the simulator takes "
        f"{m['steps_per_second']:.0f} steps per simulated second without the camera and "
        f"{m['camera_steps_per_second']:.0f} with it at 30 Hz (its frames are taken on the "
        f"steps); with the camera the robot ends "
        + ("where it ends without, to the bit." if m["camera_position_m"] == 0 else
           f"{m['camera_position_m']:.1e} m from where it ends without."))


def render_box_push(outs) -> str:
    o = outs[0][0]
    m = json_output(outs)
    steps = list(m["cenic"])
    lines = ["| integrator | " + " | ".join(f"{1000 * float(h):g} ms" for h in steps) + " |",
             "|---|" + "---|" * len(steps)]
    lines += [f"| {label} | " + " | ".join(f"{1000 * m[key][h]:.0f} mm" for h in steps) + " |"
              for key, label in (("cenic", "CENIC"), ("sap", "SAP"))]
    return (f"`{o.command}`: how far the robot at power 0.5 pushes a free 2 kg, 0.2 m box in "
            "3 s, by step:\n\n" + "\n".join(lines))


def render_spin_steps(outs) -> str:
    o = outs[0][0]
    m = json_output(outs)
    steps = list(m["cenic"])
    head = "| integrator, figure | " + " | ".join(f"{1000 * float(h):g} ms" for h in steps) + " |"
    lines = [head, "|---|" + "---|" * len(steps)]
    for key, label in (("cenic", "CENIC"), ("sap", "SAP")):
        lines.append(f"| {label}, spin / prediction | "
                     + " | ".join(f"{m[key][h]['spin']:.3f}" for h in steps) + " |")
        lines.append(f"| {label}, straight speed (m/s) | "
                     + " | ".join(f"{m[key][h]['speed']:.4f}" for h in steps) + " |")
    return (f"`{o.command}` (full power on open ground, the study metrics over the last of "
            "3 s):\n\n" + "\n".join(lines))


def _default_column(outs) -> tuple[list[str], list[list[float]], list[Output]]:
    """(stacks, wall RTF per stack per run, outputs) of the default-column runs."""
    runs = outs[0]
    stacks, values = [], []
    for o in runs:
        rows = [line for line in table(o.stdout).splitlines()[2:]]
        stacks = [r.split("|")[1].strip() for r in rows]
        values.append([float(find(r"\| ([\d.]+)x \(", r)) for r in rows])
    return stacks, values, runs


def render_default_runs(outs) -> str:
    stacks, _, runs = _default_column(outs)
    head = "| stack | " + " | ".join(
        f"run {i} ({o.started:%H:%M}, load {load_line([o])})" for i, o in enumerate(runs, 1)) + " |"
    lines = [head, "|---|" + "---|" * len(runs)]
    cells = [[r.split("|")[2].strip() for r in table(o.stdout).splitlines()[2:]] for o in runs]
    for i, stack in enumerate(stacks):
        lines.append(f"| {stack} | " + " | ".join(c[i] for c in cells) + " |")
    return (f"The default column alone, {len(runs)} runs ({measured_line(runs)}; "
            f"`{runs[0].command}`):\n\n" + "\n".join(lines))


def render_unit_costs(outs) -> str:
    ir, raycast, camera = (runs[0].stdout for runs in outs)
    direct = re.search(r"called directly: ([\d.]+) us CPU \(median batch\), ([\d.]+) us CPU "
                       r"\(best batch\)", ir)
    in_place = number(r"in place \(called by the Simulator.*?\): ([\d.]+) us CPU", ir)
    fan = number(r"full scan, 2 x cast_fan.*median\s+([\d.]+) us", raycast)

    def row(prefix: str, clock: str) -> list[str]:
        for line in table(camera).splitlines()[2:]:
            cells = [c.strip() for c in line.strip("|").split("|")]
            if cells[0].startswith(prefix) and cells[0].endswith(clock):
                return cells[1:]
        raise ValueError(prefix)

    render = row("render (the sensor", "wall clock")
    on_steps = row("added to a simulation at 30 Hz, CENIC (the default,", "wall clock")
    on_steps_cpu = row("added to a simulation at 30 Hz, CENIC (the default,", "CPU time")
    read = row("added to a simulation at 30 Hz, CENIC (the default), every frame read",
               "wall clock")
    rendered_in_place = row("added to a simulation at 30 Hz, CENIC with output_delay 0",
                            "wall clock")
    sync = row("added to a simulation at 30 Hz, SAP: in the simulation's thread", "wall clock")
    async_wall = row("added to a simulation at 30 Hz, SAP: on a worker thread", "wall clock")
    async_cpu = row("added to a simulation at 30 Hz, SAP: on a worker thread", "CPU time")
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
        f"| camera frame at 30 Hz, CENIC (default: taken on its steps; GL rendered on a "
        f"worker thread, VTK in the simulation's), no frame read, GL / VTK, added wall time | "
        f"{on_steps[0]} / {on_steps[1]} ms | `tools/bench_camera.py` |",
        f"| camera frame at 30 Hz, CENIC (default), no frame read, GL, added CPU time | "
        f"{on_steps_cpu[0]} ms | `tools/bench_camera.py` |",
        f"| camera frame at 30 Hz, CENIC (default), every frame read as it comes out (waiting "
        f"for the rest of its render), GL / VTK, added wall time | {read[0]} / {read[1]} ms | "
        f"`tools/bench_camera.py` |",
        f"| camera frame at 30 Hz, CENIC, synchronous (`output_delay: 0`: rendered in the "
        f"simulation's thread), GL / VTK, added wall time | {rendered_in_place[0]} / "
        f"{rendered_in_place[1]} ms "
        f"| `tools/bench_camera.py` |",
        f"| camera frame at 30 Hz, SAP, asynchronous GL, added wall time | {async_wall[0]} ms | "
        f"`tools/bench_camera.py` |",
        f"| camera frame at 30 Hz, SAP, asynchronous GL, added CPU time | {async_cpu[0]} ms | "
        f"`tools/bench_camera.py` |",
        f"| camera frame at 30 Hz, SAP, synchronous (`output_delay: 0`), GL / VTK, added wall "
        f"time | {sync[0]} / {sync[1]} ms | `tools/bench_camera.py` |",
    ]
    return f"Measured {measured_line(flat(outs))}:\n\n" + "\n".join(lines)


EVENT_CASES = (
    ("shipped", "as shipped (drive, command source and motion every 10 ms: on the plant's "
                "steps)"),
    ("control_60_hz", "the same systems at the book's 60 Hz (`drive.control_period: 1/60`: 40 "
                      "of their 60 event times a second fall between steps)"),
    ("control_50_hz", "the same systems at 50 Hz (`drive.control_period: 0.02`: every event on "
                      "a step, half as many)"),
    ("ir_20_hz", "+ 2 IR sensors at 20 Hz (on steps)"),
    ("ir_19_9_hz", "+ 2 IR sensors at 19.9 Hz (scan times between steps)"),
    ("ir_200_hz", "+ 2 IR sensors at 200 Hz (half of the scan times between steps)"),
)
"""`_event_cases`' rows as the docs name them."""


def render_event_times(outs) -> str:
    runs = outs[0]
    m = json.loads(runs[0].stdout)
    lines = ["| change | real-time factor, median (min-max) |", "|---|---|"]
    for key, label in EVENT_CASES:
        r = m[key]
        lines.append(f"| {label} | {r['rtf']:.1f}x ({r['rtf_min']:.1f}-{r['rtf_max']:.1f}) |")
    return (f"Measured {measured_line(runs)} (`{runs[0].command}`; physics only unless a row adds "
            f"IR, camera off, 5 runs of 10 simulated s each in turn, wall clock):\n\n"
            + "\n".join(lines))


def render_step_counts(outs) -> str:
    """Steps per simulated second: deterministic, so `--check` holds the text to them."""
    o = outs[0][0]
    m = json.loads(o.stdout)
    lines = ["| change | simulator steps per simulated s, CENIC (default) | the same, SAP |",
             "|---|---|---|"]
    lines += [f"| {label} | {m[key]['cenic']:.1f} | {m[key]['sap']:.1f} |"
              for key, label in EVENT_CASES]
    return (f"`{o.command}` (the default scene driving its figure of eight for 3 s, physics only "
            f"unless a row adds IR):\n\n" + "\n".join(lines))


def render_hot_reads(outs) -> str:
    """Inline, in a sentence: the two reads' costs and the day they were measured."""
    m = json_output(outs)
    return (f"an abstract input costs {m['request_input']:.2f} us and a discrete state number "
            f"{m['state_number']:.2f} us (measured {outs[0][0].started:%Y-%m-%d} at load "
            f"average {load_line(flat(outs))}, `{outs[0][0].command}`)")


def render_bench_ir(outs) -> str:
    o = outs[0][0]
    text = "\n".join(line for line in o.stdout.splitlines() if not line.startswith(
        ("load average", "(the median")))
    return f"Measured {measured_line([o])} (`{o.command}`):\n\n{as_markdown(text)}"


def render_bench_study(outs) -> str:
    o = outs[0][0]
    return f"Measured {measured_line([o])} (`{o.command}`):\n\n{as_markdown(o.stdout.strip())}"


def render_command_table(outs) -> str:
    """The command and the table it printed (a deterministic block: no load, no date)."""
    o = outs[0][0]
    return f"`{o.command}`:\n\n{table(o.stdout)}"


def render_counted_table(outs) -> str:
    """The day, the command and the table it printed: counts (not times, so no load), which
    still move with Drake's version and the code."""
    o = outs[0][0]
    return f"Counted {o.started:%Y-%m-%d} (`{o.command}`):\n\n{table(o.stdout)}"


def render_gym_evaluation(outs) -> str:
    """The held-out table and the trained policy's margin over its hand-written start."""
    o = outs[0][0]
    margin = find(r"^(Success, trained minus hand-written: .*)$", o.stdout)
    return f"`{o.command}`:\n\n{table(o.stdout)}\n\n{margin}"


def render_gym_training(outs) -> str:
    o = outs[0][0]
    trained = find(r"^(Trained on .*)$", o.stdout)
    curve = table(o.stdout.split("Held-out seeds")[0])
    return (f"Measured {measured_line([o])} (`{o.command}`): {trained}\n\n{curve}\n\n"
            f"![GoToGoal learning curve](images/gym_learning_curve.png)")


def render_table_with_load(outs) -> str:
    o = outs[0][0]
    return f"Measured {measured_line([o])} (`{o.command}`):\n\n{table(o.stdout)}"


def render_tables_with_load(outs) -> str:
    """Several tables of one command, each kept apart."""
    o = outs[0][0]
    tables = [table(part) for part in o.stdout.split("\n\n")]
    return f"Measured {measured_line([o])} (`{o.command}`):\n\n" + "\n\n".join(t for t in tables
                                                                            if t)


def render_camera_cost(outs) -> str:
    o = outs[0][0]
    ratios = {r.split("|")[1].strip(): r.split("|")[4].strip()
              for r in table(o.stdout).splitlines()[2:]}
    return (f"Measured {measured_line([o])} (`{o.command}`):\n\n{table(o.stdout)}\n\n"
            f"Meshes over boxes: {ratios['robot-camera']} for the robot's own camera, "
            f"{ratios['chase']} for the chase view.")


def render_creep(outs) -> str:
    o = outs[0][0]
    return f"`{o.command}`:\n\n{o.stdout.strip()}"


def render_hostile_inputs(outs) -> str:
    o = outs[0][0]
    defects = [line for line in o.stdout.splitlines() if line.startswith("defect:")]
    return (f"Measured {measured_line([o])} (`{o.command}`; CPU time per input, pydrake's import "
            f"aside):\n\n{table(o.stdout)}"
            + (f"\n\n{len(defects)} defects: see the command's output." if defects else ""))


def render_drive_legs(outs) -> str:
    o = outs[0][0]
    loops = int(find(r"^(\d+) loops: final drift", o.stdout))
    drift = number(r"final drift ([\d.]+) mm", o.stdout)
    return (f"seed 1, {loops} loop through the server: {drift:.1f} mm; {o.seconds:.0f} s of wall "
            f"time, the server's start included, measured {o.started:%Y-%m-%d} at load average "
            f"{load_line([o])}")


def render_server_flood(outs) -> str:
    o = outs[0][0]
    line = next(x for x in o.stdout.splitlines() if x.startswith("real-time factor"))
    return wrap_markdown(f"Measured {measured_line([o])} (`{o.command}`): {line}.")


def render_server_memory(outs) -> str:
    o = outs[0][0]
    paragraph = next(line for line in o.stdout.splitlines() if line.startswith("`--serve`"))
    return wrap_markdown(f"Measured {measured_line([o])}: {paragraph}")


