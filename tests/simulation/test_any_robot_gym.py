"""The gym with its `robot` option: the task driven by the Burger (no IR sensor: the
observation is the goal and the motion alone) and the Pioneer (its eight sonars' rays), the
spaces made from the robot's own sensors, the stall measured at its own wheels; a camera
asked of a robot without one, or a robot that is none, is one ValueError."""

import gymnasium
import numpy as np
import pytest

import corobot_drake.gym  # noqa: F401  (registers the env)
from corobot_drake.gym.env import GoToGoalEnv
from corobot_drake.robots import robot_spec


@pytest.mark.parametrize(("robot", "rays"), [("burger", 0), ("pioneer", 8 * 2 * 3)])
def test_a_robot_drives_the_task(robot, rays):
    env = gymnasium.make("corobot_drake/GoToGoal-v0", robot=robot, time_limit=0.5).unwrapped
    assert env.robot.spec.kind == robot
    names = env.observation_names()
    assert len(names) == rays + 4 == env.observation_space.shape[0]
    assert names[rays:] == ["goal_distance", "goal_bearing", "forward_speed", "yaw_rate"]
    sonars = robot_spec(robot).sensors.get("ir_sensors", {})
    assert {n.rsplit("_", 1)[0] for n in names[:rays]} == {f"ir_{s}" for s in sonars}
    observation, _ = env.reset(seed=3)
    assert env.observation_space.contains(observation)
    for _ in range(5):  # 0.5 s forward at power 0.8: the episode is truncated, not stalled
        observation, _, terminated, truncated, info = env.step(np.array([0.8, 0.8], np.float32))
        assert env.observation_space.contains(observation) and not info["stalled"]
    assert truncated and not terminated
    assert observation[rays + 2] > 0.1  # forward, m/s


def test_what_a_robot_lacks_or_is_not_is_refused():
    with pytest.raises(ValueError, match=r"GoToGoalConfig\.camera: the robot 'burger' has "
                                         r"no front camera"):
        GoToGoalEnv(robot="burger", camera=True)
    with pytest.raises(ValueError, match=r"^GoToGoalConfig.robot: .*nor a robot file|"
                                         r"^GoToGoalConfig.robot: .*cannot read"):
        GoToGoalEnv(robot="no/such/robot.yaml")
