"""Reinforcement learning: the Corobot as a Gymnasium environment, a trained policy, rollouts.

    import gymnasium, corobot_drake.gym
    env = gymnasium.make("corobot_drake/GoToGoal-v0")        # camera=True: a Dict with the image
    policy = corobot_drake.gym.load_policy()                  # observation -> action
    obs, info = env.reset(seed=0)

- `env.py`: `GoToGoalEnv` and its `GoToGoalConfig` (spaces, reward, held boxes);
- `layout.py`: an episode's start, goal and boxes, drawn from the seed;
- `detour.py`: `DetourPolicy`, the shipped kind: it remembers the IR hits of the episode and
  heads along the cheapest way around them (`policy.json` is the shipped one, `load_policy`);
- `policy.py`: `LinearPolicy` (features of an observation, a linear map, tanh; its
  `goal_seeker` is the hand-written baseline) and `load`, which reads either kind's JSON;
- `rollouts.py`: episodes of a policy, in one process or on Ray (the study engine's
  `ray_session`), and their summary;
- `train.py`: the cross-entropy method over a policy's parameters, episodes evaluated on Ray
  (`tools/train_policy.py`); environment steps per second: `lab/bench_gym.py`.

docs/gym.md has the spaces, the reward and the measured figures.
"""

from corobot_drake.extras import require

require("gym", "corobot_drake.gym")

import gymnasium  # noqa: E402 (after the one-line check of the extra)

from corobot_drake.gym.env import GoToGoalConfig  # noqa: E402

ENV_ID = "corobot_drake/GoToGoal-v0"

MAX_EPISODE_STEPS = round(GoToGoalConfig.time_limit / GoToGoalConfig.control_period)
"""The registration's step limit (Gymnasium's TimeLimit): the default `time_limit` over the
default `control_period`, 60 (the env truncates there itself; `gymnasium.make(...,
time_limit=10.0, max_episode_steps=100)` for longer episodes)."""

if ENV_ID not in gymnasium.registry:
    gymnasium.register(ENV_ID, entry_point="corobot_drake.gym.env:GoToGoalEnv",
                       max_episode_steps=MAX_EPISODE_STEPS)


def load_policy(path=None):
    """The shipped policy (or the one saved at `path`): a callable observation -> action. It
    remembers the episode's IR hits and forgets them by itself at an episode's first
    observation, so any loop plays it (its `reset()` forgets too)."""
    from corobot_drake.gym.policy import load

    return load(path)


__all__ = ["ENV_ID", "MAX_EPISODE_STEPS", "load_policy"]
