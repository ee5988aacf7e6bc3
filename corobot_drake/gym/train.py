"""Training a policy's parameter vector with the cross-entropy method, episodes on Ray.

The vector is a `DetourPolicy`'s (`detour.py`: each entry scales one parameter by its exp) or
a `LinearPolicy`'s weights (`CemSettings.start`). Each generation draws `population` vectors
from a diagonal Gaussian, plays each on the
generation's `episodes` training seeds (the same seeds for every candidate: common random
numbers, so candidates are compared on the same layouts), keeps the `elite` with the highest
mean return and refits the Gaussian to them (plus a little extra spread that decays, so it
does not collapse early). Training seeds start at `TRAIN_SEEDS`; the held-out seeds
`HELD_OUT` are never trained on. No deep-learning framework: numpy and Ray.
"""

from __future__ import annotations

import dataclasses as dc
import time

import numpy as np
from tqdm import tqdm

from corobot_drake.gym.detour import PARAMETER_NAMES, DetourPolicy
from corobot_drake.gym.policy import NUM_FEATURES, LinearPolicy
from corobot_drake.gym.rollouts import EpisodePool, summary
from corobot_drake.limits import OneOf, Range, bound_of, bounded

TRAIN_SEEDS = 10_000
"""The first training seed (generation g uses TRAIN_SEEDS + g * episodes + 0..episodes-1)."""
HELD_OUT = tuple(range(100))
"""Seeds the policy is judged on, never trained on."""
STARTS = {
    "detour": (DetourPolicy.from_vector, lambda: np.zeros(len(PARAMETER_NAMES))),
    "goal_seeker": (LinearPolicy.from_vector,
                    lambda: LinearPolicy.goal_seeker().weights.ravel()),
    "zero": (LinearPolicy.from_vector, lambda: np.zeros(2 * NUM_FEATURES)),
}
"""Each start: (vector -> policy, the initial mean vector)."""


@dc.dataclass(frozen=True)
class CemSettings:
    """The training's settings, each with its bound (`tools/train_policy.py` checks its flags
    against them)."""

    generations: int = bounded(4, Range(1, 1000))
    population: int = bounded(8, Range(1, 10_000, why="candidates per generation"))
    episodes: int = bounded(16, Range(1, 1000))
    """Training seeds per generation (every candidate plays all of them)."""
    elite: int = bounded(3, Range(1, 10_000, why="at most the population"))
    start: str = bounded("detour", OneOf(tuple(STARTS)))
    """The policy and its initial mean: `detour` (a `DetourPolicy` with its hand-set
    parameters), `goal_seeker` (`LinearPolicy.goal_seeker`, hand-written) or `zero` (a
    `LinearPolicy` that stays; it needs many more generations)."""
    sigma: float = bounded(0.2, Range(0.0, 100.0, low_open=True))
    """Initial standard deviation of every entry (a linear policy's weights took 0.6)."""
    extra_sigma: float = bounded(0.05, Range(0.0, 100.0))
    """Spread added to the refitted one, decaying linearly to 0 at the last generation."""
    seed: int = bounded(0, Range(0, 2**32 - 1, why="numpy's seed"))
    """Seeds the sampling of candidates."""

    def __post_init__(self):
        """ValueError naming the first field out of its bound (as the tool's flags are)."""
        for field in dc.fields(self):
            problem = bound_of(field).problem(getattr(self, field.name))
            if problem:
                raise ValueError(f"CemSettings.{field.name}: {problem}")
        if self.elite > self.population:
            raise ValueError(f"CemSettings.elite: must be at most the population "
                             f"({self.population}); got {self.elite}")


@dc.dataclass(frozen=True)
class Generation:
    """One generation's figures (its candidates on its training seeds)."""

    generation: int
    mean_return: float
    """Mean over the population's episodes."""
    elite_return: float
    """Mean over the elite's episodes."""
    best_return: float
    success_rate: float
    """Over the population's episodes."""
    elite_success_rate: float
    seconds: float


def train(settings: CemSettings, pool: EpisodePool,
          progress: bool = True) -> tuple[DetourPolicy | LinearPolicy, list[Generation]]:
    """The final mean policy and the learning curve."""
    rng = np.random.default_rng(settings.seed)
    make, initial = STARTS[settings.start]
    mean = initial()
    dim = len(mean)
    std = np.full(dim, settings.sigma)
    curve = []
    bar = tqdm(range(settings.generations), unit="generation", disable=not progress)
    for g in bar:
        start = time.perf_counter()
        seeds = TRAIN_SEEDS + g * settings.episodes + np.arange(settings.episodes)
        thetas = mean + std * rng.standard_normal((settings.population, dim))
        jobs = [(make(t), int(s)) for t in thetas for s in seeds]
        episodes = pool.run(jobs, chunk=settings.episodes)
        returns = np.array([e.episode_return for e in episodes]).reshape(settings.population, -1)
        successes = np.array([e.success for e in episodes]).reshape(settings.population, -1)
        scores = returns.mean(axis=1)
        elite = np.argsort(-scores, kind="stable")[:settings.elite]
        extra = settings.extra_sigma * (1.0 - (g + 1) / settings.generations)
        mean = thetas[elite].mean(axis=0)
        std = thetas[elite].std(axis=0) + extra
        curve.append(Generation(g + 1, float(scores.mean()), float(scores[elite].mean()),
                                float(scores.max()), float(successes.mean()),
                                float(successes[elite].mean()), time.perf_counter() - start))
        bar.set_postfix(elite_return=f"{curve[-1].elite_return:.1f}",
                        success=f"{curve[-1].success_rate:.2f}")
    return make(mean), curve


def evaluate(pool: EpisodePool, policy, seeds=HELD_OUT) -> dict:
    """`summary` of the policy's episodes on `seeds` (None: random actions)."""
    return summary(pool.run([(policy, s) for s in seeds], chunk=max(1, len(seeds) // 20)))


def plot_curve(curve: list[Generation], path, held_out: dict | None = None) -> None:
    """Returns (population mean, elite mean, best) and success rates per generation."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    g = [c.generation for c in curve]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    top.plot(g, [c.best_return for c in curve], "^-", label="best candidate")
    top.plot(g, [c.elite_return for c in curve], "o-", label="elite mean")
    top.plot(g, [c.mean_return for c in curve], "s-", label="population mean")
    top.set_ylabel("mean episode return")
    top.legend()
    top.grid(alpha=0.3)
    bottom.plot(g, [c.elite_success_rate for c in curve], "o-", label="elite")
    bottom.plot(g, [c.success_rate for c in curve], "s-", label="population")
    if held_out is not None:
        bottom.axhline(held_out["success_rate"], color="k", ls="--",
                       label=f"final policy, held-out seeds ({held_out['success_rate']:.0%})")
    bottom.set_ylim(-0.05, 1.05)
    bottom.set_ylabel("success rate (training seeds)")
    bottom.set_xlabel("CEM generation")
    bottom.legend()
    bottom.grid(alpha=0.3)
    fig.suptitle("GoToGoal: cross-entropy method over a policy's parameters")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
