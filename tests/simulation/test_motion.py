"""Commands that complete (DriveDistance, RotateDegrees, SetPose), odometry, drive state and
saved scenes, measured from the simulation of the default scene (camera off: not needed)."""

import dataclasses as dc
import functools
import itertools
import json
import math
import subprocess
import sys

import numpy as np
import pytest
from pydrake.common.yaml import yaml_dump_typed

from conftest import REPO, SAP, make_sim
from corobot_drake.cli import main
from corobot_drake.config import scenario as sc
from corobot_drake.config.scenario import load_scenario
from corobot_drake.simulation import Simulation


def _robot_yaml(profile: str = "closed_loop", extra: str = "") -> str:
    fields = [f"motion: {{profile: {profile}}}", "cameras: {front: {rgb: false}}"]
    if extra:
        fields.append(extra)
    return "robots: {corobot: {" + ", ".join(fields) + "}}"


def fast_sim(profile: str = "closed_loop", extra: str = "") -> Simulation:
    return make_sim(_robot_yaml(profile, extra))


def travelled(robot, start) -> float:
    x, y, _ = robot.position()
    return math.hypot(x - start[0], y - start[1])


def turned_deg(robot, start_heading: float, target_deg: float) -> float:
    """Heading change minus the target, deg, wrapped (the landing error)."""
    return math.degrees(math.remainder(robot.heading() - start_heading
                                       - math.radians(target_deg), 2 * math.pi))


# Landing errors measured at 1 m / power 0.2 (tools/landing_errors.py; docs/commands.md):
# closed_loop -0.45 mm (its worst over every distance and power: 0.49 mm), seed +0.07 mm.
# closed_loop's bound is the README's claim, 1 mm (the issue asks for 5). The seed's error
# grows with power (44 mm for 0.25 m at power 1), so its bound here is its measured error at
# this distance and power plus margin.
@pytest.mark.parametrize("profile, tolerance", [("closed_loop", 0.001), ("seed", 0.002)])
def test_drive_one_metre_lands(profile, tolerance):
    sim = fast_sim(profile)
    robot = sim.robot()
    start = robot.position()
    result = robot.drive_distance(1.0, 0.2)
    assert result.succeeded and result.reason == ""
    sim.advance(0.5)  # any coasting after "succeeded" counts
    assert travelled(robot, start) == pytest.approx(1.0, abs=tolerance)
    assert abs(robot.position()[1]) < 0.005  # straight
    assert robot.velocity().forward == pytest.approx(0.0, abs=1e-3)


def test_rotate_both_ways_lands_within_a_tenth_of_a_degree():
    """The issue asks for 0.5 deg; the README claims 0.1 (worst measured: 0.05 deg)."""
    sim = fast_sim()
    robot = sim.robot()
    for degrees in (90.0, -90.0):
        heading = robot.heading()
        result = robot.rotate_degrees(degrees, 0.2)
        assert result.succeeded
        sim.advance(0.3)
        assert abs(turned_deg(robot, heading, degrees)) < 0.1
    # Turning in place: the centre stays within a few mm.
    assert math.hypot(*robot.position()[:2]) < 0.01


def test_negative_distance_drives_backwards():
    sim = fast_sim()
    robot = sim.robot()
    assert robot.drive_distance(-0.3, 0.5).succeeded
    sim.advance(0.3)
    x, y, _ = robot.position()
    assert x == pytest.approx(-0.3, abs=0.005) and abs(y) < 0.005
    assert robot.encoders()["front_left"] < 0  # wheels turned backwards


def test_heading_unwraps_across_180():
    sim = fast_sim(extra="pose: {rotation: !Rpy {deg: [0, 0, 170]}}")
    robot = sim.robot()
    sim.advance(0.1)
    result = robot.rotate_degrees(20.0, 0.3)
    assert result.succeeded
    # 20 deg at ~0.98 rad/s takes well under 2 s; the long way round (340 deg) would not.
    assert result.end_time - result.start_time < 2.0
    assert math.degrees(robot.heading()) == pytest.approx(-170.0, abs=0.5)


