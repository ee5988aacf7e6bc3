"""The measurements `tools/refresh_docs.py --measure NAME` makes itself through the Python API
(JSON)."""

from __future__ import annotations

import dataclasses as dc
import json
import math
import statistics
import sys
import time

from corobot_drake.resources import DEFAULT_SCENARIO
from lab.refresh.runner import NO_CAMERA, Command, Output


def _sim(*overrides: str):
    from corobot_drake.simulation import Simulation, quiet_drake_warnings

    quiet_drake_warnings()
    return Simulation.from_file(DEFAULT_SCENARIO, overrides=[NO_CAMERA, *overrides])


def measure_ir_at_start() -> dict:
    """The default scene's IR readings at t = 0."""
    robot = _sim().robot()
    return {"rear": dc.asdict(robot.ir("rear")), "distances": robot.ir_distances()}


SAMPLES_ERROR_OVERRIDE = "robots: {corobot: {ir_sensors: {front: {samples: 1}}}}"


def measure_samples_error() -> dict:
    """The one line `python -m corobot_drake --override SAMPLES_ERROR_OVERRIDE` prints (exit
    status 2, before anything is built)."""
    import contextlib
    import io

    from corobot_drake.cli import main

    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        status = main(["--headless", "--override", SAMPLES_ERROR_OVERRIDE])
    return {"status": status, "stderr": err.getvalue()}


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
    spec = robot.spec
    turned = {k: v * 2 * math.pi / spec.encoder_ticks_per_revolution for k, v in ticks.items()}
    return {"distance": distance, "ratio": {k: t / (distance / spec.wheel_radius)
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


def measure_hot_reads(reads: int = 100_000, repeats: int = 5) -> dict:
    """us per read, in a loop (hot caches), on the station's own Context after 0.5 s of the
    figure of eight, physics only: the drive's `request` input (abstract, what the quiet
    updates read) and a number of its discrete state. Least of `repeats` rounds."""
    import timeit

    from lab.bench import physics_only_overrides

    sim = _driving([*physics_only_overrides()])
    sim.advance(0.5)
    drive = sim.robot()._parts.drive_controller
    context = drive.GetMyContextFromRoot(sim.context)
    request, mode = drive.GetInputPort("request"), drive._mode

    def least(read) -> float:
        return min(timeit.repeat(read, number=reads, repeat=repeats)) / reads * 1e6

    return {"request_input": least(lambda: request.Eval(context).seq),
            "state_number": least(lambda: context.get_discrete_state(mode)[0])}


def measure_step_counts(seconds: float = 3.0) -> dict:
    """Simulator steps per simulated second of the default scene driving (`_event_cases`),
    under the default (CENIC) and SAP at 10 ms: the same on every machine."""
    from corobot_drake.config.scenario import SAP_PLANT

    counts = {}
    for name, overrides in _event_cases().items():
        counts[name] = {}
        for plant, extra in (("cenic", []), ("sap", [SAP_PLANT % 0.01])):
            sim = _driving([*overrides, *extra])
            sim.advance(seconds)
            counts[name][plant] = sim.simulator.get_num_steps_taken() / seconds
    return counts


def measure_continuous_sensors(seconds: float = 9.0) -> dict:
    """What the sensors see under CENIC's continuous plant against SAP's discrete one, over
    the figure of eight (both IR sensors at 20 Hz): each scan's raw reading and the chassis
    position at that scan, the largest differences (m) and how many readings differ by more
    than 1 mm; then, under CENIC, the camera on against off: simulator steps per simulated
    second and the chassis' distance apart (m) at the end."""
    from corobot_drake.config.scenario import CENIC_PLANT, SAP_PLANT, load_scenario
    from corobot_drake.simulation import Simulation, quiet_drake_warnings
    from lab.bench import DRIVING, sensor_overrides

    quiet_drake_warnings()

    def scans(*overrides: str, camera: bool = False):
        sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[
            DRIVING, *sensor_overrides(ir=True, camera=camera), *overrides]))
        robot, out = sim.robot(), []
        for k in range(1, round(seconds * 20) + 1):
            # A step after each scan (k / 20 s): both integrators have taken it whichever
            # way its time and the step's round.
            sim.advance_to(k * 0.05 + 0.01)
            out.append((robot.ir_distances(), robot.position()))
        return out, sim.simulator.get_num_steps_taken() / seconds

    cenic, steps = scans(CENIC_PLANT % 0.01)
    sap, _ = scans(SAP_PLANT % 0.01)
    reading = [abs(a[0][n] - b[0][n]) for a, b in zip(cenic, sap, strict=True) for n in a[0]]
    moved = [math.dist(a[1], b[1]) for a, b in zip(cenic, sap, strict=True)]
    with_camera, camera_steps = scans(CENIC_PLANT % 0.01, camera=True)
    return {"readings": len(reading), "max_reading_m": max(reading),
            "over_1_mm": sum(d > 1e-3 for d in reading), "max_position_m": max(moved),
            "steps_per_second": steps, "camera_steps_per_second": camera_steps,
            "camera_position_m": math.dist(with_camera[-1][1], cenic[-1][1])}


