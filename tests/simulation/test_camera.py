"""The front camera, measured through the simulation (SPEC, Sensors).

The box test compares the share of the image the giant box covers with a pinhole projection
of its near face, from the camera's pose in the simulation (the robot has settled on its
tyres) and the camera's intrinsics. Tolerance: one pixel along every edge of the projected
face inside the image (rasterisation puts an edge pixel on either side): 0.4% of the image
for the horizon edge across the full width. Measured differences: 0.0-0.25%.
"""

import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from conftest import CENIC, DEFAULT_SCENARIO, REPO, SAP, TWO_CAMERAS, make_sim
from corobot_drake.cli import main
from corobot_drake.config.scenario import (
    ScenarioError,
    load_scenario,
    physics_step,
)
from corobot_drake.config.sensors import RENDERER_NAME, default_camera_config
from corobot_drake.simulation import Simulation

CAMERA = default_camera_config()
"""The Corobot's camera, as its robot file says (320 x 240)."""

pytestmark = pytest.mark.xdist_group("simulation/test_camera.py")
"""The camera tests in file order on one worker (each builds its own GL renderer: on one
worker they stay clear of another module's in the same process)."""


BOX_RGB = np.array([0.8, 0.45, 0.15])
SKY_RGB = np.array([0.53, 0.73, 0.92])
GROUND_RGB = np.array([0.45, 0.5, 0.4])


def box_mask(image: np.ndarray) -> np.ndarray:
    """Pixels of the box's orange (any brightness): R > 1.4 G and G > 1.5 B. The ground
    (R/G 0.9) and the sky (R/G 0.7) fail the first test."""
    rgb = image[:, :, :3].astype(float)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return (r > 1.4 * g) & (g > 1.5 * b)


def clip_polygon(poly: list, inside, intersect) -> list:
    """One Sutherland-Hodgman pass."""
    out = []
    for i, p in enumerate(poly):
        q = poly[i - 1]
        if inside(p):
            if not inside(q):
                out.append(intersect(q, p))
            out.append(p)
        elif inside(q):
            out.append(intersect(q, p))
    return out


def clip_to_image(poly: list, width: int, height: int) -> list:
    for axis, bound, keep_below in ((0, 0, False), (0, width, True), (1, 0, False),
                                    (1, height, True)):
        def inside(p, a=axis, c=bound, below=keep_below):
            return p[a] <= c if below else p[a] >= c

        def intersect(p, q, a=axis, c=bound):
            t = (c - p[a]) / (q[a] - p[a])
            return p + t * (q - p)

        poly = clip_polygon(poly, inside, intersect)
        if not poly:
            return []
    return poly


def area_and_edge_length(poly: list, width: int, height: int) -> tuple[float, float]:
    """The polygon's area and the length of its edges that are not on the image border."""
    if len(poly) < 3:
        return 0.0, 0.0
    area = edges = 0.0
    for i, p in enumerate(poly):
        q = poly[i - 1]
        area += q[0] * p[1] - p[0] * q[1]
        on_border = any(abs(p[a] - c) < 1e-9 and abs(q[a] - c) < 1e-9
                        for a, c in ((0, 0), (0, width), (1, 0), (1, height)))
        if not on_border:
            edges += float(np.linalg.norm(p - q))
    return abs(area) / 2, edges


def expected_box_share(sim) -> tuple[float, float]:
    """(share of the image, tolerance) for the box's +x face, by pinhole projection."""
    config = sim.scenario.robots["corobot"].cameras["front"]
    W, H = config.width, config.height
    f = (H / 2) / math.tan(math.radians(config.focal.y) / 2)
    sensor = sim.station.diagram.GetSubsystemByName("corobot.camera.front")
    X_WC = sensor.body_pose_in_world_output_port().Eval(sensor.GetMyContextFromRoot(
        sim.context))
    plant = sim.station.plant
    X_WBox = plant.EvalBodyPoseInWorld(plant.GetMyContextFromRoot(sim.context),
                                       sim.station.bodies["giant_box"])
    half = load_scenario(DEFAULT_SCENARIO).world.bodies["giant_box"].shape.size[0] / 2
    # The face's corners; the ground (z = 0) hides anything of it below z = 0.
    corners_W = [X_WBox @ np.array([half, y, z]) for y, z in
                 ((-half, -half), (half, -half), (half, half), (-half, half))]
    corners_W = [np.array([c[0], c[1], max(c[2], 0.0)]) for c in corners_W]
    X_CW = X_WC.inverse()
    poly = []
    for c in corners_W:
        x, y, z = X_CW @ c  # Drake camera frame: +z forward, +x right, +y down
        assert z > 0.05, "the whole face must be in front of the camera for this projection"
        poly.append(np.array([W / 2 + f * x / z, H / 2 + f * y / z]))
    area, edges = area_and_edge_length(clip_to_image(poly, W, H), W, H)
    return area / (W * H), edges / (W * H)


@pytest.mark.parametrize("x, y", [(0.0, 0.0), (0.0, 0.9), (0.8, 0.0), (0.4, -1.0)],
                         ids=["facing", "edge_left", "farther", "edge_right"])
