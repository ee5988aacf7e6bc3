"""The signals table's places (`signals.put_value`, `read_value`) and the publishers' shared
bases (`recording.looks.RobotStateLooks`) and the one sensor publisher (`SensorPublisher`,
on the IR and camera kinds' schedules) alone."""

import dataclasses as dc
import math
import types

import numpy as np
import pytest
from pydrake.common.value import Value
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.math import SpatialVelocity
from pydrake.systems.framework import DiagramBuilder, LeafSystem
from pydrake.systems.sensors import ImageRgba8U

from corobot_drake import signals
from corobot_drake.config.sensors import IrSensorConfig, default_camera_config
from corobot_drake.recording.looks import RobotStateLooks, SensorPublisher
from corobot_drake.sensors.ir_sensor import DISTANCE, SCAN_TIME
from corobot_drake.sensors.kind import BuiltSensor
from corobot_drake.systems.odometry import DriveState, WheelState


def test_places_write_and_read_back_every_form():
    """A float, a dict at a path (key by key), by key (`*`), by index (`#`), a list (`[]`)
    and degrees (`|deg`): each reads back what was written."""
    value = {"front_left": 1.5, "front_right": -2.0}
    tree: dict = {"drive": {"wheels": {"front_left": {"other": 1}}}}
    for place in ("drive.wheels.*.speed", "ir.*_ir.raw", "list[]", "plain", "deg.*|deg"):
        signals.put_value(tree, place, value)
        assert signals.read_value(tree, place, tuple(value)) == pytest.approx(value), place
    assert tree["drive"]["wheels"]["front_left"] == {"other": 1, "speed": 1.5}  # merged
    assert tree["ir"]["front_right_ir"]["raw"] == -2.0
    assert tree["list"] == [1.5, -2.0] and tree["plain"] == value
    assert tree["deg"]["front_left"] == pytest.approx(math.degrees(1.5))
    signals.put_value(tree, "one", 0.25)
    assert signals.read_value(tree, "one", None) == 0.25
    messages = {"velocity": np.array([3.0, 4.0]), "wheels": [{"v": 5.0}, {"v": 6.0}]}
    assert signals.read_value(messages, "velocity.#", ("a", "b")) == {"a": 3.0, "b": 4.0}
    assert signals.read_value(messages, "wheels.#.v", ("a", "b")) == {"a": 5.0, "b": 6.0}
    with pytest.raises(ValueError, match="read only"):
        signals.put_value(tree, "odom|pose", value)


def test_a_pose_place_reads_drakes_roll_pitch_yaw():
    rpy = RollPitchYaw(0.1, -0.2, 2.5)
    q = rpy.ToQuaternion()
    pose = {"position": {"x": 1.0, "y": 2.0, "z": 3.0},
            "orientation": {"w": q.w(), "x": q.x(), "y": q.y(), "z": q.z()}}
    read = signals.read_value({"p": pose}, "p|pose", signals.POSE_FIELDS)
    assert read == pytest.approx({"x": 1.0, "y": 2.0, "z": 3.0, "roll": 0.1, "pitch": -0.2,
                                  "yaw": 2.5}, abs=1e-12)


def test_the_table_is_consistent():
    """Every field has one change threshold, every run-log column one owner, and every own
    topic carries signals alike (`own_topics` checks)."""
    signals.change_thresholds()
    columns = [c for s in signals.SIGNALS.values() for c in s.log_columns]
    assert len(columns) == len(set(columns))
    assert set(signals.own_topics()) == {"wheel_loads", "wheel_slip", "tip_margin"}


