"""TiltMonitor and the run log's RunLogSample on their own (fixed inputs, evaluated outputs,
updates stepped by a Simulator on the lone system), and the run-log sink in a small diagram."""

import math

import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantValueSource, ConstantVectorSource

from conftest import Stepper
from corobot_drake.systems.drive import DriveStatus
from corobot_drake.systems.monitor import TiltMonitor
from corobot_drake.systems.runlog import (
    COLUMNS,
    LOG_PERIOD,
    SAMPLE_COLUMNS,
    TELEMETRY,
    LogSample,
    RunLogSample,
    add_run_log,
    log_rows,
    write_csv,
)

DEG = 1e-9  # degrees: acos of a rotation-matrix entry away from +-1


def tilted(roll_deg: float, pitch_deg: float = 0.0, yaw_deg: float = 0.0) -> RigidTransform:
    rpy = RollPitchYaw(*(math.radians(a) for a in (roll_deg, pitch_deg, yaw_deg)))
    return RigidTransform(rpy, [0.3, -0.2, 0.06])


def test_tilt_monitor_holds_the_largest_sampled_tilt():
    period = 0.01
    s = Stepper(TiltMonitor(period), period)
    assert s.output("max_tilt_deg")[0] == 0.0  # nothing sampled yet
    s.fix("chassis_pose", tilted(30.0, yaw_deg=120.0))  # yaw is no tilt
    s.tick()
    assert s.output("max_tilt_deg")[0] == pytest.approx(30.0, abs=DEG)
    s.fix("chassis_pose", tilted(10.0))
    s.tick(5)
    assert s.output("max_tilt_deg")[0] == pytest.approx(30.0, abs=DEG)
    s.fix("chassis_pose", tilted(0.0, pitch_deg=-45.0))
    s.tick()
    assert s.output("max_tilt_deg")[0] == pytest.approx(45.0, abs=DEG)
    s.fix("chassis_pose", tilted(180.0))  # upside down
    s.tick()
    assert s.output("max_tilt_deg")[0] == pytest.approx(180.0, abs=1e-6)  # acos near -1


def drive_status(enabled=1.0, left=0.25, right=-0.5) -> np.ndarray:
    status = DriveStatus.Zero()
    status.enabled, status.power_left, status.power_right = enabled, left, right
    status.target_left, status.target_right = 99.0, -99.0  # not logged
    return status[:]


def test_run_log_sample_reads_pose_status_and_encoders_by_name():
    system = RunLogSample()
    context = system.CreateDefaultContext()
    X = RigidTransform(RollPitchYaw(0.02, -0.01, 2.9), [1.25, -0.75, 0.06])
    system.GetInputPort("chassis_pose").FixValue(context, X)
    system.GetInputPort("drive_status").FixValue(context, drive_status())
    system.GetInputPort("encoder_ticks").FixValue(context, [301.9999999999, -12.0000000001])
    sample = LogSample(system.GetOutputPort("sample").Eval(context))
    assert LogSample.get_fields() == SAMPLE_COLUMNS[1:]
    assert (sample.left_power, sample.right_power) == (0.25, -0.5)
    assert (sample.left_ticks, sample.right_ticks) == (302.0, -12.0)  # whole ticks
    assert (sample.x, sample.y) == (1.25, -0.75)
    assert sample.yaw == pytest.approx(2.9, abs=1e-12)


def test_run_log_samples_every_log_period_and_writes_csv(tmp_path):
    builder = DiagramBuilder()
    X = RigidTransform(RollPitchYaw(0.0, 0.0, -1.0), [0.5, 0.25, 0.06])
    pose = builder.AddSystem(ConstantValueSource(AbstractValue.Make(X)))
    status = builder.AddSystem(ConstantVectorSource(drive_status(left=1.0, right=1.0)))
    ticks = builder.AddSystem(ConstantVectorSource([600.0, 599.9999999999]))
    # The telemetry ports: 4 loads, 4 slip ratios, 4 slip angles, the tip margin.
    telemetry = {name: builder.AddSystem(ConstantVectorSource(
        np.arange(len(columns)) + 10.0 * k)).get_output_port()
        for k, (name, columns) in enumerate(TELEMETRY, start=1)}
    sink = add_run_log(builder, "robot", pose.get_output_port(), status.get_output_port(),
                       ticks.get_output_port(), telemetry)
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(0.1)
    rows = log_rows(sink, simulator.get_context())
    assert rows.shape == (11, len(COLUMNS))  # t = 0, 0.01, ..., 0.1
    np.testing.assert_allclose(rows[:, 0], np.arange(11) * LOG_PERIOD, atol=1e-12)
    np.testing.assert_allclose(rows[-1, 1:8], [1.0, 1.0, 600, 600, 0.5, 0.25, -1.0], atol=1e-12)
    np.testing.assert_allclose(rows[-1, 8:], [10, 11, 12, 13, 20, 21, 22, 23, 30, 31, 32, 33,
                                              40], atol=1e-12)  # in TELEMETRY's order
    path = tmp_path / "log.csv"
    write_csv(rows, path)
    lines = path.read_text().splitlines()
    assert lines[0] == ",".join(COLUMNS)
    assert lines[-1] == ("0.100000,1,1,600,600,0.500000,0.250000,-1.000000,"
                         "10,11,12,13,20,21,22,23,30,31,32,33,40")
