"""The run log's conversion of its raw samples (the columns, the largest tilt) and the run-log
sink in a small diagram."""

import math

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

from corobot_drake.sensors.kind import BuiltSensor
from corobot_drake.systems.drive import DriveStatus
from corobot_drake.systems.odometry import CHASSIS_STATE, heading_of, rotation_rows
from corobot_drake.systems.runlog import (
    COLUMNS,
    LOG_PERIOD,
    RAW_COLUMNS,
    SAMPLED,
    add_run_log,
    layout,
    log_rows,
    max_tilt_deg,
    rows_of,
    write_csv,
)
from corobot_drake.systems.stability import TipMargin

DEG = 1e-9  # degrees: acos of a rotation-matrix entry away from +-1


def tilted(roll_deg: float, pitch_deg: float = 0.0, yaw_deg: float = 0.0) -> RigidTransform:
    rpy = RollPitchYaw(*(math.radians(a) for a in (roll_deg, pitch_deg, yaw_deg)))
    return RigidTransform(rpy, [0.3, -0.2, 0.06])


def chassis_state(X: RigidTransform) -> np.ndarray:
    """[qw, qx, qy, qz, x, y, z] of a pose (`odometry.CHASSIS_STATE`), the quaternion scaled
    by 1.5: the readers normalize it (a continuous plant's state drifts off unit norm)."""
    q = X.rotation().ToQuaternion()
    return np.concatenate([1.5 * np.array([q.w(), q.x(), q.y(), q.z()]), X.translation()])


def raw_samples(poses) -> np.ndarray:
    """Run-log raw samples [n, `RAW_COLUMNS`] whose chassis states are `poses`' (the rest 0)."""
    raw = np.zeros((len(poses), len(RAW_COLUMNS)))
    start = RAW_COLUMNS.index(CHASSIS_STATE[0])
    for row, X in zip(raw, poses, strict=True):
        row[start:start + len(CHASSIS_STATE)] = chassis_state(X)
    return raw


def test_max_tilt_is_the_largest_tilt_of_the_samples():
    """Yaw is no tilt; the quaternions (scaled by 1.5) are normalized; roll or pitch, either
    sign; upside down reads 180 (acos near -1); no sample reads 0."""
    assert max_tilt_deg(np.zeros((0, len(RAW_COLUMNS)))) == 0.0
    assert max_tilt_deg(raw_samples([tilted(0.0, yaw_deg=120.0)])) == pytest.approx(0.0, abs=1e-6)
    samples = [tilted(30.0, yaw_deg=120.0), tilted(10.0)]
    assert max_tilt_deg(raw_samples(samples)) == pytest.approx(30.0, abs=DEG)
    samples.append(tilted(0.0, pitch_deg=-45.0))
    assert max_tilt_deg(raw_samples(samples)) == pytest.approx(45.0, abs=DEG)
    samples.append(tilted(180.0))
    assert max_tilt_deg(raw_samples(samples)) == pytest.approx(180.0, abs=1e-6)


def test_max_tilt_is_the_largest_of_each_samples_tilt():
    """The smallest R[2, 2] taken once is the largest of the per-sample tilts, bit for bit:
    acos is monotonic."""
    rng = np.random.default_rng(7)
    poses = [tilted(*angles) for angles in rng.uniform(-60.0, 60.0, (50, 3))]
    each = [max_tilt_deg(raw_samples([X])) for X in poses]
    assert max_tilt_deg(raw_samples(poses)) == max(each)


def drive_status(enabled=1.0, left=0.25, right=-0.5) -> np.ndarray:
    status = DriveStatus.Zero()
    status.enabled, status.power_left, status.power_right = enabled, left, right
    status.target_left, status.target_right = 99.0, -99.0  # not logged
    return status[:]


class FlatMargin:
    """A tip margin of 40 deg whatever the pose (`TipMargin.margin_of_up`'s signature)."""

    def margin_of_up(self, ux, uy, uz):
        return np.full_like(uz, 40.0)