def test_supersede_disable_and_stall_end_with_their_reasons():
    sim = fast_sim()
    robot = sim.robot()
    first = robot.drive_distance_async(1.0, 0.2)
    sim.advance(0.5)
    assert first.status() == "running"
    robot.set_power(0.0, 0.0)  # any newer command supersedes
    assert (first.status(), first.result().reason) == ("failed", "superseded")
    second = robot.rotate_degrees_async(90.0, 0.2)
    third = robot.drive_distance_async(0.2, 0.2)  # a newer completing command too
    assert second.result().reason == "superseded"
    sim.advance(0.5)
    robot.enable(False)  # disabling the drive ends the running one as disabled
    assert (third.status(), third.result().reason) == ("failed", "disabled")
    refused = robot.drive_distance(0.5, 0.2)  # issued to a disabled drive
    assert (refused.status, refused.reason) == ("failed", "disabled")
    robot.enable(True)
    # Drive backwards into the giant box: no progress for stall_time (1 s), stalled.
    stalled = robot.drive_distance(-3.0, 0.5)
    assert (stalled.status, stalled.reason) == ("failed", "stalled")
    assert robot.position()[0] < -0.57  # it reached the box (tyres at 0.152 m behind centre)
    assert robot.drive_state().wheels["front_left"].commanded_power == 0.0  # and stopped
    summary = robot.summary()["commands"]
    assert [(c["command"], c["status"], c["reason"]) for c in summary] == [
        ("DriveDistance", "failed", "superseded"), ("SetPower", "succeeded", ""),
        ("RotateDegrees", "failed", "superseded"), ("DriveDistance", "failed", "disabled"),
        ("Enable", "succeeded", ""), ("DriveDistance", "failed", "disabled"),
        ("Enable", "succeeded", ""), ("DriveDistance", "failed", "stalled")]


def test_a_handle_and_the_readings_print_rounded_with_units():
    import re

    sim = fast_sim()
    robot = sim.robot()
    handle = robot.drive_distance_async(0.2, 0.5)
    sim.advance(0.25)
    assert repr(handle) == "<CommandHandle corobot seq 1: DriveDistance running, since t = 0.000 s>"
    end = handle.wait().end_time
    assert repr(handle) == ("<CommandHandle corobot seq 1: DriveDistance succeeded, "
                            f"t = 0.000 to {end:.3f} s>")
    start = sim.time
    superseded = robot.drive_distance_async(1.0, 0.2)
    sim.advance(0.1)
    robot.set_power(0.0, 0.0)
    assert repr(superseded) == ("<CommandHandle corobot seq 2: DriveDistance failed (superseded), "
                                f"t = {start:.3f} to {sim.time:.3f} s>")
    n = r"-?\d+\.\d"
    assert re.fullmatch(rf"IrReading\(raw=0\.\d{{4}} m, range=0\.7620 m, normalized={n}{{3}}, "
                        rf"time={n}{{3}} s\)", repr(robot.ir("front")))
    assert re.fullmatch(rf"BodyPose\(x={n}{{4}} m, y={n}{{4}} m, z={n}{{4}} m, "
                        rf"roll={n}{{4}} rad, pitch={n}{{4}} rad, yaw={n}{{4}} rad\)",
                        repr(robot.pose()))
    assert "-0.0000" not in repr(robot.velocity())  # at rest: no negative zeros


def test_encoders_count_600_ticks_per_revolution():
    sim = fast_sim(extra="wheel_angles: [6.2831853072, -0.0001, 0, 0]")
    robot = sim.robot()
    assert robot.encoders() == {"front_left": 600, "front_right": -1}  # floor quantization
    robot.drive_distance(0.5, 0.5)
    plant = sim.station.plant
    context = plant.GetMyContextFromRoot(sim.context)
    angles = [j.get_angle(context) for j in robot._parts.wheel_joints[:2]]
    ticks = robot.encoders()
    for name, angle in zip(("front_left", "front_right"), angles, strict=True):
        assert ticks[name] == math.floor(angle * 600 / (2 * math.pi))
    # 0.5 m of rolling is 0.5 / (2 pi R) = 1.319 revolutions; tyre slip stays under 2%.
    assert (ticks["front_right"] + 1) / 600 == pytest.approx(0.5 / (2 * math.pi * 0.060325),
                                                              rel=0.02)


