"""Environment steps per second of GoToGoal: one env in this process, Gymnasium's
`AsyncVectorEnv` with 1 and 2 envs, and episodes on Ray with 1 and 2 workers
(`tools/bench_gym.py`). Random actions, so every episode runs to the time limit."""

from __future__ import annotations

import time

import gymnasium
import numpy as np

from corobot_drake.gym import ENV_ID
from corobot_drake.gym.env import GoToGoalEnv
from corobot_drake.gym.rollouts import episode_pool


def in_process(steps: int) -> dict:
    """One env, `steps` random-action steps (resetting at episode ends); build excluded."""
    start = time.perf_counter()
    env = GoToGoalEnv()
    built = time.perf_counter() - start
    env.reset(seed=0)
    env.action_space.seed(0)
    start = time.perf_counter()
    for _ in range(steps):
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if terminated or truncated:
            env.reset()
    wall = time.perf_counter() - start
    return {"steps": steps, "wall": wall, "startup": built}


def vector(num_envs: int, steps: int) -> dict:
    """`AsyncVectorEnv` of `num_envs` envs (one process each), `steps` vector steps after a
    first reset; start-up (each process building its diagram) reported apart."""
    start = time.perf_counter()
    envs = gymnasium.vector.AsyncVectorEnv([lambda: gymnasium.make(ENV_ID)] * num_envs)
    envs.reset(seed=0)
    envs.action_space.seed(0)
    started = time.perf_counter() - start
    start = time.perf_counter()
    for _ in range(steps):
        envs.step(envs.action_space.sample())
    wall = time.perf_counter() - start
    envs.close()
    return {"steps": steps * num_envs, "wall": wall, "startup": started}


def on_ray(workers: int, episodes: int) -> dict:
    """`episodes` random-action episodes on a local Ray instance of `workers` workers (an
    `episode_pool`); wall time of the episodes once the workers have built their envs, and
    the start-up before (Ray's start, the workers' imports and builds)."""
    start = time.perf_counter()
    with episode_pool(workers) as pool:
        pool.wait_ready()
        ready = time.perf_counter()
        done = pool.run([(None, seed) for seed in range(episodes)])
        wall = time.perf_counter() - ready
    return {"steps": int(np.sum([e.steps for e in done])), "wall": wall,
            "startup": ready - start}