def test_rows_of_makes_the_columns_from_the_raw_samples():
    """Whole ticks, the heading of the (unnormalized) quaternion as `heading_of` of the pose,
    x and y, the held telemetry in `SAMPLED`'s order, the tip margin of the pose."""
    X = RigidTransform(RollPitchYaw(0.02, -0.01, 2.9), [1.25, -0.75, 0.06])
    raw = np.concatenate([drive_status(), [301.9999999999, -12.0000000001], chassis_state(X),
                          np.arange(12.0)])
    assert len(raw) == len(RAW_COLUMNS)
    row = rows_of(np.array([0.5]), raw[None, :], FlatMargin())[0]
    assert len(row) == len(COLUMNS)
    assert row[:5].tolist() == [0.5, 0.25, -0.5, 302.0, -12.0]  # time, powers, whole ticks
    assert (row[5], row[6]) == (1.25, -0.75)
    assert row[7] == pytest.approx(heading_of(X), abs=1e-15)
    assert row[8:20].tolist() == list(np.arange(12.0))
    assert row[20] == 40.0


def test_tip_margin_of_up_matches_the_margin_of_the_pose():
    """The vectorized margin (the run log's) and the port's (a pose) are one formula."""
    margin = TipMargin([0.01, 0.0, 0.05], {"front_left": [0.1, 0.15, 0.0],
                                           "front_right": [0.1, -0.15, 0.0],
                                           "rear_left": [-0.1, 0.15, 0.0],
                                           "rear_right": [-0.1, -0.15, 0.0]})
    poses = [tilted(r, p, y) for r, p, y in ((0, 0, 0), (10, -5, 30), (-20, 15, -100))]
    states = np.array([chassis_state(X) for X in poses])
    R = rotation_rows(states[:, :4])
    vectorized = margin.margin_of_up(R[:, 2, 0], R[:, 2, 1], R[:, 2, 2])
    context = margin.CreateDefaultContext()
    for X, value in zip(poses, vectorized, strict=True):
        margin.get_input_port().FixValue(context, X)
        assert margin.get_output_port().Eval(context)[0] == pytest.approx(value, abs=1e-12)


def test_run_log_samples_every_log_period_and_writes_csv(tmp_path):
    builder = DiagramBuilder()
    X = RigidTransform(RollPitchYaw(0.0, 0.0, -1.0), [0.5, 0.25, 0.06])
    pose = builder.AddSystem(ConstantVectorSource(chassis_state(X)))
    status = builder.AddSystem(ConstantVectorSource(drive_status(left=1.0, right=1.0)))
    ticks = builder.AddSystem(ConstantVectorSource([600.0, 599.9999999999]))
    # The held telemetry ports: 4 loads, 4 slip ratios, 4 slip angles.
    telemetry = {name: builder.AddSystem(ConstantVectorSource(
        np.arange(len(columns)) + 10.0 * k)).get_output_port()
        for k, (name, columns) in enumerate(SAMPLED, start=1)}
    sink = add_run_log(builder, "robot", pose.get_output_port(), status.get_output_port(),
                       ticks.get_output_port(), telemetry)
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(0.1)
    rows = log_rows(sink, simulator.get_context(), FlatMargin())
    assert rows.shape == (11, len(COLUMNS))  # t = 0, 0.01, ..., 0.1
    np.testing.assert_allclose(rows[:, 0], np.arange(11) * LOG_PERIOD, atol=1e-12)
    np.testing.assert_allclose(rows[-1, 1:8], [1.0, 1.0, 600, 600, 0.5, 0.25, -1.0], atol=1e-12)
    np.testing.assert_allclose(rows[-1, 8:], [10, 11, 12, 13, 20, 21, 22, 23, 30, 31, 32, 33,
                                              40], atol=1e-12)  # in SAMPLED's order
    path = tmp_path / "log.csv"
    write_csv(rows, path)
    lines = path.read_text().splitlines()
    assert lines[0] == ",".join(COLUMNS)
    assert lines[-1] == ("0.100000,1,1,600,600,0.500000,0.250000,-1.000000,"
                         "10,11,12,13,20,21,22,23,30,31,32,33,40")


class _RangeKind:
    """A sensor kind's run-log part: two columns, rows 2 and 0 of its state port."""

    field = "rangers"

    def log_columns(self, sensor):
        return (f"range_{sensor}_near", f"range_{sensor}_far")

    def log_port(self, sensor):
        return sensor.system.get_output_port(), (2, 0)


