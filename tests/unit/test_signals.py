"""The signals table's places (`signals.put_value`, `read_value`) and the publishers' shared
bases (`recording.looks.RobotStateLooks`, `CameraLooks`, `IrScanLooks`) alone."""

import math
import types

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.math import SpatialVelocity
from pydrake.systems.sensors import ImageRgba8U

from corobot_drake import signals
from corobot_drake.config.sensors import IrSensorConfig
from corobot_drake.recording.looks import CameraLooks, IrScanLooks, RobotStateLooks
from corobot_drake.sensors.ir_sensor import SCAN_TIME
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


class _Frames(CameraLooks):
    """Keeps what it is handed: (context time, capture time, the image's first pixel)."""

    def __init__(self):
        super().__init__(4, 3, look=0.01, delay=0.03)
        self.handed = []

    def publish_frame(self, context, captured, image):
        self.handed.append((context.get_time(), captured, int(image.data[0, 0, 0])))


@pytest.mark.parametrize("captured, look", [
    (math.nan, None),  # no frame: nothing handed on
    (0.015, 0.05),     # out at 0.045: the look at 0.05 sees [0.04, 0.05)
    (0.010, 0.05),     # out at 0.04: not the look at 0.04 (it runs before the updates at 0.04)
    (0.0, 0.04),
])
def test_camera_looks_hand_on_a_frame_once_at_the_look_after_it_comes_out(captured, look):
    """A frame comes out `delay` (30 ms) after its capture; of the looks every 10 ms over
    0.1 s, only the first after that instant hands it on, with its capture time and image."""
    from pydrake.systems.analysis import Simulator

    frames = _Frames()
    simulator = Simulator(frames)
    context = simulator.get_mutable_context()
    image = ImageRgba8U(4, 3)
    image.mutable_data[:] = 7
    frames.GetInputPort("rgb_image").FixValue(context, image)
    frames.GetInputPort("image_time").FixValue(context, [captured])
    simulator.AdvanceTo(0.1)
    expected = [] if look is None else [(look, captured, 7)]
    assert [(pytest.approx(t, abs=1e-12), c, v) for t, c, v in frames.handed] == expected


class _Scans(IrScanLooks):
    """Keeps what it is handed: (context time, scan time)."""

    def __init__(self, events):
        super().__init__(types.SimpleNamespace(config=IrSensorConfig(), num_rays=6,
                                               events=events))
        self.handed = []

    def publish_scan(self, context, when, scan):
        self.handed.append((context.get_time(), when))


@pytest.mark.parametrize("events, scanned, look", [
    ((0.05, 0.05), math.nan, None),  # no scan yet: nothing handed on
    ((0.05, 0.05), 0.05, 0.1),       # a look and a scan at 0.05: the look ran first
    ((0.01, 0.0), 0.05, 0.06),       # on a continuous plant's steps: the next step's look
])
def test_ir_scan_looks_hand_on_a_scan_once_at_the_look_after_it(events, scanned, look):
    """The looks run on the sensor's event schedule; over 0.2 s only the first look after
    the scan hands it on, with its time; the base knows the sensor's limits."""
    from pydrake.systems.analysis import Simulator

    scans = _Scans(events)
    assert (scans.fov_deg, scans.max_range) == (IrSensorConfig().dispersion_cone_angle,
                                                IrSensorConfig().maximum_range)
    simulator = Simulator(scans)
    context = simulator.get_mutable_context()
    state = np.zeros(scans.get_input_port().size())
    state[SCAN_TIME] = scanned
    scans.get_input_port().FixValue(context, state)
    simulator.AdvanceTo(0.2)
    expected = [] if look is None else [(look, scanned)]
    assert [(pytest.approx(t, abs=1e-12), w) for t, w in scans.handed] == expected