def test_box_fills_the_share_the_geometry_predicts(x, y):
    """The robot faces the giant box (yaw 180 deg, as after turning round at the origin)."""
    sim = make_sim(f"robots: {{corobot: {{pose: {{translation: [{x}, {y}, 0], "
                   "rotation: !Rpy {deg: [0, 0, 180]}}}}", camera=True)
    sim.advance(0.5)  # settle on the tyres; the latest frame is from t = 14/30 s
    image = sim.robot().camera_image()
    assert image.shape == (CAMERA.height, CAMERA.width, 4)
    assert image.dtype == np.uint8
    share = box_mask(image).mean()
    expected, tolerance = expected_box_share(sim)
    assert expected > 0.2
    assert share == pytest.approx(expected, abs=tolerance), (share, expected, tolerance)


def test_frames_are_lit_not_black():
    """Facing away from the box: sky above the horizon, sunlit ground below; facing the box:
    its face is lit (by the book's sun, which shines on it, and the fill light)."""
    sim = make_sim(camera=True)
    sim.advance(0.2)
    image = sim.robot().camera_image()[:, :, :3].astype(float)
    H = image.shape[0]
    sky, ground = image[: H // 4], image[3 * H // 4:]
    # The sky is the renderer's background: the scenario's colour exactly.
    np.testing.assert_allclose(sky.mean(axis=(0, 1)), SKY_RGB * 255, atol=2)
    # The ground: its own hue, lit by the sun and the fill light (> 40% of its colour).
    g = ground.mean(axis=(0, 1))
    assert np.all(g > 0.4 * GROUND_RGB * 255), g
    assert g[1] > g[0] > g[2]
    # The frame is the camera's reading, read by name; `front` is the front IR sensor's too.
    robot = sim.robot()
    reading = robot.reading("front", kind="cameras")
    np.testing.assert_array_equal(reading.data, robot.camera_image())
    assert reading.time == robot.camera_image_time() and reading.width == image.shape[1]
    assert robot.sensor_json("front", "camera") == {  # from the frame's time alone
        "width": 320, "height": 240, "encoding": "rgba8", "time": reading.time}
    # Without a kind, a shared name is the first kind's in the registry: the IR sensor.
    assert robot.reading("front") == robot.reading("front", kind="ir_sensors")

    sim = make_sim("robots: {corobot: {pose: {rotation: !Rpy {deg: [0, 0, 180]}}}}", camera=True)
    sim.advance(0.2)
    image = sim.robot().camera_image()
    face = image[:100, :, :3].reshape(-1, 3).astype(float)
    assert box_mask(image[:100]).all()
    assert np.all(face.mean(axis=0) > 0.3 * BOX_RGB * 255)


def test_under_sap_frames_come_at_the_camera_rate_after_the_output_delay():
    """On SAP's discrete plant the default camera is asynchronous: a frame captured at a tick
    (0.5 ms past each 1/fps, off the plant's steps) appears output_delay (0.03 s) later;
    before the first there is none."""
    sim = make_sim("robots: {corobot: {cameras: {front: {fps: 10}}}}", SAP, camera=True)
    robot = sim.robot()
    assert robot.has_camera
    config = sim.scenario.robots["corobot"].cameras["front"]
    assert (config.capture_offset, config.output_delay) == (0.0005, 0.03)
    assert robot.camera_image() is None and math.isnan(robot.camera_image_time())
    sim.advance_to(0.03)
    assert robot.camera_image() is None
    sim.advance_to(0.035)  # the frame captured at 0.0005 s appeared at 0.0305 s
    assert robot.camera_image_time() == pytest.approx(0.0005)
    assert robot.camera_image()[:, :, :3].max() > 0
    sim.advance_to(0.33)
    assert robot.camera_image_time() == pytest.approx(0.2005)
    sim.advance_to(0.335)
    assert robot.camera_image_time() == pytest.approx(0.3005)
    seen = set()  # every frame of 3 s: a lost one would leave a gap in the ticks
    while sim.time < 3.0:
        sim.advance(0.01)  # frames come every 0.1 s: each is seen
        seen.add(round((robot.camera_image_time() - 0.0005) * 10))
    assert seen == set(range(3, 30))  # 0.3005 s (tick 3) to 2.9005 s


def test_a_synchronous_camera_faster_than_the_plant_steps_keeps_every_frame(tmp_path):
    """200 Hz against 10 ms steps: frames at the ticks themselves, all saved."""
    scenario = load_scenario(DEFAULT_SCENARIO, overrides=[
        "robots: {corobot: {cameras: {front: {fps: 200, output_delay: 0}}}}"])
    sim = Simulation(scenario, save_camera=tmp_path)
    sim.advance(0.1)
    assert sim.robot().camera_image_time() == pytest.approx(0.0955)  # tick 19, 0.5 ms past
    files = sorted((tmp_path / "corobot").glob("*.png"))
    assert [f.name for f in files] == [f"frame_{i:06d}.png" for i in range(20)]  # ticks 0-19


def test_without_delay_frames_come_at_the_camera_rate():
    sim = make_sim("robots: {corobot: {cameras: {front: {fps: 10, output_delay: 0, "
                   "capture_offset: 0}}}}",
                   camera=True)
    robot = sim.robot()
    assert robot.camera_image_time() == 0.0  # rendered at initialization
    first = robot.camera_image()
    assert first[:, :, :3].max() > 0
    sim.advance(0.35)
    assert robot.camera_image_time() == pytest.approx(0.3)


NO_DELAY = "robots: {corobot: {cameras: {front: {output_delay: 0, capture_offset: 0}}}}"
"""The synchronous camera with its ticks at multiples of 1/fps."""

SPIN_BY_THE_EDGE = ("robots: {corobot: {pose: {translation: [0.4, -1.0, 0], "
                    "rotation: !Rpy {deg: [0, 0, 180]}}, "
                    "commands: [!SetPower {left: -0.5, right: 0.5}]}}")


def test_under_sap_delayed_frames_show_the_scene_at_their_capture():
    """SAP's asynchronous frame captured at the 16th tick (0.5 ms past 16/30 s, between plant
    steps) is, bit for bit, the synchronous camera's frame for that tick, and it appears
    0.03 s later. The robot spins in front of the box's edge, so consecutive frames differ."""
    sync = make_sim(SPIN_BY_THE_EDGE, "robots: {corobot: {cameras: {front: {output_delay: 0}}}}",
                    SAP, camera=True)
    sync.advance_to(0.545)
    assert sync.robot().camera_image_time() == pytest.approx(0.54)  # tick 16, on the next step
    delayed = make_sim(SPIN_BY_THE_EDGE, SAP, camera=True)
    tick = 0.0005 + 16.0 / 30.0
    delayed.advance_to(tick + 0.03 - 0.001)
    assert delayed.robot().camera_image_time() == pytest.approx(0.0005 + 15.0 / 30.0)
    previous = delayed.robot().camera_image()
    delayed.advance_to(tick + 0.03 + 0.001)
    assert delayed.robot().camera_image_time() == pytest.approx(tick)
    np.testing.assert_array_equal(delayed.robot().camera_image(), sync.robot().camera_image())
    assert np.abs(previous.astype(int) - sync.robot().camera_image().astype(int)).max() > 0


def test_no_camera():
    sim = make_sim("robots: {corobot: {cameras: {front: {rgb: false}}}}", camera=True)
    robot = sim.robot()
    assert not robot.has_camera
    assert not sim.station.diagram.HasSubsystemNamed("corobot.camera.front")
    assert not hasattr(robot, "camera_image")  # a robot without a camera has no such call
    assert sim.summary()["robots"]["corobot"]["camera_frames"] == 0


@pytest.mark.parametrize("override, field", [
    ("{depth: true}", "robots.corobot.cameras.front.depth"),
    ("{output_delay: 0.04}", "robots.corobot.cameras.front.output_delay"),
    ("{fps: 0}", "robots.corobot.cameras.front.fps"),
    ("{renderer_class: RenderEngineGltfClient}", "robots.corobot.cameras.front.renderer_class"),
    ("{clipping_near: 2.0, clipping_far: 1.0}", "robots.corobot.cameras.front.clipping_far"),
])
def test_bad_camera_is_a_clear_error(override, field):
    with pytest.raises(ScenarioError, match=field.replace(".", r"\.") + ":"):
        load_scenario(DEFAULT_SCENARIO,
                      overrides=[f"robots: {{corobot: {{cameras: {{front: {override}}}}}}}"])


def test_cli_saves_numbered_frames(tmp_path, capsys):
    summary = tmp_path / "summary.json"
    assert main([str(DEFAULT_SCENARIO), "--headless", "--duration", "0.5",
                 "--save-camera", str(tmp_path / "frames"), "--camera-rate", "10",
                 "--summary", str(summary)]) == 0
    files = sorted((tmp_path / "frames" / "corobot").glob("*.png"))
    assert [f.name for f in files] == [f"frame_{i:06d}.png" for i in range(5)]
    assert json.loads(summary.read_text())["robots"]["corobot"]["camera_frames"] == 5
    image = np.asarray(Image.open(files[-1]))
    assert image.shape == (CAMERA.height, CAMERA.width, 3)
    assert image.mean() > 50
    assert main([str(DEFAULT_SCENARIO), "--headless", "--camera-rate", "0"]) == 2
    assert "--camera-rate" in capsys.readouterr().err


def _full_disk_frames(tmp_path, monkeypatch):
    """A --save-camera directory whose first frame's file is a link to /dev/full (every
    write fails: No space left on device), and a temporary directory of its own."""
    import tempfile

    frames = tmp_path / "frames"
    (frames / "corobot").mkdir(parents=True)
    (frames / "corobot" / "frame_000000.png").symlink_to("/dev/full")
    temp = tmp_path / "temp"
    temp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temp))
    return frames, temp


