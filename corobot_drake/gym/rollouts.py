"""Episodes of a policy on GoToGoal: in this process, or many on Ray workers.

`run_episode` plays one seed to its end. `EpisodePool` keeps one env per Ray worker (an actor:
the diagram is built once per worker, each episode resets it) inside the study engine's
`ray_session` (a local Ray instance, or a cluster by address); `rollouts` is the one-call form.
A policy is any picklable callable observation -> action (with a `reset()`, called before each
episode, if it remembers); `None` means uniformly random actions, drawn from the episode's
seed.
"""

from __future__ import annotations

import contextlib
import dataclasses as dc
from collections.abc import Callable, Iterator, Sequence

import numpy as np
from tqdm import tqdm

from corobot_drake.gym.env import GoToGoalConfig, GoToGoalEnv


@dc.dataclass(frozen=True)
class Episode:
    """How one episode went."""

    seed: int
    """The seed the episode's layout (and random actions) were drawn from."""
    success: bool
    """The robot came within `GoToGoalConfig.goal_radius` of the goal, ending the episode."""
    flipped: bool
    """The robot tilted past `GoToGoalConfig.flip_tilt_deg`, ending the episode."""
    episode_return: float
    """The sum of the episode's rewards."""
    steps: int
    """Control steps taken (`GoToGoalConfig.control_period` s each)."""
    collision_steps: int
    """Steps that ended with the robot touching a box."""
    stall_steps: int
    """Steps that ended stalled: wheels commanded to move, the chassis hardly moving."""
    final_distance: float
    """m from the goal at the end."""


def run_episode(env: GoToGoalEnv, policy: Callable | None, seed: int) -> Episode:
    """Plays the episode of `seed` with `policy` (None: random actions) to its end; a policy
    with memory (a `reset` method) forgets the previous episode first."""
    obs, info = env.reset(seed=seed)
    if policy is None:
        env.action_space.seed(seed)
    elif callable(getattr(policy, "reset", None)):
        policy.reset()
    total, steps, collisions, stalls = 0.0, 0, 0, 0
    while True:
        action = env.action_space.sample() if policy is None else policy(obs)
        obs, reward, terminated, truncated, info = env.step(action)
        total += reward
        steps += 1
        collisions += info["collided"]
        stalls += info["stalled"]
        if terminated or truncated:
            return Episode(seed, info["is_success"], info["flipped"], total, steps, collisions,
                           stalls, info["goal_distance"])


class EpisodeWorker:
    """One worker's env (a Ray actor: `ray.remote(EpisodeWorker)`)."""

    def __init__(self, config: GoToGoalConfig | None = None):
        self.env = GoToGoalEnv(config)

    def ready(self) -> bool:
        """True once the env is built (the actor's constructor has run)."""
        return True

    def run_jobs(self, start: int, jobs) -> tuple[int, list[Episode]]:
        """`start` (where the batch sits in the caller's list) and each (policy, seed) job's
        episode."""
        return start, [run_episode(self.env, policy, seed) for policy, seed in jobs]


class EpisodePool:
    """Ray workers, each with its env, kept for many batches of episodes (a training run)."""

    def __init__(self, workers: int, config: GoToGoalConfig | None = None):
        import ray

        remote = ray.remote(num_cpus=1)(EpisodeWorker)
        self._actors = [remote.remote(config) for _ in range(workers)]

    def wait_ready(self) -> None:
        """Waits until every worker has built its env."""
        import ray

        ray.get([actor.ready.remote() for actor in self._actors])

    def run(self, jobs: Sequence[tuple[Callable | None, int]], progress: bool = False,
            chunk: int = 1) -> list[Episode]:
        """Each (policy, seed) job's episode, in the order of `jobs`; `chunk` episodes per
        task (fewer round trips)."""
        from ray.util import ActorPool

        tasks = [(i, jobs[i:i + chunk]) for i in range(0, len(jobs), chunk)]
        out: list[Episode | None] = [None] * len(jobs)
        pool = ActorPool(self._actors)
        bar = tqdm(total=len(jobs), unit="episode", disable=not progress, leave=False)

        def submit(actor, task):
            start, batch = task
            return actor.run_jobs.remote(start, batch)

        for start, episodes in pool.map_unordered(submit, tasks):
            out[start:start + len(episodes)] = episodes
            bar.update(len(episodes))
        bar.close()
        return out


@contextlib.contextmanager
def episode_pool(workers: int | None = None, address: str | None = None,
                 config: GoToGoalConfig | None = None) -> Iterator[EpisodePool]:
    """An EpisodePool in the study engine's Ray session (started and stopped here unless Ray
    is already initialized)."""
    from corobot_drake.study.engine import ray_session

    with ray_session(address, workers) as n:
        yield EpisodePool(n, config)


def rollouts(policy: Callable | None, seeds: Sequence[int], *, workers: int | None = None,
             address: str | None = None, config: GoToGoalConfig | None = None,
             progress: bool = True) -> list[Episode]:
    """The episodes of `seeds` with `policy`, on Ray (in seed order)."""
    with episode_pool(workers, address, config) as pool:
        return pool.run([(policy, s) for s in seeds], progress=progress)


def summary(episodes: Sequence[Episode]) -> dict:
    """Success rate, mean return, mean steps, collision and stall steps per episode, flips,
    and the seeds whose goal was not reached."""
    return {
        "episodes": len(episodes),
        "success_rate": float(np.mean([e.success for e in episodes])),
        "mean_return": float(np.mean([e.episode_return for e in episodes])),
        "mean_steps": float(np.mean([e.steps for e in episodes])),
        "collision_steps": float(np.mean([e.collision_steps for e in episodes])),
        "stall_steps": float(np.mean([e.stall_steps for e in episodes])),
        "flips": int(sum(e.flipped for e in episodes)),
        "not_reached": [e.seed for e in episodes if not e.success],
    }
