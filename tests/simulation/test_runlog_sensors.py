"""The run log carries each sensor's columns (`SensorKind.log_columns`) after the robot's own:
the default Corobot's IR sensors' distances and the lidar Corobot's nearest range, as
`Robot.reading` has them."""

import math

import numpy as np
import pytest

from conftest import REPO
from corobot_drake.config.scenario import load_scenario
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.simulation import Simulation, quiet_drake_warnings
from corobot_drake.systems.runlog import COLUMNS
from lab.bench import NO_CAMERA

LOOKS = (0.1, 0.2, 0.3)
"""s: when the readings are read (each a run-log row's time)."""


def test_the_ir_sensors_columns_are_their_readings_at_the_rows_times(tmp_path):
    """At rest, the front IR sees nothing within its range (0.762 m) and the rear one the
    giant box 29 in behind the robot (0.62865 m, SPEC); each row at a look holds what
    `Robot.reading` gave then, and the CSV has the columns after the robot's own."""
    quiet_drake_warnings()
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[NO_CAMERA]))
    robot = sim.robot("corobot")
    read = {}
    for t in LOOKS:
        sim.advance_to(t)
        read[t] = {f"ir_{name}": robot.reading(name, kind="ir_sensors").raw
                   for name in ("front", "rear")}
    rows = robot.run_log()
    columns = robot.log_columns
    assert columns == (*COLUMNS, "ir_front", "ir_rear")
    for t, values in read.items():
        (row,) = rows[abs(rows[:, 0] - t) < 1e-9]
        assert {c: row[columns.index(c)] for c in values} == values, t
    # The chassis settles on its wheels by well under a micrometre (0.1 nm seen).
    assert read[0.3] == {"ir_front": pytest.approx(0.762, abs=1e-6),
                         "ir_rear": pytest.approx(0.62865, abs=1e-6)}
    robot.write_log(tmp_path / "run.csv")
    header, *lines = (tmp_path / "run.csv").read_text().splitlines()
    assert header.split(",")[-2:] == ["ir_front", "ir_rear"]
    assert [float(v) for v in lines[-1].split(",")[-2:]] == pytest.approx([0.762, 0.62865],
                                                                           abs=1e-6)


def test_a_lidars_columns_are_its_latest_scans_nearest_range_and_bearing():
    """The lidar Corobot at rest in its room: each row at a look holds the nearest measured
    range of the scan `Robot.reading` gave then (10 Hz: the scan at the look itself) and that
    ray's bearing; the pillar at (1, -1), radius 0.15, is the nearest thing: sqrt(2) - 0.15 m
    from the robot's centre, less the lidar's offset, at about -45 degrees."""
    quiet_drake_warnings()
    sim = Simulation(load_scenario(REPO / "scenarios" / "corobot_lidar.yaml",
                                   overrides=[NO_CAMERA]))
    robot = sim.robot("corobot")
    read = {}
    for t in LOOKS:
        sim.advance_to(t)
        scan = robot.reading("top")
        i = int(np.nanargmin(np.where(np.isfinite(scan.ranges), scan.ranges, np.inf)))
        read[t] = {"lidar_top_nearest": scan.ranges[i],
                   "lidar_top_bearing": scan.bearings()[i]}
    rows, columns = robot.run_log(), robot.log_columns
    assert columns[-2:] == ("lidar_top_nearest", "lidar_top_bearing")
    for t, values in read.items():
        (row,) = rows[abs(rows[:, 0] - t) < 1e-9]
        assert {c: row[columns.index(c)] for c in values} == values, t
    # The lidar sits a few cm from the centre: within 0.1 m and 5 degrees of the centre's view.
    assert read[0.3]["lidar_top_nearest"] == pytest.approx(2**0.5 - 0.15, abs=0.1)
    assert math.degrees(read[0.3]["lidar_top_bearing"]) == pytest.approx(-45.0, abs=5.0)