def _save_camera_lines(err: str) -> list[str]:
    assert "Traceback" not in err
    return [line for line in err.splitlines() if "--save-camera" in line]


def test_frames_on_a_full_disk_go_to_a_fallback_named_in_one_line(tmp_path, monkeypatch,
                                                                  capsys):
    """The run goes on and writes its other outputs; exit status 1, as for --summary."""
    frames, temp = _full_disk_frames(tmp_path, monkeypatch)
    summary = tmp_path / "summary.json"
    assert main([str(DEFAULT_SCENARIO), "--headless", "--duration", "0.5", "--save-camera",
                 str(frames), "--camera-rate", "10", "--summary", str(summary)]) == 1
    (fallback,) = temp.glob("corobot-save-camera-*")
    assert _save_camera_lines(capsys.readouterr().err) == [
        f"error: --save-camera: {frames}/corobot/frame_000000.png: cannot write (No space left "
        f"on device); it and the frames after it written to {fallback} instead"]
    assert sorted(f.name for f in fallback.iterdir()) == [f"frame_{i:06d}.png" for i in range(5)]
    assert json.loads(summary.read_text())["robots"]["corobot"]["camera_frames"] == 5


def test_frames_with_no_fallback_either_are_lost_in_one_line(tmp_path, monkeypatch, capsys):
    import errno
    import tempfile

    frames, _ = _full_disk_frames(tmp_path, monkeypatch)

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(tempfile, "mkdtemp", full)
    assert main([str(DEFAULT_SCENARIO), "--headless", "--duration", "0.5", "--save-camera",
                 str(frames), "--camera-rate", "10"]) == 1
    assert _save_camera_lines(capsys.readouterr().err) == [
        f"error: --save-camera: {frames}/corobot/frame_000000.png: cannot write (No space left "
        "on device); nor to the temporary directory (No space left on device): it and the "
        "frames after it are lost"]