BOX_PUSH_STEPS = (0.01, 0.005, 0.002, 0.001)
"""s: the steps `measure_box_push` runs each integrator at."""


def measure_box_push(seconds: float = 3.0) -> dict:
    """How far the robot at power 0.5 pushes a free 2 kg, 0.2 m box on the ground in
    `seconds` (m; the box starts 0.5 m ahead, the scene of tests/simulation/test_user_bodies.py),
    per integrator and step (`BOX_PUSH_STEPS`): {"cenic": {step: m}, "sap": {step: m}}."""
    from corobot_drake.config.scenario import CENIC_PLANT, SAP_PLANT, load_scenario
    from corobot_drake.simulation import Simulation, quiet_drake_warnings

    quiet_drake_warnings()
    scene = ["robots: {corobot: {commands: [!SetPower {left: 0.5, right: 0.5}], "
             "cameras: {front: {rgb: false}}}}",
             "world: {bodies: {crate: {shape: !Box {size: [0.2, 0.2, 0.2]}, mass: 2.0, "
             "pose: {translation: [0.5, 0.0, 0.1]}}}}"]
    out = {}
    for name, plant in (("cenic", CENIC_PLANT), ("sap", SAP_PLANT)):
        out[name] = {}
        for step in BOX_PUSH_STEPS:
            sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[*scene, plant % step]))
            sim.advance(seconds)
            body = sim.station.bodies["crate"]
            X = sim.station.plant.EvalBodyPoseInWorld(
                sim.station.plant.GetMyContextFromRoot(sim.context), body)
            out[name][f"{step:g}"] = float(X.translation()[0]) - 0.5
    return out


SPIN_STEPS = (0.001, 0.002, 0.005, 0.01)
"""s: the steps `measure_spin_steps` runs each integrator at."""


def measure_spin_steps(seconds: float = 3.0) -> dict:
    """The default robot at full power on open ground (IR and camera off), per integrator and
    step (`SPIN_STEPS`): the steady yaw rate spinning in place against the isotropic-Coulomb
    prediction (`tuning.tire_grip.predicted_spin_rate`) and the steady straight speed (m/s),
    the study metrics over the last second of `seconds`: {"cenic": {step: {"spin": ratio,
    "speed": m/s}}, "sap": ...}."""
    from corobot_drake.config.scenario import CENIC_PLANT, SAP_PLANT, load_scenario
    from corobot_drake.robots import robot_spec
    from corobot_drake.simulation import Simulation, quiet_drake_warnings
    from corobot_drake.study.metrics import METRICS, RobotRun
    from corobot_drake.tuning.tire_grip import predicted_spin_rate
    from lab.bench import physics_only_overrides

    quiet_drake_warnings()
    prediction = predicted_spin_rate(robot_spec().top_speed())

    def steady(plant: str, left: float, metric: str) -> float:
        sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[
            *physics_only_overrides(), plant,
            f"robots: {{corobot: {{commands: [!SetPower {{left: {left}, right: 1.0}}]}}}}"]))
        robot = sim.robot()
        start = robot.pose()
        sim.advance(seconds)
        return float(METRICS[metric](RobotRun(sim, robot, start, robot.heading())))

    return {name: {f"{step:g}": {"spin": abs(steady(plant % step, -1.0, "steady_yaw_rate"))
                                 / prediction,
                                 "speed": steady(plant % step, 1.0, "steady_speed")}
                   for step in SPIN_STEPS}
            for name, plant in (("cenic", CENIC_PLANT), ("sap", SAP_PLANT))}


MEASUREMENTS = {
    "box-push": measure_box_push,
    "spin-steps": measure_spin_steps,
    "continuous-sensors": measure_continuous_sensors,
    "ir-at-start": measure_ir_at_start,
    "samples-error": measure_samples_error,
    "saved-mid-drive": measure_saved_mid_drive,
    "wheel-turn": measure_wheel_turn,
    "event-times": measure_event_times,
    "step-counts": measure_step_counts,
    "hot-reads": measure_hot_reads,
}


def measure_command(name: str, repeats: int = 1) -> Command:
    return Command(f"python tools/refresh_docs.py --measure {name}", repeats)


def json_output(outs: list[list[Output]], index: int = 0) -> dict:
    return json.loads(outs[index][0].stdout)