def test_a_sensors_columns_are_its_state_rows_picked_after_the_robots_own(tmp_path):
    """A sensor's `log_columns` follow the robot's, each row of its `log_port` picked by the
    sensor's gain `<robot>.run_log_<field>_<name>`, in the rows and the CSV."""
    builder = DiagramBuilder()
    pose = builder.AddSystem(ConstantVectorSource(chassis_state(tilted(0))))
    status = builder.AddSystem(ConstantVectorSource(drive_status(left=0.5, right=0.5)))
    ticks = builder.AddSystem(ConstantVectorSource([0.0, 0.0]))
    telemetry = {name: builder.AddSystem(ConstantVectorSource(np.zeros(len(columns))))
                 .get_output_port() for name, columns in SAMPLED}
    state = builder.AddSystem(ConstantVectorSource([0.25, 9.0, 0.5]))
    sensor = BuiltSensor(_RangeKind(), "robot", "aft", None, state, None, 10.0)
    sensors = {"rangers": {"aft": sensor}}
    robot_layout = layout(sensor_columns=("range_aft_near", "range_aft_far"))
    sink = add_run_log(builder, "robot", pose.get_output_port(), status.get_output_port(),
                       ticks.get_output_port(), telemetry, layout=robot_layout, sensors=sensors)
    simulator = Simulator(builder.Build())
    simulator.AdvanceTo(0.02)
    rows = log_rows(sink, simulator.get_context(), FlatMargin(), layout=robot_layout)
    assert robot_layout.columns == (*COLUMNS, "range_aft_near", "range_aft_far")
    np.testing.assert_array_equal(rows[:, -2:], [[0.5, 0.25]] * 3)
    path = tmp_path / "log.csv"
    write_csv(rows, path, robot_layout)
    header, *lines = path.read_text().splitlines()
    assert header.endswith(",tip_margin,range_aft_near,range_aft_far")
    assert lines[-1].endswith(",0.500000,0.250000")
    with pytest.raises(ValueError, match="not the layout's"):
        add_run_log(DiagramBuilder(), "robot", pose.get_output_port(),
                    status.get_output_port(), ticks.get_output_port(), telemetry,
                    sensors=sensors)


def test_held_when_read_the_held_ports_are_not_sampled_but_the_contact_states_are():
    """A continuous plant's run log: the row leaves the held telemetry out (made when read:
    `runlog.ContactSamples`), and the station's contact-state sink keeps the plant's state and
    each robot's held chassis velocity every 0.1 s."""
    from pydrake.multibody.plant import MultibodyPlant

    from corobot_drake.systems.contact import held_velocity_name
    from corobot_drake.systems.runlog import (
        CONTACT_STATES,
        HELD,
        HELD_COLUMNS,
        HELD_PERIOD,
        add_contact_states,
        raw_columns,
    )

    builder = DiagramBuilder()
    pose = builder.AddSystem(ConstantVectorSource(chassis_state(RigidTransform())))
    status = builder.AddSystem(ConstantVectorSource(drive_status(left=1.0, right=1.0)))
    ticks = builder.AddSystem(ConstantVectorSource([3.0, 4.0]))
    telemetry = {name: builder.AddSystem(ConstantVectorSource(np.zeros(len(columns))))
                 .get_output_port() for name, columns in SAMPLED}
    sink = add_run_log(builder, "robot", pose.get_output_port(), status.get_output_port(),
                       ticks.get_output_port(), telemetry, held_when_read=True)
    plant = builder.AddSystem(MultibodyPlant(0.0))  # no bodies: an empty state
    plant.Finalize()
    for robot, k in (("a", 0), ("b", 10)):  # each robot's held chassis velocity
        builder.AddNamedSystem(held_velocity_name(robot), ConstantVectorSource(np.arange(6.0) + k))
    add_contact_states(builder, plant, ["a", "b"])
    diagram = builder.Build()
    assert not any(diagram.HasSubsystemNamed(f"robot.run_log_{port}") for port in HELD)
    simulator = Simulator(diagram)
    simulator.AdvanceTo(0.25)
    log = sink.FindLog(simulator.get_context())
    assert log.data().shape == (len(raw_columns(True)), 26)
    assert set(raw_columns(True)) == set(RAW_COLUMNS) - set(HELD_COLUMNS)
    samples = diagram.GetSubsystemByName(CONTACT_STATES).FindLog(simulator.get_context())
    np.testing.assert_allclose(samples.sample_times(), np.arange(3) * HELD_PERIOD, atol=1e-12)
    np.testing.assert_array_equal(samples.data()[:, -1], [*range(6), *range(10, 16)])
    with pytest.raises(ValueError, match="made when read"):
        log_rows(sink, simulator.get_context(), FlatMargin())