def test_robot_state_looks_read_the_chassis_in_base_link():
    """The chassis (body 1) at yaw 90 deg moving along world +y and turning: its velocity
    in base_link is forward (+x) and its yaw rate about +z; the wheel state splits into
    angles and rates; the drive state passes through."""
    looks = RobotStateLooks(chassis_index=1)
    context = looks.CreateDefaultContext()
    X_WB = RigidTransform(RollPitchYaw(0, 0, math.pi / 2), [1.0, 2.0, 0.0])
    looks.GetInputPort("body_poses").FixValue(context, [RigidTransform(), X_WB])
    looks.GetInputPort("body_spatial_velocities").FixValue(context, [
        SpatialVelocity.Zero(), SpatialVelocity(w=[0, 0, 0.5], v=[0, 0.3, 0])])
    looks.GetInputPort("wheel_state").FixValue(context, np.arange(8.0))
    state = DriveState(0.0, True, 0.3, 20.0, {"front_left": WheelState(0.1, 0.2)},
                       (0.0, 0.0, 0.0), 0.0)
    looks.GetInputPort("drive_state").FixValue(context, state)
    X, linear, angular = looks.chassis(context)
    assert X.IsExactlyEqualTo(X_WB)
    np.testing.assert_allclose(linear, [0.3, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(angular, [0.0, 0.0, 0.5], atol=1e-15)
    angles, rates = looks.wheel_state(context)
    assert angles.tolist() == [0, 1, 2, 3] and rates.tolist() == [4, 5, 6, 7]
    assert looks.drive_state(context) == state


class _Frame(LeafSystem):
    """A camera's outputs, for a publisher to read: `rgb_image` (4 x 3, every byte 7) and
    `image_time` (input `captured`, s)."""

    def __init__(self):
        super().__init__()
        image = ImageRgba8U(4, 3)
        image.mutable_data[:] = 7
        self.DeclareAbstractOutputPort("rgb_image", lambda: Value(image),
                                       lambda c, v: v.set_value(image))
        self.DeclareVectorOutputPort("image_time", 1, lambda c, o: o.SetFromVector(
            self.get_input_port().Eval(c)))
        self.DeclareVectorInputPort("captured", 1)


@pytest.mark.parametrize("captured, look", [
    (math.nan, None),  # no frame: nothing handed on
    (0.015, 0.05),     # out at 0.045: the look at 0.05 sees [0.04, 0.05)
    (0.010, 0.05),     # out at 0.04: not the look at 0.04 (it runs before the updates at 0.04)
    (0.0, 0.04),
])
def test_a_camera_s_publisher_hands_on_a_frame_once_at_the_look_after_it_comes_out(captured,
                                                                                   look):
    """A frame comes out `delay` (30 ms) after its capture; of the looks every 10 ms over
    0.1 s (the camera kind's: its `look`), only the first after that instant hands it on,
    with its capture time and image."""
    from pydrake.systems.analysis import Simulator

    from corobot_drake.sensors.camera import CameraKind

    frame = _Frame()
    camera = types.SimpleNamespace(image=frame.GetOutputPort("rgb_image"),
                                   image_time=frame.GetOutputPort("image_time"), delay=0.03,
                                   look=0.01, worker=None)  # frames render when read
    sensor = BuiltSensor(CameraKind(), "r", "front", default_camera_config(), frame,
                         camera.image, 30.0, extra={"camera": camera})
    handed = []  # (look time, capture time, first byte)
    publisher = SensorPublisher(sensor, lambda r: handed.append(
        (simulator.get_context().get_time(), r.time, int(r.image.data[0, 0, 0]))))
    builder = DiagramBuilder()
    builder.AddSystem(frame)
    builder.AddSystem(publisher)
    publisher.connect(builder)
    builder.ExportInput(frame.get_input_port(), "captured")
    diagram = builder.Build()
    simulator = Simulator(diagram)
    diagram.get_input_port().FixValue(simulator.get_mutable_context(), [captured])
    simulator.AdvanceTo(0.1)
    expected = [] if look is None else [(look, captured, 7)]
    assert [(pytest.approx(t, abs=1e-12), c, v) for t, c, v in handed] == expected


@pytest.mark.parametrize("step, scanned, look", [
    (0.0, math.nan, None),  # no scan yet: nothing handed on
    (0.0, 0.05, 0.1),       # a look and a scan at 0.05 (the scans' schedule): the look ran first
    (0.01, 0.05, 0.06),     # on a continuous plant's steps: the next step's look
])
def test_an_ir_sensor_s_publisher_hands_on_a_scan_once_at_the_look_after_it(step, scanned, look):
    """The looks run on the sensor's event schedule (the IR kind's `looks`); over 0.2 s only
    the first look after the scan hands it on, with its time and the sensor's limits."""
    from pydrake.systems.analysis import Simulator

    from corobot_drake.sensors.ir_sensor import IrSensor, IrSensorKind

    config = IrSensorConfig()
    system = IrSensor(config, None, [], step=step)
    sensor = BuiltSensor(IrSensorKind(), "r", "front", config, system,
                         system.GetOutputPort("reading"), config.scan_rate_hz)
    handed = []  # (look time, scan)
    publisher = SensorPublisher(sensor, lambda r: handed.append((context.get_time(), r)))
    simulator = Simulator(publisher)
    context = simulator.get_mutable_context()
    state = np.zeros(system.state_size)
    state[SCAN_TIME], state[DISTANCE] = scanned, 0.3
    publisher.GetInputPort("scan_state").FixValue(context, state)
    simulator.AdvanceTo(0.2)
    if look is None:
        assert handed == []
        return
    ((when, scan),) = handed
    assert when == pytest.approx(look, abs=1e-12)
    assert (scan.time, scan.range, scan.max_range) == (scanned, 0.3, config.maximum_range)
    assert scan.field_of_view == pytest.approx(math.radians(config.dispersion_cone_angle))
    assert scan.ends.shape == (system.num_rays, 3)


class _Sample(LeafSystem):
    """A kind's sensor whose `reading` port (abstract) is its reading: a `_Value` taken at
    input `taken` (s)."""

    def __init__(self):
        super().__init__()
        self.DeclareVectorInputPort("taken", 1)
        self.DeclareAbstractOutputPort(
            "reading", lambda: Value(_Value(math.nan, 0.0)),
            lambda c, v: v.set_value(_Value(self.get_input_port().Eval(c)[0], 2.5)))


@dc.dataclass(frozen=True)
class _Value:
    time: float
    value: float


def test_a_kind_s_publisher_by_default_reads_its_reading_port_at_its_rate():
    """A kind that overrides none of the publisher's hooks: the publisher's one input is its
    `reading` port, it looks every 1 / rate s from 0, and hands on the reading once, at the
    first look after its time."""
    from pydrake.systems.analysis import Simulator

    from corobot_drake.sensors.kind import SensorKind

    sample = _Sample()
    sensor = BuiltSensor(SensorKind(), "r", "s", None, sample, sample.get_output_port(), 10.0)
    handed = []  # (look time, reading)
    publisher = SensorPublisher(sensor, lambda r: handed.append(
        (simulator.get_context().get_time(), r)))
    assert [publisher.get_input_port(i).get_name()
            for i in range(publisher.num_input_ports())] == ["reading"]
    builder = DiagramBuilder()
    builder.AddSystem(sample)
    builder.AddSystem(publisher)
    publisher.connect(builder)
    builder.ExportInput(sample.get_input_port(), "taken")
    diagram = builder.Build()
    simulator = Simulator(diagram)
    diagram.get_input_port().FixValue(simulator.get_mutable_context(), [0.1])
    simulator.AdvanceTo(0.55)
    assert [(pytest.approx(t, abs=1e-12), r) for t, r in handed] == [(0.2, _Value(0.1, 2.5))]
