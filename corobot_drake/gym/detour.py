"""`DetourPolicy`: drive to the goal around the boxes the IR sensors have seen (with memory).

The front IR sensor's cone is 8 deg wide: it loses a box as soon as the robot turns from it,
and a policy of the current observation alone turns back into it. This one remembers. Each
step it

- dead-reckons its heading from the observed yaw rate (trapezoidal, since `reset`), and so its
  pose in a frame centred on the goal (the goal's observed distance and bearing give the
  position);
- stores where each IR ray stopped short of its range, in that frame, with points up to
  `box_depth` behind it (a box's far side, which the sensor never sees);
- keeps a map of the cost to the goal on a grid of that frame (`CELL`): the shortest way
  around the stored hits, no cell nearer one than `clearance`, a cell within `comfort` more
  costing up to `crowding` times more per metre (recomputed when a hit is stored);
- heads for the cheapest of `HEADINGS` points `lookahead` away that it can reach without
  crossing a blocked cell (`persistence`: keeping to the last choice between equals), turning
  toward it (`turn_gain`) and driving forward as it comes into line (`speed`, falling to 0 at
  `align` rad off), or backward when the point is behind (`reverse`).

Only observations and its own state (no simulator state). It forgets by itself at an
episode's first observation (`starts_episode`), so any loop gets its score, a plain Gymnasium
one included; `reset()` forgets too (`rollouts.run_episode` calls it). Its parameters are what
`train.py` tunes.
"""

from __future__ import annotations

import dataclasses as dc
import json
import math
from pathlib import Path

import numpy as np

from corobot_drake.gym.env import GoToGoalConfig
from corobot_drake.robots import corobot
from corobot_drake.sensors.raycast import cross_of_rays_in_sensor_frame

HEADINGS = 72
"""Candidate headings, evenly around the robot (5 deg apart)."""
HIT_MARGIN = 0.01
"""m: a ray shorter than the IR range by more than this stopped at something."""
DEPTH_POINTS = 3
"""Points stored per hit, from the hit to `box_depth` behind it."""
CELL = 0.06
"""m: the side of a cell of the cost map."""
MAP_MARGIN = 1.0
"""m: the map reaches this much farther from the goal than the start."""
SEGMENT_CHECKS = 4
"""Points checked for blocked cells along the way to each lookahead point."""
REVERSE_HYSTERESIS = 0.3
"""rad between starting and ending a backward drive (see `DetourParameters.reverse`)."""
GOAL_JUMP_SPEED = 2.0
"""m/s: a goal distance changing faster than this between two calls (over three times the
robot's top speed) is a new episode's goal."""


@dc.dataclass(frozen=True)
class DetourParameters:
    """The tunable numbers (all positive; `train.py` scales each by exp of its vector entry)."""

    clearance: float = 0.17
    """m: no way passes nearer a stored hit (the robot's half width is 0.14 m)."""
    comfort: float = 0.2
    """m beyond `clearance` within which a cell costs more."""
    crowding: float = 3.0
    """Extra cost per metre (times a metre's) of a cell at `clearance`, falling linearly to 0
    at `clearance + comfort`."""
    box_depth: float = 0.3
    """m an obstacle is taken to reach behind a hit."""
    lookahead: float = 0.3
    """m from the robot to the points it chooses among."""
    turn_gain: float = 2.5
    """Power difference (each side) per rad of heading error."""
    lead: float = 0.2
    """s: the heading error is taken where the observed yaw rate will have turned the robot
    this much later (the drive's slew limit makes a spin overshoot)."""
    speed: float = 1.0
    """Forward power when in line with the chosen heading."""
    align: float = 0.9
    """rad off the chosen heading at which the forward power falls to 0."""
    reverse: float = 2.2
    """rad: a heading farther off than this is driven to backward (the rear sensor ahead)
    until it is back within `reverse - REVERSE_HYSTERESIS`."""
    persistence: float = 0.05
    """m of cost per rad a heading turns from the one chosen last (no dithering between two
    ways of the same cost)."""


PARAMETER_NAMES = tuple(f.name for f in dc.fields(DetourParameters))