def test_drive_state_and_two_wheel_view():
    sim = fast_sim()
    robot = sim.robot()
    robot.set_power(0.5, -0.25)
    sim.advance(1.0)
    state = robot.drive_state()
    assert state.time_stamp == pytest.approx(sim.time)
    assert state.is_enabled and state.distance_between_wheels == pytest.approx(0.22352)
    assert state.power_scaling_factor == pytest.approx(10.16)
    assert state.wheels["rear_left"].commanded_power == pytest.approx(0.5)
    assert state.wheels["rear_right"].commanded_power == pytest.approx(-0.25)
    assert state.wheels["rear_left"].encoder_ticks is None
    assert state.wheels["front_left"].axle_speed == pytest.approx(5.08, rel=0.05)
    assert state.heading == pytest.approx(robot.heading())
    assert state.position == pytest.approx(robot.position())
    two = state.two_wheel()
    assert two.left == state.wheels["front_left"] and two.right == state.wheels["front_right"]
    assert two.left.encoder_ticks == robot.encoders()["front_left"]


def test_set_pose_lands_settles_and_supersedes():
    sim = fast_sim()
    robot = sim.robot()
    running = robot.drive_distance_async(1.0, 0.5)
    sim.advance(1.0)
    handle = robot.set_pose(1.0, -2.0, 135.0)
    assert (running.status(), running.result().reason) == ("failed", "superseded")
    plant = sim.station.plant
    tilts, heights = [], []
    for _ in range(100):  # 1 s at 100 Hz
        sim.advance(0.01)
        X = plant.EvalBodyPoseInWorld(plant.GetMyContextFromRoot(sim.context),
                                      robot._parts.chassis)
        tilts.append(math.degrees(math.acos(np.clip(X.rotation().matrix()[2, 2], -1, 1))))
        heights.append(X.translation()[2])
    assert handle.status() == "succeeded"
    assert max(tilts) < 2.0
    assert max(heights) < 1e-3  # no bounce: it lands where it rests (tyres sink ~0.5 mm)
    x, y, _ = robot.position()
    assert math.hypot(x - 1.0, y + 2.0) < 1e-3
    assert math.degrees(robot.heading()) == pytest.approx(135.0, abs=0.1)
    assert abs(robot.velocity().forward) < 1e-3


def test_scripted_commands_and_summary(tmp_path):
    path = tmp_path / "summary.json"
    script = ("commands: [!DriveDistance {distance: 0.3, power: 0.5}, "
              "!RotateDegrees {degrees: 90, power: 0.5}, !SetPose {x: 0.5, y: 0.5, yaw_deg: 0}, "
              "!DriveDistance {distance: 5, power: 1}]")
    assert main(["--headless", "--duration", "6", "--override", _robot_yaml(extra=script),
                 "--summary", str(path)]) == 0
    robot = json.loads(path.read_text())["robots"]["corobot"]
    commands = robot["commands"]
    assert [(c["command"], c["status"]) for c in commands] == [
        ("DriveDistance", "succeeded"), ("RotateDegrees", "succeeded"),
        ("SetPose", "succeeded"), ("DriveDistance", "running")]
    for before, after in itertools.pairwise(commands):
        assert after["start_time"] >= before["end_time"]  # each waits for the previous
    assert set(robot["encoders"]) == {"front_left", "front_right"}
    assert robot["heading"] == pytest.approx(0.0, abs=0.01)
    assert robot["position"][1] == pytest.approx(0.5, abs=0.01)


def _poses(sim):
    plant = sim.station.plant
    context = plant.GetMyContextFromRoot(sim.context)
    bodies = [sim.robot()._parts.chassis, *sim.station.bodies.values()]
    return [plant.EvalBodyPoseInWorld(context, b).translation() for b in bodies]


def _max_gap(a, b) -> float:
    return max(np.linalg.norm(p - q) for p, q in zip(_poses(a), _poses(b), strict=True))


SAVE_SCRIPT = ("commands: [!DriveDistance {distance: -0.45, power: 1}, "
               "!RotateDegrees {degrees: 30, power: 0.5}, !Wait {seconds: 1.0}, "
               "!SetPower {left: 0.3, right: 0.3}]")