CIRCLE = "robots: {corobot: {commands: [!SetPower {left: 0.4, right: 0.8}]}}"


def test_under_sap_frames_taken_on_plant_steps_are_the_exact_time_images():
    """The 30 Hz tick at 16/30 s falls between SAP's 10 ms plant steps; the frame is taken at
    the step at 0.54 s and is, bit for bit, what the sensor renders at exactly 16/30 s (a
    discrete plant's scene only changes at steps). The robot spins in front of the box's
    edge, so consecutive frames differ."""
    sim = make_sim(SPIN_BY_THE_EDGE, NO_DELAY, SAP, camera=True)
    assert physics_step(sim.scenario.plant_config, sim.scenario.simulator_config) == 0.01
    sensor = sim.station.diagram.GetSubsystemByName("corobot.camera.front")
    tick = 16.0 / 30.0
    sim.advance_to(tick - 0.01)
    previous = sim.robot().camera_image().copy()
    assert sim.robot().camera_image_time() == pytest.approx(0.5)  # tick 15, on a step
    sim.advance_to(tick)
    exact = np.array(sensor.color_image_output_port().Eval(
        sensor.GetMyContextFromRoot(sim.context)).data)
    assert sim.robot().camera_image_time() == pytest.approx(0.5)  # not taken yet
    sim.advance_to(0.545)
    assert sim.robot().camera_image_time() == pytest.approx(0.54)
    np.testing.assert_array_equal(sim.robot().camera_image(), exact)
    assert np.abs(exact.astype(int) - previous.astype(int)).max() > 0


def test_the_synchronous_camera_adds_no_simulator_stops():
    """Frames come on the plant's steps, so the Simulator stops at the same times with the
    camera as without it."""
    steps = []
    for camera in (False, True):
        sim = make_sim(CIRCLE, NO_DELAY, camera=camera)
        sim.advance(1.0)
        steps.append(sim.simulator.get_num_steps_taken())
    assert steps[0] == steps[1]
    sim = make_sim(CIRCLE, NO_DELAY, camera=True)
    sim.advance(1.005)
    assert sim.robot().camera_image_time() == pytest.approx(1.0)  # tick 30 on step 100


def test_under_cenic_the_camera_changes_nothing_of_the_motion():
    """A capture between the steps would split a CENIC step and move the robot (with the
    asynchronous camera the chassis bounced: its vertical speed swung 5-8 mm/s from step to
    step against 1.3): on a continuous plant the camera takes its frames on the steps, so the
    run is the same to the bit with it and without it, stop for stop."""
    runs = []
    for camera in (False, True):
        sim = make_sim(CIRCLE, CENIC, camera=camera)
        sim.advance(1.0)
        pose = sim.robot().pose()
        runs.append((sim.simulator.get_num_steps_taken(), pose.x, pose.y, pose.yaw))
    assert runs[0] == runs[1]


def test_under_cenic_frames_come_on_the_steps_after_the_output_delay():
    """Tick k (0.5 ms past k / 10 s) is taken at the next step, 0.01 + k / 10 s, and comes
    out 0.03 s later, on a step too; before the first there is none (as with Drake's
    asynchronous camera: nothing is taken at initialization). Every tick's frame comes out."""
    sim = make_sim("robots: {corobot: {cameras: {front: {fps: 10}}}}", CENIC, camera=True)
    robot = sim.robot()
    assert sim.station.robots["corobot"].cameras["front"].delay == 0.03
    sim.advance_to(0.04)
    assert robot.camera_image() is None and math.isnan(robot.camera_image_time())
    sim.advance_to(0.045)
    assert robot.camera_image_time() == pytest.approx(0.01)
    assert robot.camera_image()[:, :, :3].max() > 0
    seen = set()
    while sim.time < 3.0:
        sim.advance(0.01)
        seen.add(round((robot.camera_image_time() - 0.01) * 10))
    assert seen == set(range(0, 30))  # 0.01 s (tick 0) to 2.91 s (tick 29)