def _ray_geometry(name: str) -> tuple[np.ndarray, np.ndarray]:
    """(origin (2,), unit directions (n, 2)): each ray of the Corobot's IR sensor `name`'s
    cross on the ground plane, in the chassis frame (a pitched ray's length counts by its
    cosine), as its robot file mounts it."""
    ir = corobot.sensor("ir_sensors", name)
    position, rpy_deg = corobot.mount_of("ir_sensors", name)
    d_S = cross_of_rays_in_sensor_frame(ir["samples"], ir["dispersion_cone_angle"])
    yaw = math.radians(rpy_deg[2])
    c, s = math.cos(yaw), math.sin(yaw)
    planar = np.column_stack([c * d_S[:, 0] - s * d_S[:, 1], s * d_S[:, 0] + c * d_S[:, 1]])
    return np.array(position[:2]), planar


_RAYS = [_ray_geometry("front"), _ray_geometry("rear")]
IR_RANGE = corobot.sensor("ir_sensors", "front")["maximum_range"]
"""m: the Corobot's IR sensors' reading when nothing is in range (its robot file's)."""
NUM_RAYS = sum(len(d) for _, d in _RAYS)
"""IR rays at the observation's start (front then rear)."""
_ANGLES = np.linspace(-math.pi, math.pi, HEADINGS, endpoint=False)
_UNIT = np.column_stack([np.cos(_ANGLES), np.sin(_ANGLES)])
_NEIGHBOURS = [(di, dj, math.hypot(di, dj)) for di in range(-2, 3) for dj in range(-2, 3)
               if math.gcd(di, dj) == 1]
"""The wavefront's steps: the 16 nearest directions (a path's length is within 3 % of its
Euclidean length whatever its direction)."""


def _wrap(angle):
    """Angle(s) in (-pi, pi]."""
    return np.arctan2(np.sin(angle), np.cos(angle))


