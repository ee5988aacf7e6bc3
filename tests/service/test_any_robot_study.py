"""A study of robots of three kinds in one scene (the Corobot, the Burger, the Pioneer): each
run's row has every robot's metrics, a per-wheel metric by that robot's own wheels, and a
grid path reaches a robot file's robot's drive. One run at a time in this process (the
engine's worker's `simulate`; Ray is test_study.py's)."""

import pytest

from corobot_drake.robots import robot_spec
from corobot_drake.study.runner import simulate
from corobot_drake.study.spec import expand, load_study, scenario_path

SCENARIO = """
robots:
  corobot: {}
  burger: {robot: burger, pose: {translation: [0, 1, 0]}}
  pioneer: {robot: pioneer, pose: {translation: [0, -1.5, 0]}}
"""
STUDY = """scenario: three.yaml
duration: 0.3
grid:
  robots.pioneer.drive.motor_torque_scaling: [4.0, 6.0]
overrides:
  - "robots: {burger: {commands: [!SetPower {left: 1.0, right: 1.0}]},
              pioneer: {commands: [!SetPower {left: 1.0, right: 1.0}]}}"
metrics: [speed, wheel_loads, ir]
"""


def test_each_robots_metrics_are_its_own(tmp_path):
    (tmp_path / "three.yaml").write_text(SCENARIO)
    (tmp_path / "study.yaml").write_text(STUDY)
    study = load_study(tmp_path / "study.yaml")
    scenario = scenario_path(study, tmp_path / "study.yaml")
    rows = [simulate(study, scenario, run) for run in expand(study)]
    assert [r["status"] for r in rows] == ["ok", "ok"], [r["error"] for r in rows]
    for robot in ("corobot", "burger", "pioneer"):
        loads = {k for k in rows[0] if k.startswith(f"{robot}.wheel_loads.")}
        assert loads == {f"{robot}.wheel_loads.{w}" for w in robot_spec(robot).wheel_names}
    sonars = {k for k in rows[0] if k.startswith("pioneer.ir.")}
    assert len(sonars) == 8 and not any(k.startswith("burger.ir.") for k in rows[0])
    # Full power for 0.3 s, past the slew: each Pioneer rolls at its scaling x 0.1075 m
    # (the soft tyres' effective radius ~1% less: 2%).
    for row, scaling in zip(rows, (4.0, 6.0), strict=True):
        assert row["pioneer.speed"] == pytest.approx(scaling * 0.1075, rel=0.02)
    assert rows[0]["burger.speed"] == pytest.approx(0.22, rel=0.02)