def gl_worker(sim, hold):
    """The hold's render worker; skips where the scene's cameras render with VTK (no GL)."""
    if sim.station.renderers[RENDERER_NAME] != "RenderEngineGl":
        pytest.skip("no GL renderer here: VTK cameras render in place")
    assert hold._worker is not None, "a GL camera under CENIC renders on a worker"
    return hold._worker


def test_under_cenic_delayed_frames_render_on_a_thread_that_ends_with_the_simulation():
    """Each frame renders on the camera's worker thread, from the plant's state at its step
    (one render per frame read), and that thread ends when the simulation is freed."""
    import threading
    import weakref

    def workers():
        return [t for t in threading.enumerate() if t.name.startswith("corobot-camera")]

    before = set(workers())
    sim = make_sim("robots: {corobot: {cameras: {front: {fps: 10}}}}", CENIC, camera=True)
    hold = sim.station.diagram.GetSubsystemByName("corobot.camera.front.hold")
    worker = gl_worker(sim, hold)
    assert worker.renders == 0
    for k in range(11):  # ticks 0-10 taken (0.01 ... 1.01 s), 0-10 out (... 1.04 s)
        sim.advance_to(0.045 + 0.1 * k)
        assert sim.robot().camera_image().shape[1] == 320
    assert sim.robot().camera_image_time() == pytest.approx(1.01)
    assert worker.renders == 11
    mine = set(workers()) - before
    assert len(mine) == 1
    freed = weakref.ref(sim)
    del sim, hold
    assert freed() is None
    assert not mine & set(workers())


def test_a_frame_without_its_render_started_renders_when_taken():
    """A frame whose render the worker did not start (a Context restored mid-flight) is
    rendered when it is due: the same image."""
    sim = make_sim(SPIN_BY_THE_EDGE, CENIC, camera=True)
    worker = gl_worker(sim, sim.station.diagram.GetSubsystemByName("corobot.camera.front.hold"))
    plant = sim.station.plant
    x = plant.GetPositionsAndVelocities(plant.GetMyContextFromRoot(sim.context))
    worker.submit(("started", 0.0), x)
    started = np.array(worker.take(("started", 0.0), x).data)
    not_started = np.array(worker.take(("never submitted", 0.0), x).data)
    np.testing.assert_array_equal(started, not_started)
    sensor = sim.station.diagram.GetSubsystemByName("corobot.camera.front")
    in_place = np.array(sensor.color_image_output_port().Eval(
        sensor.GetMyContextFromRoot(sim.context)).data)
    np.testing.assert_array_equal(started, in_place)


def test_a_render_worker_that_cannot_start_leaves_the_camera_rendering_in_place(monkeypatch):
    import threading

    import corobot_drake.sensors.camera as camera

    def refuse(*args):
        raise RuntimeError("no GL on this thread (a test's)")

    def workers():
        return [t for t in threading.enumerate() if t.name.startswith("corobot-camera")]

    before = set(workers())
    monkeypatch.setattr(camera, "build_render_scene", refuse)
    with pytest.warns(UserWarning, match=r"render in the simulation's thread .*no GL on this "
                                         r"thread \(a test's\)"):
        sim = make_sim(CENIC, "robots: {corobot: {cameras: {front: {width: 32, height: 24}}}}",
                       camera=True)
    assert sim.station.diagram.GetSubsystemByName("corobot.camera.front.hold")._worker is None
    assert set(workers()) <= before  # the worker that failed is gone
    sim.advance_to(0.045)
    assert sim.robot().camera_image_time() == pytest.approx(0.01)


def test_a_vtk_camera_renders_in_place_under_cenic():
    sim = make_sim(CENIC, "robots: {corobot: {cameras: {front: {renderer_class: "
                   "RenderEngineVtk, width: 32, height: 24}}}}", camera=True)
    assert sim.station.diagram.GetSubsystemByName("corobot.camera.front.hold")._worker is None
    sim.advance_to(0.045)
    assert sim.robot().camera_image_time() == pytest.approx(0.01)


def test_a_worker_renders_with_the_engine_its_renderer_name_shares_in_the_scene():
    """Cameras of one renderer name share the engine the first of them made; a second
    camera asking for VTK under that name renders with the scene's GL engine, and so does its
    render worker's copy: its frame is the in-place render, bit for bit."""
    sim = make_sim(SPIN_BY_THE_EDGE, CENIC, "robots: {corobot: {cameras: {second: "
                   "{renderer_class: RenderEngineVtk, width: 64, height: 48}}}}", camera=True)
    hold = sim.station.diagram.GetSubsystemByName("corobot.camera.second.hold")
    worker = gl_worker(sim, hold)
    plant = sim.station.plant
    sim.advance_to(0.2)
    x = plant.GetPositionsAndVelocities(plant.GetMyContextFromRoot(sim.context))
    sensor = sim.station.diagram.GetSubsystemByName("corobot.camera.second")
    in_place = np.array(sensor.color_image_output_port().Eval(
        sensor.GetMyContextFromRoot(sim.context)).data)
    assert in_place[:, :, :3].std() > 10  # the box's edge and the ground: no blank view
    np.testing.assert_array_equal(np.array(worker.take("now", x).data), in_place)