def test_saved_scene_reloads_where_it_was(tmp_path):
    sim = fast_sim(extra=SAVE_SCRIPT)
    while [r.command for r in sim.robot().command_log()][-1:] != ["Wait"]:
        sim.advance(0.1)
    sim.advance(0.1)  # at rest, waiting
    path = tmp_path / "saved.yaml"
    sim.save_scenario(path)
    again = Simulation(load_scenario(path))
    assert again.time == pytest.approx(sim.time)
    assert _max_gap(sim, again) < 1e-6
    for _ in range(3):  # the wait's rest, then driving on
        sim.advance(1.0)
        again.advance(1.0)
        assert _max_gap(sim, again) < 1e-3
    assert [c["command"] for c in again.robot().summary()["commands"]] == ["Wait", "SetPower"]


def test_scene_saved_while_driving_carries_on(tmp_path):
    sim = fast_sim(extra=SAVE_SCRIPT)
    sim.advance(2.0)  # closing in on the drive's goal
    path = tmp_path / "saved.yaml"
    sim.save_scenario(path)
    again = Simulation(load_scenario(path))
    sim.advance(0.2)
    again.advance(0.2)
    assert _max_gap(sim, again) < 1e-3  # nothing jumps: velocities and wheel speeds carry on
    sim.advance(3.0)
    again.advance(3.0)
    # The drive carries on from its start pose and heading with its recent progress
    # (docs/commands.md, saved-mid-drive, has the figure: 0.0 mm).
    assert _max_gap(sim, again) < 1e-3
    assert [c["command"] for c in again.robot().summary()["commands"]][:2] == [
        "DriveDistance", "RotateDegrees"]  # what was left of the drive, then the script's rest


RESUME_COMMANDS = {"drive": "!DriveDistance {distance: 0.3, power: %g}",
                   "rotate": "!RotateDegrees {degrees: -60, power: %g}"}
RESUME_SETTLE = 0.3
"""s after the command ends when the landings are compared (the seed profile's stop slides
on for ~0.2 s at power 1)."""


def _through_yaml(scenario: sc.Scenario) -> sc.Scenario:
    """The scenario as a saved file gives it back (`save_scenario`, then `load_scenario`)."""
    return load_scenario(data=yaml_dump_typed(scenario, schema=sc.Scenario),
                         defaults=sc.Scenario())


@functools.cache
def _uninterrupted(profile: str, kind: str, power: float):
    """The command run uninterrupted: (time to compare at, (x, y, heading) then, the scenes
    saved on the way by time). Saved after its first update (a seed turn has no progress
    sample yet), at 0.6 s, and 0, 40 and 80 ms after the seed profile's first halving, while
    its 0.1 s of progress samples refill (every update: tests/unit/test_systems_motion.py and
    tools/resume_landing.py)."""
    sim = fast_sim(profile, extra=f"commands: [{RESUME_COMMANDS[kind] % power}]")
    motion = sim.robot()._parts.motion
    saves, halved, t = {}, None, 0.0
    while True:
        t = round(t + 0.01, 6)
        sim.advance_to(t)
        active = motion.get_state(motion.GetMyContextFromRoot(sim.context)).active
        if active is None:
            break
        if halved is None and active.scale < 1.0:
            halved = t
        refilling = halved is not None and round((t - halved) / 0.01) in (0, 4, 8)
        if refilling or t in (0.01, 0.6):
            saves[t] = _through_yaml(sim.saved_scenario())
    assert halved is not None or profile == "closed_loop"
    end = t + RESUME_SETTLE
    sim.advance_to(end)
    robot = sim.robot()
    return end, (*robot.position()[:2], robot.heading()), saves


@functools.cache
def _resumer(profile: str) -> Simulation:
    """One simulation per profile, reset onto each saved scene (a reset run is bit for bit a
    fresh one's)."""
    return fast_sim(profile)


