"""Every robot on the wires: one CLI run of the three shipped robots side by side (the
Corobot, the Burger's two wheels and caster, the Pioneer's four skid-steer wheels), writing
the summary, the run logs, MCAP and a rosbag. Each robot's wheels are its own everywhere: by
name in the summary, one run-log column each, its joints in /joint_states, one value each in
the contact telemetry; its /robot_description is its own model; /tf has its base_link and
its wheels' frames."""

import csv
import json
import subprocess
import sys

import pytest
from test_lidar_wires import _bag
from test_recording import read_mcap

from corobot_drake.robots import robot_spec
from corobot_drake.ros2.urdf import robot_urdf
from corobot_drake.signals import wheel_short

pytest.importorskip("rosbags", reason="the [ros2] extra (tools/setup installs it)")

ROBOTS = ("corobot", "burger", "pioneer")
SCENARIO = """
robots:
  corobot: {commands: [!SetPower {left: 0.5, right: 0.5}]}
  burger: {robot: burger, pose: {translation: [0, 1, 0]},
           commands: [!SetPower {left: 0.5, right: 0.5}]}
  pioneer: {robot: pioneer, pose: {translation: [0, -1.5, 0]},
            commands: [!SetPower {left: 0.5, right: 0.5}]}
"""
"""Each robot driving forward at half power, apart (a 0.3 s run)."""


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> dict:
    out = tmp_path_factory.mktemp("robots")
    (out / "three.yaml").write_text(SCENARIO)
    subprocess.run([sys.executable, "-m", "corobot_drake", str(out / "three.yaml"),
                    "--headless", "--duration", "0.3", "--summary", str(out / "summary.json"),
                    "--log", str(out / "run.csv"), "--mcap", str(out / "run.mcap"),
                    "--rosbag", str(out / "bag")], check=True, capture_output=True,
                   timeout=300)
    return {"dir": out, "summary": json.loads((out / "summary.json").read_text())["robots"],
            "mcap": read_mcap(out / "run.mcap")}


@pytest.fixture(scope="module")
def bag(run) -> dict:
    names = [f"/{r}/{t}" for r in ROBOTS for t in ("joint_states", "robot_description",
                                                   "wheel_loads", "wheel_slip")]
    return _bag(run["dir"] / "bag", "/tf", *names)


@pytest.mark.parametrize("robot", ROBOTS)
def test_the_summary_and_run_log_are_by_its_wheels(run, robot):
    spec, summary = robot_spec(robot), run["summary"][robot]
    assert list(summary["wheels"]) == list(spec.wheel_names)
    assert list(summary["commanded_power"]) == list(spec.wheel_names)
    assert len(summary["wheel_loads_N"]) == len(spec.wheels)
    # Every wheel turns forward at half power (0.3 s: past the slew, rad/s).
    assert all(v > 1.0 for v in summary["wheels"].values())
    with open(run["dir"] / f"run.{robot}.csv") as f:
        header = next(csv.reader(f))
    short = wheel_short(spec.wheel_names)
    assert [c for c in header if c.startswith("load_")] == [f"load_{s}" for s in short]
    assert header[:8] == ["time", "left_power", "right_power", "left_ticks", "right_ticks",
                          "x", "y", "yaw"]


@pytest.mark.parametrize("robot", ROBOTS)
def test_the_mcap_has_its_joints_and_wheels(run, robot):
    spec = robot_spec(robot)
    _, _, joints = run["mcap"][f"/{robot}/joint_states"][-1]
    assert [j.name for j in joints.joints] == [f"{robot}/{j}" for j in spec.wheel_joints]
    _, _, loads = run["mcap"][f"/{robot}/wheel_loads"][-1]
    assert list(loads["wheels"]) == list(spec.wheel_names)
    _, _, drive = run["mcap"][f"/{robot}/drive_state"][-1]
    assert list(drive["wheels"]) == list(spec.wheel_names)


@pytest.mark.parametrize("robot", ROBOTS)
def test_the_bag_has_its_description_joints_and_frames(bag, robot):
    spec = robot_spec(robot)
    ((_, description),) = bag[f"/{robot}/robot_description"]
    assert description.data == robot_urdf(spec, robot)
    _, joints = bag[f"/{robot}/joint_states"][-1]
    assert list(joints.name) == list(spec.wheel_joints)
    assert len(joints.position) == len(joints.velocity) == len(spec.wheels)
    for topic in ("wheel_loads", "wheel_slip"):
        _, message = bag[f"/{robot}/{topic}"][-1]
        assert list(message.wheel_names) == list(spec.wheel_names)
        assert message.header.frame_id == f"{robot}/base_link"
    _, tf = bag["/tf"][-1]
    frames = {t.child_frame_id for t in tf.transforms if t.child_frame_id.startswith(robot)}
    assert frames == {f"{robot}/base_link", *(f"{robot}/{w.link}" for w in spec.wheels)}