def test_a_worker_thread_without_gl_leaves_the_camera_rendering_in_place(monkeypatch):
    """The default renderer falls back to VTK where GL is missing; on a worker's thread the
    copy asks for GL by name, so a thread without GL makes the camera render in place (with
    the scene's GL engine) instead of rendering with another engine."""
    import threading

    import corobot_drake.sensors.camera as camera

    made = camera.make_render_engine

    def no_gl_on_workers(renderer_class, *args):
        if threading.current_thread().name.startswith("corobot-camera"):
            assert renderer_class == "RenderEngineGl"
            raise camera.RendererUnavailableError("camera renderer RenderEngineGl: no GL here")
        return made(renderer_class, *args)

    monkeypatch.setattr(camera, "make_render_engine", no_gl_on_workers)
    with pytest.warns(UserWarning, match="render in the simulation's thread .*no GL here"):
        sim = make_sim(CENIC, "robots: {corobot: {cameras: {front: {width: 32, height: 24}}}}",
                       camera=True)
    if sim.station.renderers[RENDERER_NAME] != "RenderEngineGl":
        pytest.skip("no GL renderer here: VTK cameras render in place")
    assert sim.station.diagram.GetSubsystemByName("corobot.camera.front.hold")._worker is None
    sim.advance_to(0.045)
    assert sim.robot().camera_image_time() == pytest.approx(0.01)


def test_under_cenic_a_delayed_frame_is_the_synchronous_frame_of_its_step():
    """With the delay or without, a frame is taken at the same step, of the same scene (the
    runs are the same: no capture splits a step), bit for bit."""
    sync = make_sim(SPIN_BY_THE_EDGE, CENIC,
                    "robots: {corobot: {cameras: {front: {output_delay: 0}}}}", camera=True)
    sync.advance_to(0.545)
    assert sync.robot().camera_image_time() == pytest.approx(0.54)  # tick 16's step
    delayed = make_sim(SPIN_BY_THE_EDGE, CENIC, camera=True)
    delayed.advance_to(0.565)
    assert delayed.robot().camera_image_time() == pytest.approx(0.51)  # tick 15's, out at 0.54
    previous = delayed.robot().camera_image()
    delayed.advance_to(0.575)  # out at 0.57
    assert delayed.robot().camera_image_time() == pytest.approx(0.54)
    np.testing.assert_array_equal(delayed.robot().camera_image(), sync.robot().camera_image())
    assert np.abs(previous.astype(int) - sync.robot().camera_image().astype(int)).max() > 0


def test_gl_and_vtk_render_the_same_picture():
    """The two renderers, same lights and scene: from 4 m the box's face with both vertical
    edges, the sky above and beside it, the ground below. Both give the box share the geometry
    predicts (within its one-pixel edge tolerance), mean colours within 2 grey levels
    (measured: under 0.02), and pixels more than 10 levels apart only along edges: under 1 %
    of the image, the box's outline (measured: 0.07 %)."""
    images = {}
    for renderer in ("RenderEngineGl", "RenderEngineVtk"):
        sim = make_sim("robots: {corobot: {pose: {translation: [4.0, 1.0, 0], "
                       "rotation: !Rpy {deg: [0, 0, 185]}}, "
                       f"cameras: {{front: {{renderer_class: {renderer}, output_delay: 0}}}}}}}}",
                       camera=True)
        assert sim.station.renderers == {"corobot_camera": renderer}
        sim.advance(0.3)
        images[renderer] = image = sim.robot().camera_image()
        expected, tolerance = expected_box_share(sim)
        assert box_mask(image).mean() == pytest.approx(expected, abs=tolerance)
        sky = np.all(np.abs(image[:, :, :3].astype(float) - SKY_RGB * 255) < 2, axis=2)
        assert 0.1 < sky.mean() < 0.5  # the scene has sky, box and ground, with edges
    gl, vtk = (images[r][:, :, :3].astype(int) for r in ("RenderEngineGl", "RenderEngineVtk"))
    np.testing.assert_allclose(gl.reshape(-1, 3).mean(axis=0), vtk.reshape(-1, 3).mean(axis=0),
                               atol=2)
    assert (np.abs(gl - vtk).max(axis=2) > 10).mean() < 0.01


def test_the_default_renderer_is_gl_here():
    """tools/setup installs Xvfb, so the default ("") renders with GL (about half the cost of
    VTK per frame: docs/performance.md)."""
    sim = make_sim(camera=True)
    assert sim.station.renderers == {"corobot_camera": "RenderEngineGl"}, (
        "no X display and no Xvfb: run tools/setup as root or apt-get install xvfb")


NO_DISPLAY = """
import sys, warnings
import corobot_drake.sensors.camera as camera
camera.x_display = lambda: None  # as on a machine with neither DISPLAY nor Xvfb
from corobot_drake.cli import main
sys.exit(main(sys.argv[1:]))
"""


def test_without_a_display_gl_is_a_clear_error_and_the_default_falls_back(tmp_path):
    """In a child process: VTK's headless EGL contexts and GL's GLX ones cannot share a
    thread (libglvnd), and this test process renders with GLX."""
    def run(*args):
        return subprocess.run([sys.executable, "-c", NO_DISPLAY, str(DEFAULT_SCENARIO),
                               "--headless", "--duration", "0.1", *args],
                              capture_output=True, text=True, timeout=120)

    fallback = run("--save-camera", str(tmp_path))
    assert fallback.returncode == 0, fallback.stderr
    assert "camera: rendering with VTK" in fallback.stderr
    image = np.asarray(Image.open(tmp_path / "corobot" / "frame_000000.png"))
    assert image.mean() > 50
    gl = "robots: {corobot: {cameras: {front: {renderer_class: RenderEngineGl}}}}"
    for extra in ((), ("--serve", "--port", "0")):
        result = run("--override", gl, *extra)
        assert result.returncode == 2, (extra, result.stderr)
        assert "RenderEngineGl: no X display" in result.stderr
        assert "Traceback" not in result.stderr


