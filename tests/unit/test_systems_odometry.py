"""The odometry systems on their own: ChassisPoses, Compass, Gps, the wheel encoders and
DriveStateReporter (fixed inputs, evaluated outputs)."""

import math

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import SpatialInertia, UnitInertia
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

from corobot_drake.robots import robot_spec
from corobot_drake.systems.drive import DriveStatus
from corobot_drake.systems.odometry import (
    ChassisPoses,
    Compass,
    DriveStateReporter,
    Gps,
    add_chassis_poses,
    add_wheel_encoders,
)

EXACT = 1e-12  # rad or m: a rotation matrix and one atan2


def pose(x, y, z, roll, pitch, yaw) -> RigidTransform:
    return RigidTransform(RollPitchYaw(roll, pitch, yaw), [x, y, z])


def test_chassis_poses_pick_each_robots_body_from_body_poses():
    system = ChassisPoses({"a": 2, "b": 1})
    context = system.CreateDefaultContext()
    poses = [RigidTransform(), pose(1, 2, 3, 0, 0, 0.5), pose(-4, 5, 0.1, 0.2, -0.1, 2.0)]
    system.get_input_port().FixValue(context, poses)
    assert system.GetOutputPort("a").Eval(context).IsExactlyEqualTo(poses[2])
    assert system.GetOutputPort("b").Eval(context).IsExactlyEqualTo(poses[1])
    moved = [*poses[:2], pose(7, 8, 9, 0, 0, 1.0)]  # a new input: the cached list follows
    system.get_input_port().FixValue(context, moved)
    assert system.GetOutputPort("a").Eval(context).IsExactlyEqualTo(moved[2])


@pytest.mark.parametrize("yaw", [0.0, 0.7, -2.0, math.pi - 1e-9, -math.pi + 1e-9])
def test_compass_and_gps_read_a_fixed_pose(yaw):
    X = pose(1.5, -2.25, 0.06, 0.03, -0.02, yaw)  # a little roll and pitch: still the yaw
    readings = []
    for system, port in ((Compass(), "heading"), (Gps(), "position")):
        context = system.CreateDefaultContext()
        system.GetInputPort("chassis_pose").FixValue(context, X)
        readings.append(system.GetOutputPort(port).Eval(context))
    heading, position = readings
    assert heading[0] == pytest.approx(yaw, abs=EXACT)
    np.testing.assert_array_equal(position, [1.5, -2.25, 0.06])


def test_compass_is_in_minus_pi_to_pi():
    system = Compass()
    context = system.CreateDefaultContext()
    system.GetInputPort("chassis_pose").FixValue(context, pose(0, 0, 0, 0, 0, 3 * math.pi / 2))
    assert system.GetOutputPort("heading").Eval(context)[0] == pytest.approx(-math.pi / 2,
                                                                             abs=EXACT)


def test_compass_reads_a_state_quaternion_that_drifted_from_unit_norm():
    """The discrete plant's state quaternion drifts from unit norm; Drake makes body_poses
    from the normalized quaternion, so the compass must read the true yaw."""
    plant = MultibodyPlant(0.01)
    body = plant.AddRigidBody("chassis", SpatialInertia(
        1.0, np.zeros(3), UnitInertia.SolidBox(0.3, 0.2, 0.1)))
    plant.Finalize()
    builder = DiagramBuilder()
    builder.AddSystem(plant)
    compass = builder.AddSystem(Compass())
    builder.Connect(add_chassis_poses(builder, plant, {"robot": body})["robot"],
                    compass.GetInputPort("chassis_pose"))
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    q = [0.9, 0.0, 0.0, -0.3]  # w, x, y, z: |q| = 0.949
    plant.SetPositions(plant.GetMyMutableContextFromRoot(context), [*q, 1.0, 2.0, 0.0])
    heading = compass.GetOutputPort("heading").Eval(compass.GetMyContextFromRoot(context))
    assert heading[0] == pytest.approx(2 * math.atan2(-0.3, 0.9), abs=EXACT)


def encoder_ticks(q_front_left: float, q_front_right: float) -> np.ndarray:
    builder = DiagramBuilder()
    wheel_state = np.zeros(8)  # [q, v] of front_left, front_right, rear_left, rear_right
    wheel_state[:2] = q_front_left, q_front_right
    wheel_state[2:4] = 100.0, -100.0  # rear wheels: no encoders
    source = builder.AddSystem(ConstantVectorSource(wheel_state))
    builder.ExportOutput(add_wheel_encoders(builder, "robot", source.get_output_port()))
    diagram = builder.Build()
    return diagram.get_output_port().Eval(diagram.CreateDefaultContext())


@pytest.mark.parametrize("q", [0.0, 0.001, 1.0, 2 * math.pi * 0.4999, -0.001, -7.5, 123.4])
def test_encoders_count_floor_600_ticks_per_revolution(q):
    ticks = encoder_ticks(q, -q)
    expected = [math.floor(600 * a / (2 * math.pi)) for a in (q, -q)]
    # Drake quantizes the angle, then a gain turns it into ticks: whole numbers to rounding.
    np.testing.assert_allclose(ticks, expected, atol=1e-9)
    assert robot_spec("corobot").encoder_ticks_per_revolution == 600


def test_drive_state_reporter_assembles_the_drive_state():
    reporter = DriveStateReporter(power_scaling_factor=10.16)
    context = reporter.CreateDefaultContext()
    context.SetTime(2.5)
    status = DriveStatus.Zero()
    status.enabled, status.power_left, status.power_right = 1.0, 0.25, -0.5
    status.target_left, status.target_right = 2.54, -5.08
    for name, value in (("drive_status", status[:]), ("axle_speed", [1.0, -2.0, 1.5, -2.5]),
                        ("encoder_ticks", [41.9999999999, -7.0000000001]),
                        ("position", [0.5, -0.25, 0.06]), ("heading", [1.25])):
        reporter.GetInputPort(name).FixValue(context, value)
    state = reporter.GetOutputPort("drive_state").Eval(context)
    assert (state.time_stamp, state.is_enabled, state.power_scaling_factor) == (2.5, True, 10.16)
    assert state.distance_between_wheels == robot_spec("corobot").track
    assert (state.position, state.heading) == ((0.5, -0.25, 0.06), 1.25)
    wheels = {n: (w.commanded_power, w.axle_speed, w.encoder_ticks)
              for n, w in state.wheels.items()}
    assert wheels == {"front_left": (0.25, 1.0, 42), "front_right": (-0.5, -2.0, -7),
                      "rear_left": (0.25, 1.5, None), "rear_right": (-0.5, -2.5, None)}
    two = state.two_wheel()
    assert (two.left, two.right) == (state.wheels["front_left"], state.wheels["front_right"])
    status.enabled = 0.0
    reporter.GetInputPort("drive_status").FixValue(context, status[:])
    assert reporter.GetOutputPort("drive_state").Eval(context).is_enabled is False