@pytest.mark.parametrize("power", [0.5, 1.0])
@pytest.mark.parametrize("kind", ["drive", "rotate"])
@pytest.mark.parametrize("profile", ["closed_loop", "seed"])
def test_a_command_saved_at_any_time_resumes_to_the_same_landing(profile, kind, power):
    """A resumed command lands within 1 mm and 0.1 deg of the uninterrupted one
    (the issue's target; tests/unit/test_systems_motion.py checks every update on a toy robot).
    The saved scene carries the command on from where it started (its `start`), at the power
    it runs at, with its progress at the last updates (`recent_progress`: the seed profile's
    0.1 s window, the closed loop's speed) and the drive's commanded axle speeds; the script
    restarts at the saved time. Measured: within 0.001 mm and 0.0001 deg (the hold's last
    correction is not saved; docs/commands.md: `python tools/resume_landing.py`)."""
    end, (x0, y0, h0), saves = _uninterrupted(profile, kind, power)
    again = _resumer(profile)
    for save, scenario in saves.items():
        again.reset(scenario)
        again.advance_to(end)
        robot = again.robot()
        (x, y, _), h = robot.position(), robot.heading()
        assert math.hypot(x - x0, y - y0) < 1e-3, save
        assert abs(math.degrees(math.remainder(h - h0, 2 * math.pi))) < 0.1, save


STOP_SCRIPT = ("commands: [!SetPower {left: 0.6, right: 0.4}, !Wait {seconds: 1.0}, "
               "!AllStop {}]")


def _wheel_angles(sim: Simulation) -> np.ndarray:
    plant_context = sim.station.plant.GetMyContextFromRoot(sim.context)
    return np.array([j.get_angle(plant_context) for j in sim.robot()._parts.wheel_joints])


@pytest.mark.parametrize("plant", [(), (SAP,)], ids=["cenic", "sap"])
def test_a_saved_scene_keeps_the_odometry_and_the_hold_angles(plant):
    """The dead-reckoned odometry drifts from the true pose (1-12 mm on this curve); a saved
    scene carries it on as it was (it once restarted at the true pose), and the drive's hold
    angles (where a resting wheel is pulled back to: a few urad from where the ground pushed
    it). Saved while driving between two updates, when the AllStop is due (1.0 s) and issued
    but not yet taken (1.005 s), and at rest: each resumed run ends as the uninterrupted one.

    SAP, measured: the odometry to the bit, the wheel angles within 3e-9 rad (the hold's last
    correction is not saved); without the hold angles they differed by 2e-6 rad. CENIC: a
    scene saved while driving differs by about 1e-17 (the pose through YAML), and CENIC's
    driving on slipping tyres grows that to 0.01-0.02 mm of odometry and 0.05-0.09 mm of
    pose by the end (re-initializing the Simulator at the unchanged state changes nothing),
    inside the resume's 1 mm (docs/commands.md) and far below the odometry's drift that a
    restart at the true pose would lose."""
    extra = STOP_SCRIPT.replace("left: 0.6", "left: 0.8")
    sim, saves = make_sim(_robot_yaml("closed_loop", extra), *plant), {}
    for t in (0.505, 1.0, 1.005, 3.0):
        sim.advance_to(t)
        saves[t] = _through_yaml(sim.saved_scenario())
    sim.advance_to(5.0)
    again = make_sim(_robot_yaml("closed_loop"), *plant)
    for save, scenario in saves.items():
        robot = scenario.robots["corobot"]
        x, y, _ = robot.pose.translation
        drift = math.hypot(robot.odometry[0] - x, robot.odometry[1] - y)
        assert drift > 1e-3  # 2.7-12 mm (CENIC), 4-12 mm (SAP)
        again.reset(scenario)
        again.advance_to(5.0)
        odometry, expected = again.robot().odometry(), sim.robot().odometry()
        if sim.continuous:
            assert math.hypot(odometry.x - expected.x, odometry.y - expected.y) < 0.1 * drift
            assert math.dist(again.robot().position(), sim.robot().position()) < 1e-3, save
            continue
        assert odometry == expected, save
        assert again.robot().pose().x == pytest.approx(sim.robot().pose().x, abs=1e-9), save
        np.testing.assert_allclose(_wheel_angles(again), _wheel_angles(sim), rtol=0,
                                   atol=1e-7, err_msg=str(save))
    resting = saves[3.0].robots["corobot"]
    assert max(abs(h - a) for h, a in zip(resting.wheel_hold_angles, resting.wheel_angles,
                                          strict=True)) > 1e-6  # the hold angles matter