def test_the_webcam_service_has_no_frame_before_the_first_output():
    """What the HTTP webcam reads (`calls.grab_frame`): nothing before the first frame
    (the server answers 503 then), the RGB frame and its capture time after."""
    from corobot_drake.serving import calls

    sim = make_sim(camera=True)
    t, frame_time, image = calls.grab_frame("corobot", sim)
    assert image is None and math.isnan(frame_time) and t == 0.0
    sim.advance_to(0.035)  # the first frame, taken on the step at 10 ms, is out at 40 ms
    assert calls.grab_frame("corobot", sim)[2] is None
    sim.advance_to(0.045)
    t, frame_time, image = calls.grab_frame("corobot", sim)
    assert t == pytest.approx(0.045) and frame_time == pytest.approx(0.01)
    assert image.shape == (CAMERA.height, CAMERA.width, 3) and image.mean() > 50


def test_a_robot_with_two_cameras_renders_each_from_its_own_pose(tmp_path):
    """A second camera, `rear`, looking back from above: both rendered each frame (one
    engine for both), each through its own ports, its own frames in the webcam's reader and
    its own saved files. The front one sees the scene ahead, the rear one the scene behind:
    the two images share only sky and ground, so they differ by far more than rendering
    noise (tens of grey levels on average, against 0 for one camera twice)."""
    from corobot_drake.serving import calls

    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[TWO_CAMERAS]),
                     save_camera=tmp_path)
    robot = sim.robot()
    assert robot.camera_names == ("front", "rear") and robot.has_camera
    assert list(sim.station.renderers) == ["corobot_camera"]
    sim.advance(0.1)
    front, rear = robot.camera_image("front"), robot.camera_image("rear")
    assert front.shape == rear.shape == (48, 64, 4)
    # The tick at 0.0005 + 2/30 s, taken on the plant step after it.
    assert robot.camera_image_time("front") == robot.camera_image_time("rear") == pytest.approx(
        0.07, abs=1e-9)
    np.testing.assert_array_equal(robot.camera_image(), front)  # no name: the front camera
    assert np.abs(front.astype(int) - rear.astype(int)).mean() > 20
    sky = np.asarray(sim.scenario.world.sky_color[:3]) * 255
    for image in (front, rear):  # each was rendered: it shows more than the clear colour
        assert np.abs(image[:, :, :3] - sky).mean() > 20
    _, _, webcam = calls.grab_frame("corobot", sim, camera="rear")
    np.testing.assert_array_equal(webcam, rear[:, :, :3])
    assert sim.station.diagram.HasOutputPort("corobot.camera.rear.rgb_image")
    # The ticks at 0.0005 + k/30 s for k = 0, 1, 2, each camera's in its own folder.
    assert robot.camera_frames_saved() == 2 * 3
    assert len(list((tmp_path / "corobot" / "rear").glob("frame_*.png"))) == 3
    assert len(list((tmp_path / "corobot").glob("frame_*.png"))) == 3
    with pytest.raises(KeyError, match=r"has no camera 'top'.*it has front, rear"):
        robot.camera_image("top")


def test_a_stale_display_is_replaced_by_a_private_xvfb(tmp_path):
    """DISPLAY naming no server (an ended ssh -X session): a warning, a private Xvfb, frames,
    exit 0 (it used to end in a traceback from the renderer)."""
    env = {**os.environ, "DISPLAY": ":987"}
    run = subprocess.run([sys.executable, "-m", "corobot_drake", str(DEFAULT_SCENARIO),
                          "--headless", "--duration", "0.1", "--save-camera", str(tmp_path)],
                         capture_output=True, text=True, timeout=120, env=env)
    assert run.returncode == 0, run.stderr
    assert "DISPLAY=:987 cannot be opened" in run.stderr and "Traceback" not in run.stderr
    # Taken on the steps at 10, 40 and 70 ms (the ticks 0.5, 33.8, 67.2 ms), each out 30 ms
    # later and saved at the saver's next look: the third, out at 100 ms, the run's end, is not.
    assert len(list((tmp_path / "corobot").glob("*.png"))) == 2


def test_a_picture_mid_run_leaves_the_simulation_as_it_was():
    """render.py photographs a running simulation from its own SceneGraph context: the
    asynchronous camera (which refuses a geometry change mid-run) goes on, and the run is
    bit for bit the one without the picture."""
    from corobot_drake.sensors import render

    runs = []
    for picture in (False, True):
        sim = make_sim(CIRCLE, camera=True)
        sim.advance(0.2)
        if picture:
            name = render.add_renderer(sim, shadows=False)
            image = render.render(sim, render.chase_view(render.chassis_pose(sim)), 160, 120,
                                  name=name)
            assert image.shape == (120, 160, 3) and image.mean() > 50
        sim.advance(0.2)
        runs.append((sim.robot().pose(), sim.robot().camera_image_time(),
                     sim.robot().camera_image()))
    assert runs[0][:2] == runs[1][:2]
    np.testing.assert_array_equal(runs[0][2], runs[1][2])


