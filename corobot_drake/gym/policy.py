"""`LinearPolicy`: powers = tanh(W @ features(observation)), in numpy, saved as JSON.

The features make a linear map enough for GoToGoal: the goal's bearing as its sine and
cosine (no jump at +-pi), its distance capped at 1 m (slow down near it), each IR ray's
proximity 1 - distance / range (0: nothing seen, 1: touching), the robot's speed and yaw rate,
and a constant.
"""

from __future__ import annotations

import dataclasses as dc
import json
from pathlib import Path

import numpy as np

from corobot_drake.robots import corobot

SHIPPED = Path(__file__).resolve().parent / "policy.json"
"""The policy `load_policy()` returns (written by `tools/train_policy.py --ship`)."""
NUM_RAYS = 12
"""IR rays in the observation (front then rear, 6 each): the observation's first entries."""
FRONT_RAYS = 6
FEATURE_NAMES = ("bias", "sin_bearing", "cos_bearing", "goal_distance_1m",
                 *(f"front_proximity_{i}" for i in range(FRONT_RAYS)), "rear_proximity",
                 "forward_speed", "yaw_rate")
NUM_FEATURES = len(FEATURE_NAMES)


def features(observation) -> np.ndarray:
    """The feature vector of a GoToGoal state observation (or a Dict's `state`)."""
    obs = np.asarray(observation["state"] if isinstance(observation, dict) else observation,
                     dtype=float)
    proximity = 1.0 - obs[:NUM_RAYS] / corobot.sensor("ir_sensors", "front")["maximum_range"]
    distance, bearing, speed, yaw_rate = obs[NUM_RAYS:NUM_RAYS + 4]
    return np.concatenate([[1.0, np.sin(bearing), np.cos(bearing), min(distance, 1.0)],
                           proximity[:FRONT_RAYS], [proximity[FRONT_RAYS:].max(), speed,
                                                    yaw_rate]])


@dc.dataclass
class LinearPolicy:
    """observation -> [left, right] power = tanh(weights @ features(observation))."""

    weights: np.ndarray = dc.field(default_factory=lambda: np.zeros((2, NUM_FEATURES)))

    @classmethod
    def goal_seeker(cls) -> LinearPolicy:
        """A hand-written start: drive toward the goal (forward with the bearing's cosine,
        turn with its sine), slow down and turn right as the front rays see something."""
        w = np.zeros((2, NUM_FEATURES))
        front = slice(4, 4 + FRONT_RAYS)
        w[:, FEATURE_NAMES.index("cos_bearing")] = 3.0
        w[:, FEATURE_NAMES.index("sin_bearing")] = (-3.0, 3.0)
        w[0, front], w[1, front] = 4.0 / FRONT_RAYS, -4.0 / FRONT_RAYS
        w[:, front] -= 2.0 / FRONT_RAYS
        return cls(w)

    @classmethod
    def from_vector(cls, theta) -> LinearPolicy:
        return cls(np.asarray(theta, dtype=float).reshape(2, NUM_FEATURES))

    def __call__(self, observation) -> np.ndarray:
        return np.tanh(self.weights @ features(observation)).astype(np.float32)

    def reset(self) -> None:
        """Nothing to forget (a policy of the current observation)."""

    def save(self, path: str | Path, **about) -> None:
        """JSON: the feature names, the weights (one row per side) and `about` (how it was
        trained, what it scored)."""
        Path(path).write_text(json.dumps({
            "kind": "LinearPolicy", "features": list(FEATURE_NAMES),
            "weights": {"left": self.weights[0].tolist(), "right": self.weights[1].tolist()},
            **about}, indent=1) + "\n")

    @classmethod
    def load(cls, path: str | Path | None = None) -> LinearPolicy:
        return cls.from_saved(json.loads(Path(path or SHIPPED).read_text()), path or SHIPPED)

    @classmethod
    def from_saved(cls, data: dict, path) -> LinearPolicy:
        """The policy of a saved file's JSON `data` (ValueError naming a bad field)."""
        if data.get("features") != list(FEATURE_NAMES):
            raise ValueError(f"{path}: features: expected {list(FEATURE_NAMES)}, "
                             f"got {data.get('features')!r:.200}")
        try:
            weights = np.array([data["weights"]["left"], data["weights"]["right"]], dtype=float)
        except (KeyError, TypeError, ValueError):
            weights = None
        if weights is None or weights.shape != (2, NUM_FEATURES) or not np.isfinite(weights).all():
            raise ValueError(f"{path}: weights: expected left and right, {NUM_FEATURES} finite "
                             f"numbers each")
        return cls(weights)


def load(path: str | Path | None = None):
    """The policy saved at `path` (default: the shipped one), of its `kind`: a `DetourPolicy`
    or a `LinearPolicy` (ValueError naming what is wrong with the file)."""
    from corobot_drake.gym.detour import DetourPolicy

    path = Path(path or SHIPPED)
    try:
        data = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ValueError(f"{path}: not a saved policy ({e})") from None
    kinds = {"DetourPolicy": DetourPolicy, "LinearPolicy": LinearPolicy}
    kind = data.get("kind") if isinstance(data, dict) else None
    if kind not in kinds:
        raise ValueError(f"{path}: kind: expected one of {', '.join(kinds)}, got {kind!r:.40}")
    return kinds[kind].from_saved(data, path)

