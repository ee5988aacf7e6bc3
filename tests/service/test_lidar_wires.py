"""The lidar on the wires: one CLI run of scenarios/corobot_lidar.yaml writing MCAP, a rosbag
and the summary; every scan is on /scan/top in both, in frame lidar_top, the same ranges the
Python `Robot` reads, and /tf_static places the frame on the platform."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest
from test_recording import read_mcap

from corobot_drake.config.scenario import load_scenario
from corobot_drake.resources import SCENARIOS_DIR
from corobot_drake.simulation import Simulation

pytest.importorskip("rosbags", reason="the [ros2] extra (tools/setup installs it)")

SCENARIO = SCENARIOS_DIR / "corobot_lidar.yaml"
NOISY = ("robots: {corobot: {cameras: {front: {rgb: false}}, "
         "lidars: {top: {noise_std: 0.01, dropout: 0.05, range_max: 2.5}}}}")
"""Noise, dropouts (NaN) and misses (+inf beyond 2.5 m): every kind of range on the wires."""
TIMES = (0.0, 0.1, 0.2, 0.3)
"""s: the scans of a 0.35 s run."""
STEPPING = 1e-6
"""m: the in-process run stops 1 ms after each scan to read it, the CLI's does not: CENIC's
steps differ and the robot's pose with them, by ~1e-10 m here (the noise and dropouts are
the same: a function of the seed and the scan)."""


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> dict:
    out = tmp_path_factory.mktemp("lidar")
    subprocess.run([sys.executable, "-m", "corobot_drake", str(SCENARIO), "--headless",
                    "--duration", "0.35", "--mcap", str(out / "run.mcap"), "--rosbag",
                    str(out / "bag"), "--summary", str(out / "summary.json"),
                    "--override", NOISY], check=True, capture_output=True, timeout=300)
    sim = Simulation(load_scenario(SCENARIO, overrides=[NOISY]))
    scans = []
    for t in TIMES:
        sim.advance_to(t + 0.001)  # the scan due at t is taken leaving t
        scans.append(sim.robot().reading("top"))
    return {"dir": out, "scans": scans}


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


def test_each_scan_is_a_foxglove_laser_scan_in_the_mcap(run):
    messages = read_mcap(run["dir"] / "run.mcap")["/scan/top"]
    assert [(t, schema) for t, schema, _ in messages] == [
        (t, "foxglove.LaserScan") for t in TIMES]
    for (_, _, m), scan in zip(messages, run["scans"], strict=True):
        assert (m.frame_id, m.start_angle, m.end_angle) == ("lidar_top", -math.pi,
                                                            scan.angle_max)
        assert m.timestamp.seconds + m.timestamp.nanos / 1e9 == pytest.approx(scan.time)
        np.testing.assert_allclose(np.array(m.ranges), scan.ranges, rtol=0, atol=STEPPING)


def test_each_scan_is_a_sensor_msgs_laser_scan_in_the_bag_on_its_frame(run):
    topics = _bag(run["dir"] / "bag", "/scan/top", "/tf_static")
    messages = topics["/scan/top"]
    assert [t for t, _ in messages] == [round(t * 1e9) for t in TIMES]
    ranges = np.array(run["scans"][-1].ranges)
    assert np.isnan(ranges).any() and np.isposinf(ranges).any()  # both reach the wires
    for (_, m), scan in zip(messages, run["scans"], strict=True):
        assert m.header.frame_id == "lidar_top" and m.ranges.dtype == np.float32
        assert (m.angle_increment, m.scan_time, m.range_max) == pytest.approx(
            (math.radians(1.0), 0.1, 2.5))
        np.testing.assert_allclose(m.ranges, np.float32(scan.ranges), rtol=1e-6, atol=STEPPING)
    mcap = read_mcap(run["dir"] / "run.mcap")["/scan/top"]
    for (_, m), (_, _, f) in zip(messages, mcap, strict=True):  # one run: the same scans
        np.testing.assert_array_equal(m.ranges, np.float32(f.ranges))
    (static,) = [m for _, m in topics["/tf_static"]]
    (mount,) = [x for x in static.transforms if x.child_frame_id == "lidar_top"]
    assert mount.header.frame_id == "base_link"
    t = mount.transform.translation
    assert (t.x, t.y, t.z) == pytest.approx((0.0, 0.0, 0.27225), abs=1e-12)


def test_the_summary_holds_the_last_scan_in_brief(run):
    brief = json.loads((run["dir"] / "summary.json").read_text())["robots"]["corobot"][
        "sensors"]["lidars"]["top"]
    r = np.array(run["scans"][-1].ranges)
    assert brief == {"time": 0.3, "rays": 360, "in_range": int(np.isfinite(r).sum()),
                     "dropped": int(np.isnan(r).sum()), "too_near": 0,
                     "nearest": pytest.approx(float(np.nanmin(r[np.isfinite(r)]))),
                     "nearest_bearing": pytest.approx(-math.pi / 4, abs=0.1)}
