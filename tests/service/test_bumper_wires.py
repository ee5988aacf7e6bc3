"""The bumper on the wires: one CLI run of the Corobot driving its front bumper into the giant
box (0.9 cm away at the start) writing MCAP, a rosbag and the summary; every sample is on
/bumper/front_bumper in both, in frame bumper_front_bumper, the same as the Python `Robot`
reads, pressed on /bumper/front_bumper/pressed in the bag, and /tf_static places the frame at
the mount. The same run recorded for Meshcat's replay shows the press."""

import json
import subprocess
import sys

import pytest
from test_recording import _meshcat_messages, _track, read_mcap

from corobot_drake.config.scenario import load_scenario
from corobot_drake.recording.meshcat_html import RECORDING_FPS
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.sensors.bumper import COLOR, PRESSED_COLOR, default_front
from corobot_drake.simulation import Simulation

pytest.importorskip("rosbags", reason="the [ros2] extra (tools/setup installs it)")

RAM = ("robots: {corobot: {pose: {translation: [-0.55, 0, 0], rotation: !Rpy {deg: [0, 0, 180]}},"
       " bumpers: {front_bumper: {}}, cameras: {front: {rgb: false}},"
       " commands: [!SetPower {left: 1.0, right: 1.0}]}}")
DURATION = 0.3  # s: it meets the box between the samples of 0.08 and 0.1 s
TIMES = [round(0.02 * k, 2) for k in range(15)]
"""s: the samples of the run (the one due at 0.3 s is taken leaving 0.3: after the run)."""
TOPIC, FRAME = "/bumper/front_bumper", "bumper_front_bumper"
PRESSED_TOPIC = f"{TOPIC}/pressed"


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> dict:
    out = tmp_path_factory.mktemp("bumper")
    subprocess.run([sys.executable, "-m", "corobot_drake", str(DEFAULT_SCENARIO), "--headless",
                    "--duration", str(DURATION), "--mcap", str(out / "run.mcap"), "--rosbag",
                    str(out / "bag"), "--summary", str(out / "summary.json"),
                    "--override", RAM], check=True, capture_output=True, timeout=300)
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[RAM]))
    sim.advance_to(DURATION)
    return {"dir": out, "last": sim.robot().reading("front_bumper")}


def _bag(path, *names: str) -> dict[str, list]:
    """{topic: [(log time ns, message), ...]} of the topics `names` of a bag."""
    from rosbags.rosbag2 import Reader

    from corobot_drake.ros2.bus import typestore

    store = typestore()
    topics: dict[str, list] = {}
    with Reader(path) as reader:
        wanted = [c for c in reader.connections if c.topic in names]
        for connection, t_ns, data in reader.messages(connections=wanted):
            topics.setdefault(connection.topic, []).append(
                (t_ns, store.deserialize_cdr(data, connection.msgtype)))
    return topics


def test_each_sample_is_a_corobot_bumper_in_the_mcap(run):
    messages = read_mcap(run["dir"] / "run.mcap")[TOPIC]
    assert [(t, schema) for t, schema, _ in messages] == [(t, "corobot.Bumper") for t in TIMES]
    pressed = [m["pressed"] for _, _, m in messages]
    assert pressed == [t >= 0.1 for t in TIMES]  # from the first sample past the box's face
    for t, _, m in messages:
        assert m["frame_id"] == FRAME
        assert m["timestamp"]["sec"] + m["timestamp"]["nsec"] / 1e9 == pytest.approx(t)
    last = run["last"]
    assert messages[-1][2]["force"] == pytest.approx(last.force, rel=1e-9)
    assert messages[-1][2]["force_vector"] == pytest.approx(
        dict(zip("xyz", last.force_vector, strict=True)), rel=1e-9, abs=1e-9)


def test_each_sample_is_a_wrench_stamped_in_the_bag_on_its_frame(run):
    topics = _bag(run["dir"] / "bag", TOPIC, "/tf_static")
    messages = topics[TOPIC]
    assert [t for t, _ in messages] == [round(t * 1e9) for t in TIMES]
    mcap = read_mcap(run["dir"] / "run.mcap")[TOPIC]
    for (_, m), (_, _, f) in zip(messages, mcap, strict=True):  # one run: the same samples
        assert m.header.frame_id == FRAME
        force = m.wrench.force
        assert (force.x, force.y, force.z) == tuple(f["force_vector"].values())
        assert (m.wrench.torque.x, m.wrench.torque.y, m.wrench.torque.z) == (0.0, 0.0, 0.0)
    (static,) = [m for _, m in topics["/tf_static"]]
    (mount,) = [x for x in static.transforms if x.child_frame_id == FRAME]
    assert mount.header.frame_id == "base_link"
    t = mount.transform.translation
    assert (t.x, t.y, t.z) == pytest.approx(default_front(), abs=1e-12)