@pytest.mark.parametrize("script", ["", "commands: [!SetPose {x: 0.1, y: 0, yaw_deg: 0}], "])
def test_a_simulation_is_freed_when_its_last_reference_goes(script):
    """No reference cycle keeps a Simulation (a Robot is a view of it; the SetPose monitor
    holds the command sources): it is freed by its reference count, in the thread that drops
    it. Left to the cycle collector, which runs in whichever thread allocates next (a
    server's, Ray's), its GL renderer was torn down beside another thread's GL calls: a
    segfault in Mesa's GLX."""
    import gc
    import weakref

    gc.disable()
    try:
        sim = make_sim(f"robots: {{corobot: {{{script}cameras: {{front: {{width: 32, "
                       "height: 24}}}}", camera=True)
        robot = sim.robot()
        robot.drive_distance_async(0.1, 0.5)
        sim.advance_to(0.1)
        assert robot.signal("axle_speeds")
        freed = weakref.ref(sim)
        del sim, robot
        assert freed() is None
    finally:
        gc.enable()


XVFB_STOPPED_WHILE_STARTING = """
import os, shutil, signal, subprocess, sys
from corobot_drake.cli import ctrl_c_stops
from corobot_drake.sensors import xdisplay
if shutil.which("Xvfb") is None or xdisplay._xlib() is None:
    print("no Xvfb"); sys.exit()
started = []
class Recorded(subprocess.Popen):
    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        started.append(self)
xdisplay.subprocess.Popen = Recorded
ctrl_c_stops()
read = xdisplay._read_display_number
def read_then_sigterm(fd):
    number = read(fd)
    os.kill(os.getpid(), signal.SIGTERM)  # taken at the next bytecode, before XOpenDisplay
    return number
xdisplay._read_display_number = read_then_sigterm
try:
    xdisplay.start_xvfb()
except KeyboardInterrupt:
    pass
(server,) = started
print("left running" if server.poll() is None else "stopped")
if server.poll() is None:
    server.kill()
    server.wait()
"""


def test_a_stop_while_the_private_xvfb_starts_stops_the_server():
    """SIGTERM (the entry point's KeyboardInterrupt) after Xvfb reported its display but
    before this process connected to it: the server is stopped with it (`-terminate` would
    never end a server no client has connected to)."""
    run = subprocess.run([sys.executable, "-c", XVFB_STOPPED_WHILE_STARTING],
                         capture_output=True, text=True, timeout=60)
    if run.stdout.strip() == "no Xvfb":
        pytest.skip("no Xvfb or Xlib (tools/setup installs both)")
    assert run.stdout.strip() == "stopped", run.stdout + run.stderr


def test_llvmpipe_keeps_off_the_simulation_s_cores():
    """Mesa's software rasterizer gets the cores beyond the physics and the render worker,
    unless the user chose (`LP_NUM_THREADS` set)."""
    from corobot_drake.sensors.camera import llvmpipe_threads

    for cores, threads in ((1, "0"), (2, "0"), (3, "1"), (16, "14")):
        environ = {}
        llvmpipe_threads(environ, cores)
        assert environ == {"LP_NUM_THREADS": threads}
    environ = {"LP_NUM_THREADS": "4"}
    llvmpipe_threads(environ, 2)
    assert environ == {"LP_NUM_THREADS": "4"}


def _llvmpipe_threads_after_building(*overrides: str) -> tuple[str, str]:
    """(renderer, LP_NUM_THREADS or "None") in a fresh process that built a simulation with a
    camera and `overrides` (Mesa reads the variable when it makes its first GL screen)."""
    code = ("import os; from conftest import make_sim; "
            f"sim = make_sim(*{list(overrides)!r}, camera=True); "
            f"print(sim.station.renderers[{RENDERER_NAME!r}], os.environ.get('LP_NUM_THREADS'))")
    env = {k: v for k, v in os.environ.items() if k != "LP_NUM_THREADS"}
    env["PYTHONPATH"] = os.pathsep.join([str(REPO / "tests"), str(REPO)])
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                          cwd=REPO, timeout=120)
    renderer, threads = done.stdout.split()[-2:]
    if renderer != "RenderEngineGl":
        pytest.skip("no GL renderer here")
    return renderer, threads


def test_a_camera_on_a_render_worker_sets_llvmpipe_s_threads_before_its_first_frame():
    assert _llvmpipe_threads_after_building()[1] == str(
        max(0, len(os.sched_getaffinity(0)) - 2))


@pytest.mark.parametrize("overrides", [
    (SAP,), ("robots: {corobot: {cameras: {front: {output_delay: 0}}}}",)], ids=["sap", "in-place"])
def test_a_camera_rendering_elsewhere_leaves_llvmpipe_s_threads(overrides):
    # Drake's RgbdSensorAsync (SAP) and a render in the simulation's thread are faster with
    # llvmpipe's own threads.
    assert _llvmpipe_threads_after_building(*overrides)[1] == "None"
