"""Meshcat's slip markers and the view's framing for robots other than the Corobot: a ball
per wheel of the robot (the Burger's two, beside its own tyres), and the framing holds the
robot's own shapes."""

import msgpack
import numpy as np
import pytest
from pydrake.geometry import Meshcat
from pydrake.math import RigidTransform, RollPitchYaw

from conftest import Stepper
from corobot_drake.config.scenario import load_scenario
from corobot_drake.robots import robot_spec
from corobot_drake.serving.view import scene_points
from corobot_drake.simulation import Simulation
from corobot_drake.systems.slip_markers import MARKER_GAP, MARKER_PERIOD, SlipMarkers


def test_slip_markers_alone_draw_a_ball_per_wheel_of_the_robot():
    spec = robot_spec("burger")
    meshcat = Meshcat()
    s = Stepper(SlipMarkers(meshcat, "/slip/b", spec=spec), MARKER_PERIOD)
    X_WC = RigidTransform(RollPitchYaw(0, 0, 0.5), [1.0, 2.0, 0.0])
    s.fix("chassis_pose", X_WC)
    s.fix("wheel_slip_ratio", [0.0, -1.0])
    s.fix("wheel_slip_angle", [0.0, 0.0])
    s.tick()
    colour = {w: msgpack.unpackb(meshcat._GetPackedProperty(f"/slip/b/{w}", "color"))["value"]
              for w in spec.wheel_names}
    assert colour == {"left": [0.0, 0.8, 0.0, 1.0], "right": [1.0, 0.0, 0.0, 1.0]}
    right = spec.wheels[spec.wheel_names.index("right")]
    x, y, z = right.center
    matrix = msgpack.unpackb(meshcat._GetPackedTransform("/slip/b/right"))["matrix"]
    expected = X_WC @ np.array([x, y - right.width / 2 - MARKER_GAP, z])
    assert matrix[12:15] == pytest.approx(expected, abs=1e-12)


def test_the_framing_holds_a_robot_by_its_own_shapes():
    sim = Simulation(load_scenario(data="robots: {burger: {robot: burger, pose: "
                                        "{translation: [3, 0, 0]}}}"))
    points = scene_points(sim)
    # Points of its own shapes, near where it stands (the scene has nothing else): up to
    # its lidar's top (0.192 m), above the Corobot's platform that framed every robot
    # (its centre at 0.184 m).
    near = points[np.hypot(points[:, 0] - 3, points[:, 1]) < 0.5]
    assert len(near) == len(points) and near[:, 2].max() >= 0.19


def test_slip_markers_of_a_four_wheel_skid_steer_are_a_ball_per_wheel():
    """The Pioneer: four balls, one beside each tyre, coloured by its own wheel's slip."""
    spec = robot_spec("pioneer")
    meshcat = Meshcat()
    s = Stepper(SlipMarkers(meshcat, "/slip/p", spec=spec), MARKER_PERIOD)
    s.fix("chassis_pose", RigidTransform())
    s.fix("wheel_slip_ratio", [0.0, -1.0, 0.0, -1.0])
    s.fix("wheel_slip_angle", [0.0] * 4)
    s.tick()
    assert len(spec.wheel_names) == 4
    colour = [msgpack.unpackb(meshcat._GetPackedProperty(f"/slip/p/{w}", "color"))["value"]
              for w in spec.wheel_names]
    assert colour == [[0.0, 0.8, 0.0, 1.0], [1.0, 0.0, 0.0, 1.0]] * 2