def test_each_sample_is_a_bool_pressed_in_the_bag_beside_its_wrench(run):
    """A subscriber need not know the threshold: pressed with every sample, at its time."""
    topics = _bag(run["dir"] / "bag", TOPIC, PRESSED_TOPIC)
    pressed = topics[PRESSED_TOPIC]
    assert [t for t, _ in pressed] == [t for t, _ in topics[TOPIC]]
    mcap = read_mcap(run["dir"] / "run.mcap")[TOPIC]
    assert [m.data for _, m in pressed] == [f["pressed"] for _, _, f in mcap]
    assert [m.data for _, m in pressed] == [t >= 0.1 for t in TIMES]


def test_the_replay_shows_the_press(tmp_path):
    """The recording keys the box's colour at the press (the colour before it one frame
    earlier, so the replay switches rather than fades), and nothing else: never released."""
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[RAM]), record=True)
    sim.advance(0.2)
    sim.save_recording(tmp_path / "run.html")
    (animation,) = [m for m in _meshcat_messages((tmp_path / "run.html").read_text())
                    if m["type"] == "set_animation"]
    path = sim.station.robots["corobot"].sensors["bumpers"]["front_bumper"].extra[
        "meshcat_path"]
    keys = _track(animation, f"{path}/<object>", ".material.color")
    rgb = [[c.r(), c.g(), c.b()] for c in (COLOR, PRESSED_COLOR)]
    assert [k["value"] for k in keys] == rgb
    # Drawn at the end of the step that took the sample of 0.1 s (the continuous plant's 10
    # ms steps): in the frame of 0.11 s (64 frames a second), the black one frame before.
    assert [k["time"] for k in keys] == [int(0.11 * RECORDING_FPS) - 1,
                                         int(0.11 * RECORDING_FPS)]


def test_the_summary_holds_the_last_sample(run):
    summary = json.loads((run["dir"] / "summary.json").read_text())["robots"]["corobot"][
        "sensors"]["bumpers"]["front_bumper"]
    last = run["last"]
    assert summary == {"pressed": True, "force": pytest.approx(last.force, rel=1e-9),
                       "force_vector": pytest.approx(list(last.force_vector), rel=1e-9,
                                                     abs=1e-9),
                       "time": pytest.approx(TIMES[-1])}


def test_the_replay_shows_a_link_bumpers_shell_while_pressed(tmp_path):
    """A Burger whose base link is its bumper drives its body into the giant box: its shell
    (the link's two collision shapes, `/bumper/<robot>/<bumper>`) hidden, then shown from the
    press on; in the replay, its `visible` keyed likewise."""
    burger = ("{robot: burger, pose: {translation: [-0.6896, 0, 0], rotation: !Rpy {deg: [0, 0, "
              "180]}}, lidars: {scan: {enabled: false}}, bumpers: {front: {geometry: link, "
              "X_PB: {base_frame: base, translation: [0.037, 0, 0.082]}}}}")
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[
        f"robots: {{corobot: {{cameras: {{front: {{rgb: false}}}}}}, rammer: {burger}}}"]),
        record=True)
    path = "/bumper/rammer/front"
    meshcat = sim.station.meshcat
    assert meshcat.HasPath(f"{path}/0") and meshcat.HasPath(f"{path}/1")
    assert not meshcat.HasPath(f"{path}/2")
    sim.robot("rammer").set_power(0.5, 0.5)
    sim.advance(0.2)  # its body meets the box between the samples of 0.14 and 0.16 s
    assert sim.robot("rammer").reading("front").pressed
    assert sim.station.diagram.GetSubsystemByName("rammer.bumper.front.meshcat").shown is True
    sim.save_recording(tmp_path / "run.html")
    (animation,) = [m for m in _meshcat_messages((tmp_path / "run.html").read_text())
                    if m["type"] == "set_animation"]
    keys = _track(animation, path, ".visible")
    # Drawn at the end of the CENIC step that took the sample of 0.16 s.
    assert [(k["time"], k["value"]) for k in keys] == [
        (int(0.17 * RECORDING_FPS) - 1, False), (int(0.17 * RECORDING_FPS), True)]