def _rotation(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def _windows(padded: np.ndarray, pad: int, n: int, offsets):
    """Each offset's n x n window of an array padded by `pad` cells on every side."""
    for di, dj, *rest in offsets:
        yield padded[pad + di:pad + di + n, pad + dj:pad + dj + n], rest


class CostMap:
    """Metres-equivalent cost to the goal from every cell of a square grid centred on it."""

    def __init__(self, half_extent: float):
        self.n = 2 * math.ceil(half_extent / CELL) + 1
        self.half = (self.n // 2) * CELL
        self.cost = np.full((self.n, self.n), math.inf)

    def cells(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(row, column) of each point (goal frame, m) and whether it is on the grid."""
        ij = np.rint((points + self.half) / CELL).astype(int)
        inside = ((ij >= 0) & (ij < self.n)).all(axis=-1)
        return np.clip(ij, 0, self.n - 1), inside

    def at(self, points: np.ndarray) -> np.ndarray:
        """The cost at each point, interpolated between the 4 nearest cells (inf next to a
        blocked cell, and off the grid)."""
        x = (points + self.half) / CELL
        low = np.floor(x).astype(int)
        f = x - low
        inside = ((low >= 0) & (low < self.n - 1)).all(axis=-1)
        i, j = np.clip(low[..., 0], 0, self.n - 2), np.clip(low[..., 1], 0, self.n - 2)
        fi, fj = f[..., 0], f[..., 1]
        corners = np.stack([self.cost[i, j], self.cost[i + 1, j], self.cost[i, j + 1],
                            self.cost[i + 1, j + 1]])
        weights = np.stack([(1 - fi) * (1 - fj), fi * (1 - fj), (1 - fi) * fj, fi * fj])
        blocked = np.isinf(corners).any(axis=0) | ~inside
        value = (np.where(np.isinf(corners), 0.0, corners) * weights).sum(axis=0)
        return np.where(blocked, math.inf, value)

    def update(self, hits: np.ndarray, p: DetourParameters) -> None:
        """Recomputes the cost from the stored hits (goal frame, m)."""
        n = self.n
        occupied = np.zeros((n, n), bool)
        ij, inside = self.cells(hits)
        occupied[ij[inside, 0], ij[inside, 1]] = True
        reach = math.ceil((p.clearance + p.comfort) / CELL)
        offsets = [(di, dj, CELL * math.hypot(di, dj)) for di in range(-reach, reach + 1)
                   for dj in range(-reach, reach + 1)
                   if math.hypot(di, dj) * CELL <= p.clearance + p.comfort]
        near = np.full((n, n), math.inf)  # m to the nearest occupied cell (within reach)
        padded = np.pad(occupied, reach)
        for window, (length,) in _windows(padded, reach, n, offsets):
            near[window & (near > length)] = length
        weight = 1.0 + p.crowding * np.clip((p.clearance + p.comfort - near) / p.comfort,
                                            0.0, 1.0)
        weight[near < p.clearance] = math.inf
        self.cost = _wavefront(weight, n // 2)


def _wavefront(weight: np.ndarray, centre: int) -> np.ndarray:
    """Cost from every cell to the centre one, stepping in `_NEIGHBOURS` at CELL x length x
    the two cells' mean `weight` (Bellman-Ford sweeps until nothing changes; a knight's step
    over a blocked cell's corner is allowed, a cell's width being under the clearance)."""
    n = len(weight)
    cost = np.full((n, n), math.inf)
    cost[centre, centre] = 0.0
    padded_weight = np.pad(weight, 2, constant_values=math.inf)
    steps = [CELL * length * (weight + window) / 2
             for window, (length,) in _windows(padded_weight, 2, n, _NEIGHBOURS)]
    for _ in range(4 * n):
        padded = np.pad(cost, 2, constant_values=math.inf)
        new = cost
        for (window, _), step in zip(_windows(padded, 2, n, _NEIGHBOURS), steps, strict=True):
            new = np.minimum(new, window + step)
        new[centre, centre] = 0.0
        if np.array_equal(new, cost):
            break
        cost = new
    return cost


class DetourPolicy:
    """observation -> [left, right] power, remembering the IR hits of the episode."""

    def __init__(self, parameters: DetourParameters | None = None,
                 control_period: float = GoToGoalConfig.control_period):
        """`control_period`: s between calls (the env's step), for the dead reckoning."""
        self.parameters = parameters or DetourParameters()
        self.control_period = control_period
        self.reset()

    def reset(self) -> None:
        """Forgets the episode: heading 0, no stored hits, no map."""
        self._heading = 0.0
        self._yaw_rate: float | None = None
        self._hits: list[np.ndarray] = []
        self._map: CostMap | None = None
        self._chosen: float | None = None  # rad, goal frame: the last heading chosen
        self._backward = False
        self._last: tuple[float, bool] | None = None  # the last call's goal distance, at rest

    def starts_episode(self, distance: float, speed: float, yaw_rate: float) -> bool:
        """Whether an observation (goal distance m, forward speed m/s, yaw rate rad/s) is an
        episode's first: the robot at rest (both exactly 0, as every env reset leaves it; a
        driven robot never stops exactly) after a call where it was not, or the goal farther
        from the last call's than the robot can drive in a control period."""
        if self._last is None:
            return True
        last_distance, was_at_rest = self._last
        at_rest = speed == 0.0 and yaw_rate == 0.0
        return ((at_rest and not was_at_rest)
                or abs(distance - last_distance) > GOAL_JUMP_SPEED * self.control_period)

    # --- training's vector form -----------------------------------------------------------
    @classmethod
    def from_vector(cls, theta) -> DetourPolicy:
        """Each parameter the default's times exp(theta[i]) (theta = 0: the defaults)."""
        base = np.array([getattr(DetourParameters(), n) for n in PARAMETER_NAMES])
        values = base * np.exp(np.asarray(theta, dtype=float))
        return cls(DetourParameters(*map(float, values)))

    # --- acting ---------------------------------------------------------------------------
    def __call__(self, observation) -> np.ndarray:
        obs = np.asarray(observation["state"] if isinstance(observation, dict) else observation,
                         dtype=float)
        distance, bearing, speed, yaw_rate = map(float, obs[NUM_RAYS:NUM_RAYS + 4])
        if self.starts_episode(distance, speed, yaw_rate):
            self.reset()
        self._last = (distance, speed == 0.0 and yaw_rate == 0.0)
        if self._yaw_rate is not None:
            self._heading += self.control_period * (self._yaw_rate + yaw_rate) / 2
        self._yaw_rate = yaw_rate
        goal = distance * np.array([math.cos(bearing), math.sin(bearing)])  # robot frame
        rotation = _rotation(self._heading)  # robot frame -> goal-centred frame
        if self._map is None:
            self._map = CostMap(distance + MAP_MARGIN)
            self._map.update(np.zeros((0, 2)), self.parameters)
        hits = self._ray_hits(obs[:NUM_RAYS])
        if len(hits):
            self._hits.append((hits - goal) @ rotation.T)
            self._map.update(np.concatenate(self._hits), self.parameters)
        heading = self._choose_heading(-rotation @ goal, rotation, bearing)
        return self._powers(heading, yaw_rate)

    def _ray_hits(self, distances: np.ndarray) -> np.ndarray:
        """Robot-frame points of the rays that hit, each with its `box_depth` behind it."""
        out = []
        behind = np.linspace(0.0, self.parameters.box_depth, DEPTH_POINTS)
        start = 0
        for origin, directions in _RAYS:
            r = distances[start:start + len(directions)]
            start += len(directions)
            hit = r < IR_RANGE - HIT_MARGIN
            if hit.any():
                reach = r[hit, None] + behind[None, :]  # (hits, DEPTH_POINTS)
                out.append((origin + reach[..., None] * directions[hit, None, :]).reshape(-1, 2))
        return np.concatenate(out) if out else np.zeros((0, 2))

    def _choose_heading(self, position: np.ndarray, rotation: np.ndarray,
                        bearing: float) -> float:
        """rad, robot frame: toward the cheapest point `lookahead` ahead reachable without a
        blocked cell (`position`: the robot in the goal frame; no such point: the goal)."""
        directions = _UNIT @ rotation.T  # goal frame
        fractions = np.linspace(1.0 / SEGMENT_CHECKS, 1.0, SEGMENT_CHECKS)
        points = (position + self.parameters.lookahead * fractions[:, None, None]
                  * directions[None])  # (SEGMENT_CHECKS, HEADINGS, 2)
        cost = self._map.at(points)
        cost = np.where(np.isinf(cost).any(axis=0), math.inf, cost[-1])
        if not np.isfinite(cost).any():
            return bearing
        absolute = _ANGLES + self._heading
        if self._chosen is not None:
            cost = cost + self.parameters.persistence * np.abs(_wrap(absolute - self._chosen))
        best = int(np.argmin(cost))
        self._chosen = float(absolute[best])
        return float(_ANGLES[best])

    def _powers(self, heading: float, yaw_rate: float) -> np.ndarray:
        """Left, right power turning toward `heading` (rad, robot frame, + to the left) at
        `yaw_rate` (rad/s)."""
        p = self.parameters
        limit = p.reverse - (REVERSE_HYSTERESIS if self._backward else 0.0)
        self._backward = abs(heading) > limit
        if self._backward:
            heading = float(_wrap(heading - math.pi))  # the rear's error
        forward = p.speed * max(0.0, 1.0 - abs(heading) / p.align)
        forward = -forward if self._backward else forward
        turn = p.turn_gain * (heading - p.lead * yaw_rate)
        left, right = forward - turn, forward + turn
        scale = max(1.0, abs(left), abs(right))
        return np.array([left / scale, right / scale], dtype=np.float32)
    # --- files ----------------------------------------------------------------------------
    def save(self, path: str | Path, **about) -> None:
        """JSON: the kind, the parameters by name and `about` (how it was trained)."""
        Path(path).write_text(json.dumps({
            "kind": "DetourPolicy", "parameters": dc.asdict(self.parameters), **about},
            indent=1) + "\n")

    @classmethod
    def from_saved(cls, data: dict, path) -> DetourPolicy:
        """The policy of a saved file's JSON `data` (ValueError naming a bad parameter)."""
        values = data.get("parameters")
        if not isinstance(values, dict) or set(values) != set(PARAMETER_NAMES):
            raise ValueError(f"{path}: parameters: expected {list(PARAMETER_NAMES)}, got "
                             f"{values!r:.200}")
        for name, value in values.items():
            if not isinstance(value, (int, float)) or not 0 < value < math.inf:
                raise ValueError(f"{path}: parameters.{name}: must be a positive finite "
                                 f"number; got {value!r:.40}")
        return cls(DetourParameters(**{n: float(v) for n, v in values.items()}))
