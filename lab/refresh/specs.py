"""Every generated block: its file, its commands, its renderer, its kind and cost."""

from __future__ import annotations

import shlex
from types import SimpleNamespace

from lab.refresh import renders as r
from lab.refresh.gallery import gallery_specs
from lab.refresh.measures import measure_command
from lab.refresh.runner import (
    DETERMINISTIC,
    OLD_CHECKOUT,
    ORDER,
    PICTURE,
    SAP_OVERRIDE,
    TIMING,
    Command,
    Spec,
)
from lab.refresh.text import picture


def blocks() -> list[Spec]:
    """Every generated block of the docs, in the order a full refresh runs them."""
    c = _shared_commands()
    specs = [*_model_and_command_specs(c), *_front_end_specs(c), *_performance_specs(c),
             *gallery_specs()]
    return sorted(specs, key=lambda s: ORDER[s.kind])


def _shared_commands() -> SimpleNamespace:
    """The commands (and pictures) several blocks read."""
    shipped = r.shipped_scaling()
    top_speed = Command(f"python tools/tune_motor_torque_scaling.py --scaling {shipped:g} "
                        f"--max-iterations 1", ok=(0, 1))
    meshes = Command("python tools/make_meshes.py --check", ok=(0, 1))
    ir_start = measure_command("ir-at-start")
    landing = Command("python tools/landing_errors.py --plot docs/images/landing_errors.png")
    bench_ir = Command("python tools/bench_ir.py")
    bench_raycast = Command("python tools/bench_raycast.py")
    bench_camera = Command("python tools/bench_camera.py")
    default_column = Command('python tools/bench.py --plants "CENIC 10 ms" --seconds 5 '
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
    """The model, tuning, commands and the pictures of docs/usage.md (once the README's)."""
    return [
        Spec("looks-triangles", "docs/looks.md", (c.meshes,), r.render_looks_triangles,
             DETERMINISTIC, 3),
        Spec("sensors-ir-at-start", "docs/sensors.md", (c.ir_start,), r.render_ir_start_sensors,
             DETERMINISTIC, 8),
        Spec("sensors-samples-error", "docs/sensors.md", (measure_command("samples-error"),),
             r.render_samples_error, DETERMINISTIC, 3),
        Spec("tune-motor-torque-scaling", "docs/tuning.md",
             (Command("python tools/tune_motor_torque_scaling.py --scaling 20"), c.top_speed),
             r.render_tune, DETERMINISTIC, 10),
        Spec("tune-motor-torque-scaling-sweep", "docs/tuning.md",
             (Command("python tools/tune_motor_torque_scaling.py --sweep"),), r.render_tune_sweep,
             DETERMINISTIC, 40),
        Spec("fit-drive-log", "docs/tuning.md",
             (Command("python tools/fit_drive_log.py --simulate 12 20"),), r.render_fit,
             DETERMINISTIC, 5),
        Spec("step-limit", "docs/physics.md", (Command("python tools/step_limit.py"),),
             r.render_command_table, DETERMINISTIC, 40),
        Spec("creep-isolate", "docs/physics.md", (Command("python tools/creep.py --isolate"),),
             r.render_creep, DETERMINISTIC, 60),
        Spec("creep", "docs/physics.md", (Command("python tools/creep.py"),), r.render_creep,
             DETERMINISTIC, 90),
        Spec("fit-drive-log-stall", "docs/tuning.md",
             (Command("python tools/fit_drive_log.py --simulate 12 20 --stall"),),
             r.render_fit_stall, DETERMINISTIC, 40),
        Spec("calibrate-odometry", "docs/tuning.md",
             (Command("python tools/calibrate_odometry.py --simulate --drive-test"),),
             r.render_calibrate_odometry, DETERMINISTIC, 300),
        Spec("wheel-turn", "docs/looks.md", (measure_command("wheel-turn"),), r.render_wheel_turn,
             DETERMINISTIC, 5),
        Spec("saved-mid-drive", "docs/commands.md", (measure_command("saved-mid-drive"),),
             r.render_saved_mid_drive, DETERMINISTIC, 10),
        Spec("resume-landing", "docs/commands.md",
             (Command("python tools/resume_landing.py"),), r.render_resume_landing,
             DETERMINISTIC, 300),
        Spec("landing-errors", "docs/landings.md", (c.landing,), r.render_landing_errors,
             DETERMINISTIC, 90),
        Spec("drive-test-drift", "docs/landings.md", tuple(
            Command(f"python tools/drive_test.py --loops 3 --seeds 20 --workers 1 --profile {p} "
                    f"--out out/drive_test_{p}")
            for p in ("closed_loop", "seed")), r.render_drive_drift, DETERMINISTIC, 820),
        *(Spec(name, "docs/usage.md", (Command(cmd),), picture(alt, f"images/{png}", cmd),
               PICTURE, seconds) for name, alt, png, cmd, seconds in c.pictures),
    ]


def _front_end_specs(c: SimpleNamespace) -> list[Spec]:
    """The services, sensors, recording, gym and studies."""
    return [
        Spec("drive-legs-server", "docs/costs.md",
             (Command("python examples/drive_legs.py --loops 1 --seed 1"),), r.render_drive_legs,
             TIMING, 45),
        Spec("server-flood", "docs/costs.md",
             (Command("python tools/bench_server_flood.py"),),
             r.render_server_flood, TIMING, 30),
        Spec("server-memory", "docs/costs.md",
             (Command("python tools/bench_memory.py --sim-minutes 60 --warmup-minutes 1 "
                      "--sample-every 60"),), r.render_server_memory, TIMING, 2200),
        Spec("camera-cost", "docs/costs.md", (Command("python tools/camera_cost.py"),),
             r.render_camera_cost, TIMING, 70),
        Spec("bench-camera", "docs/costs.md", (c.bench_camera,), r.render_table_with_load,
             TIMING, 90),
        Spec("bench-ir", "docs/costs.md", (c.bench_ir,), r.render_bench_ir, TIMING, 50),
        Spec("setup-cost", "docs/install.md", (Command("python tools/measure_setup.py"),),
             r.render_bench_ir, TIMING, 500),
        Spec("bench-lidar", "docs/costs.md", (Command("python tools/bench_lidar.py"),),
             r.render_bench_ir, TIMING, 60),
        Spec("bumper-instructions", "docs/costs.md",
             (Command('python tools/count_instructions.py --seconds 0.2 --override "robots: '
                      '{corobot: {bumpers: {front_bumper: {}}}}"'),),
             r.render_counted_table, TIMING, 300),
        Spec("bench-recording", "docs/costs.md",
             (Command("python tools/bench_recording.py"),), r.render_table_with_load, TIMING, 300),
        Spec("bench-ros2", "docs/costs.md", (Command("python tools/bench_ros2.py"),),
             r.render_tables_with_load, TIMING, 400),
        Spec("gym-evaluation", "docs/gym.md",
             (Command("python tools/train_policy.py --evaluate"),), r.render_gym_evaluation,
             DETERMINISTIC, 500),
        Spec("gym-training", "docs/costs.md", (Command("python tools/train_policy.py --ship"),),
             r.render_gym_training, TIMING, 1700),
        Spec("bench-gym", "docs/costs.md", (Command("python tools/bench_gym.py"),),
             r.render_bench_study, TIMING, 150),
        Spec("bench-study", "docs/costs.md",
             (Command("python tools/bench_study.py --seeds 24 --duration 8"),),
             r.render_bench_study, TIMING, 150),
    ]


def _performance_specs(c: SimpleNamespace) -> list[Spec]:
    """docs/performance.md's costs, and the hostile inputs' (docs/usage.md)."""
    return [
        Spec("unit-costs", "docs/performance.md", (c.bench_ir, c.bench_raycast, c.bench_camera),
             r.render_unit_costs, TIMING, 150),
        Spec("event-times", "docs/performance.md", (measure_command("event-times"),),
             r.render_event_times, TIMING, 70),
        Spec("hot-reads", "docs/performance.md", (measure_command("hot-reads"),),
             r.render_hot_reads, TIMING, 20),
        Spec("step-counts", "docs/performance.md", (measure_command("step-counts"),),
             r.render_step_counts, DETERMINISTIC, 15),
        Spec("tire-grip", "docs/tuning.md",
             (Command("python tools/tune_tire_grip.py --plot docs/images/tire_grip.png",
                      ok=(0, 1)),),
             r.render_tire_grip, DETERMINISTIC, 2500),
        Spec("default-column-runs", "docs/performance.md", (c.default_column,),
             r.render_default_runs, TIMING, 110),
        Spec("readme-hostile-inputs", "docs/costs.md",
             (Command("python tools/hostile_inputs.py", ok=(0, 1)),), r.render_hostile_inputs,
             TIMING, 90),
        Spec("bench-robots", "docs/performance.md",
             (Command("python tools/bench.py --robots 1,2,4,8,16 --no-table --no-micro "
                      "--seconds 5 --repeats 1"),), r.render_bench_robots, TIMING, 300),
        Spec("bench-layers", "docs/performance.md",
             (Command("python tools/bench.py --layers --no-table --no-micro --seconds 8 "
                      "--repeats 41"),), r.render_bench_robots, TIMING, 300),
        Spec("profile-step", "docs/performance.md",
             (Command("python tools/profile_step.py --seconds 20 --repeats 9"),),
             r.render_profile_step, TIMING, 300),
        Spec("layers-instructions", "docs/performance.md",
             (Command("python tools/count_instructions.py --seconds 0.5"),),
             r.render_bench_robots, TIMING, 900),
        Spec("count-instructions", "docs/performance.md",
             (Command('python tools/count_instructions.py --cache-sim '
                      f'--override "{SAP_OVERRIDE}" '
                      '--override "{plant_config: {time_step: 0.01, '
                      'discrete_contact_approximation: similar}, simulator_config: '
                      '{integration_scheme: runge_kutta3}}" '
                      '--override "robots: {corobot: {contact: {resolution_hint: 0.007}}}" '
                      '--override "world: {bodies: {giant_box: {fixed: true}}}" '
                      '--override "robots: {corobot: {drive: {control_period: 0.02}}}"'),),
             r.render_counted_table, TIMING, 450),
        Spec("bench-compare", "docs/performance.md",
             (Command(f"python tools/bench_compare.py --old {OLD_CHECKOUT} --rounds 15"),),
             r.render_bench_robots, TIMING, 600),
        Spec("bench-compare-drive-test", "docs/performance.md",
             (Command(f"python tools/bench_compare.py --old {OLD_CHECKOUT} --rounds 2 "
                      "--cases 'drive test'"),),
             r.render_bench_robots, TIMING, 700),
        Spec("bench-compare-sap", "docs/performance.md",
             (Command("python tools/bench_compare.py --old /tmp/corobot-old --rounds 3 "
                      f"--new-override {shlex.quote(SAP_OVERRIDE)}"),),
             r.render_bench_robots, TIMING, 600),
        Spec("cenic-solver", "docs/performance.md",
             (Command("python tools/cenic_solver.py --repeats 9"),), r.render_bench_study,
             TIMING, 200),
        Spec("box-push", "docs/performance.md", (measure_command("box-push"),),
             r.render_box_push, DETERMINISTIC, 60),
        Spec("spin-steps", "docs/physics.md", (measure_command("spin-steps"),),
             r.render_spin_steps, DETERMINISTIC, 60),
        Spec("continuous-sensors", "docs/performance.md", (measure_command("continuous-sensors"),),
             r.render_continuous_sensors, DETERMINISTIC, 60),
        Spec("bench-full", "docs/performance.md",
             (Command("python tools/bench.py --seconds 5 --repeats 3"),), r.render_bench_full,
             TIMING, 200),
    ]