def test_a_command_saved_before_its_first_update_resumes_as_issued():
    """The script issues the drive when the wait ends (at 0.2 s); MotionCommands takes it at
    the next update: a scene saved in between carries it as issued (it was once lost)."""
    sim = fast_sim("seed", extra="commands: [!Wait {seconds: 0.2}, "
                   "!DriveDistance {distance: 0.3, power: 1.0}]")
    again, saves = _resumer("seed"), {}
    for t in (0.2, 0.21, 0.22):
        sim.advance_to(t)
        saves[t] = _through_yaml(sim.saved_scenario())
    sim.advance_to(1.5)  # the drive ends near 0.9 s
    for save, scenario in saves.items():
        again.reset(scenario)
        again.advance_to(1.5)
        assert math.dist(again.robot().position(), sim.robot().position()) < 1e-3, save
        assert [c["command"] for c in again.robot().summary()["commands"]] == ["DriveDistance"]


def test_drive_test_same_seed_same_numbers(tmp_path):
    """Two runs of the tool print the same numbers to the last digit. At full power (15 s
    simulated for the loop instead of 38 s at the default 0.2): the determinism asserted does
    not depend on the power."""
    outputs = []
    for name in ("a.png", "b.png"):
        run = subprocess.run(
            [sys.executable, str(REPO / "tools" / "drive_test.py"), "--loops", "1", "--seed",
             "7", "--power", "1", "--plot", str(tmp_path / name)], capture_output=True,
            text=True, check=True)
        outputs.append([line for line in run.stdout.splitlines()
                        if not line.startswith("path plot")])
        assert (tmp_path / name).stat().st_size > 10_000
    assert outputs[0] == outputs[1]
    assert "0 failed commands" in outputs[0][-1]


def test_compass_agrees_with_the_chassis_yaw_after_a_long_drive():
    """SAP's discrete plant lets its state quaternion drift from unit norm (CENIC's keeps it
    normalized); the compass must not care
    (test_systems_odometry: a non-unit state quaternion). One turn and a drive take the norm
    0.5% off (measured: 0.0053; five turns and drives, 25 s, 1.9%): a compass that read the
    quaternion as a unit one (atan2 of its entries) would be off by ~2e-3 rad here, a
    thousand times the tolerance."""
    sim = make_sim(SAP)
    robot = sim.robot()
    robot.rotate_degrees(170, 0.5)
    robot.drive_distance(0.3, 0.5)
    plant = sim.station.plant
    quaternion = plant.GetPositions(plant.GetMyContextFromRoot(sim.context),
                                    plant.GetModelInstanceByName("corobot"))[:4]
    assert abs(np.linalg.norm(quaternion) - 1.0) > 1e-3  # the drift the compass must ignore
    assert robot.heading() == pytest.approx(robot.pose().yaw, abs=1e-6)


@pytest.fixture(scope="module")
def physics_only_sim():
    return make_sim("robots: {corobot: {ir_sensors: {front: {enabled: false}, rear: "
                    "{enabled: false}}}}")


@pytest.mark.parametrize("later", [sc.SetPower(0.2, 0.2), sc.Wait(0.2), sc.AllStop()],
                         ids=lambda c: type(c).__name__)
@pytest.mark.parametrize("first", [sc.SetPower(0.3, 0.3), sc.DriveDistance(0.05, 0.5),
                                   sc.RotateDegrees(10.0, 0.5)], ids=lambda c: type(c).__name__)
def test_the_summary_shows_every_ended_command_ended(physics_only_sim, first, later):
    """End to end: whatever follows a command in the script, the summary
    shows it `succeeded` (none of these can fail here) with its end time, and the script's
    last command too once the drive has taken it."""
    sim = physics_only_sim
    scenario = dc.replace(sim.scenario, robots={"corobot": dc.replace(
        sim.scenario.robots["corobot"], commands=[first, later])})
    sim.reset(scenario)
    sim.advance(2.5)  # the 5 cm drive and 10 deg turn take under 1.5 s
    commands = sim.summary()["robots"]["corobot"]["commands"]
    assert [c["command"] for c in commands] == [type(first).__name__, type(later).__name__]
    for c in commands:
        assert (c["status"], c["reason"]) == ("succeeded", ""), commands
        assert c["start_time"] <= c["end_time"] <= sim.time
