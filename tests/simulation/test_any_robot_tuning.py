"""The tuning tools on a robot other than the Corobot (the Burger: wheel radius 0.033 m,
track 0.160 m, 4096 encoder ticks per revolution, 0.22 m/s at power 1), as a user runs them
on their own robot's scenario: the drive-log fit finds the drive parameters a simulated log
was made with, the top-speed tuning starts from the robot's own top speed, the odometry
calibration reads its encoders and compares with its own radius and track."""

import pytest

from conftest import load_tool
from corobot_drake.config.scenario import load_scenario
from corobot_drake.resources import SCENARIOS_DIR
from corobot_drake.simulation import Simulation

SCENARIO = str(SCENARIOS_DIR / "burger.yaml")
PIONEER = str(SCENARIOS_DIR / "pioneer.yaml")
"""The Pioneer: a skid steer of four 0.1075 m wheels, track 0.40 m, 600 ticks, 0.7 m/s."""


def test_the_drive_log_fit_finds_the_burgers_drive_again(tmp_path, capsys):
    main = load_tool("fit_drive_log").main
    log = tmp_path / "burger.csv"
    assert main([str(log), "--simulate", "6", "15", "--scenario", SCENARIO,
                 "--plot", str(tmp_path / "fit.png")]) == 0
    out = capsys.readouterr().out
    scaling = float(out.split("motor_torque_scaling: ")[-1].split()[0])
    slew = float(out.split("slew_rate: ")[-1].split()[0])
    # Read with the Burger's 4096 ticks (600 would read 6.8x the speed); the Corobot's fit
    # is within 0.1% (test_sysid.py): the Burger's within 1%.
    assert scaling == pytest.approx(6.0, rel=0.01)
    assert slew == pytest.approx(15.0, rel=0.01)


@pytest.mark.parametrize(("scenario", "started", "top_speed"), [
    # 0.22 / 0.033 rad/s at power 1: rolling without slip gives the top speed.
    (SCENARIO, "tuning burger: target 0.2200 m/s, start scaling 6.66667", 0.22),
    # The four-wheel Pioneer: its own 0.7 m/s (0.7 / 0.1075), its four tyres rolling
    # without slip on the straight.
    (PIONEER,
     "tuning pioneer: target 0.7000 m/s, start scaling 6.51163", 0.7),
], ids=["burger", "pioneer"])
def test_the_top_speed_tuning_starts_from_the_robots_own(tmp_path, capsys, scenario, started,
                                                         top_speed):
    main = load_tool("tune_motor_torque_scaling").main
    main(["--scenario", scenario, "--settle", "0.6", "--measure", "0.3",
          "--max-iterations", "1", "--plot", str(tmp_path / "t.png")])
    out = capsys.readouterr().out
    assert started in out
    measured = float(out.split("top speed ")[1].split()[0])
    assert measured == pytest.approx(top_speed, rel=0.02)


def drive_log(scenario: str, robot_name: str, powers, folder) -> str:
    """The run log (a CSV in `folder`) of `robot_name` in `scenario` driven 1 s at each of
    `powers` ((left, right) pairs)."""
    sim = Simulation(load_scenario(scenario))
    robot = sim.robot(robot_name)
    for left, right in powers:
        robot.set_power(left, right)
        sim.advance(1.0)
    log = folder / f"{robot_name}.csv"
    robot.write_log(log)
    return str(log)


def calibrated(log: str, scenario: str, tmp_path, capsys, monkeypatch):
    """(what calibrate_odometry printed, its effective wheel radius m, its effective track m)
    for `log` with a shipped `scenario` named from another folder."""
    main = load_tool("calibrate_odometry").main
    monkeypatch.chdir(tmp_path)  # a shipped scenario by its name, from any folder
    assert main([log, "--scenario", scenario, "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    radius = float(out.split("effective_wheel_radius: ")[1].split()[0])
    track = float(out.split("effective_track_width: ")[1].split()[0])
    return out, radius, track


def test_the_odometry_calibration_reads_the_robots_encoders(tmp_path, capsys, monkeypatch):
    log = drive_log(SCENARIO, "burger", ((0.8, 0.8), (-0.6, 0.6), (0.8, 0.8), (0.6, -0.6)),
                    tmp_path)
    out, radius, track = calibrated(log, "burger.yaml", tmp_path, capsys, monkeypatch)
    assert "(nominal 0.033000)" in out and "(geometric 0.16000)" in out
    # A two-wheel robot rolls at its radius and turns about its track, less the tyres'
    # compression and scrub: within 3% and 10%.
    assert radius == pytest.approx(0.033, rel=0.03)
    assert track == pytest.approx(0.160, rel=0.10)


def test_the_odometry_calibration_reads_a_skid_steers_encoders(tmp_path, capsys, monkeypatch):
    """On the Pioneer the calibration compares with its own radius and track; a skid steer
    turns about a wider effective track than its wheels' (they scrub sideways: the
    Corobot's is 1.7x its own), so only the radius is held close."""
    log = drive_log(PIONEER, "pioneer", ((0.5, 0.5), (-0.5, 0.5), (0.5, 0.5), (0.5, -0.5)),
                    tmp_path)
    out, radius, track = calibrated(log, "pioneer.yaml", tmp_path, capsys, monkeypatch)
    assert "(nominal 0.107500)" in out and "(geometric 0.40000)" in out
    assert radius == pytest.approx(0.1075, rel=0.03)
    assert track > 0.40
