"""A sensor's ticks (offset + k / rate, k = 0, 1, ...) against the plant's steps."""

import math

TICK_TOLERANCE = 1e-9
"""s: a tick this close to a plant step counts as on it (float sums of periods)."""


def last_tick(t: float, rate: float, offset: float) -> tuple[int, float]:
    """(k, t_k): the last tick t_k = offset + k / rate at or before `t` (k = -1 before the
    first); `rate` in Hz, times in s."""
    k = math.floor((t - offset) * rate + TICK_TOLERANCE * rate)
    return k, offset + k / rate


def tick_in_step(t: float, rate: float, offset: float, step: float) -> bool:
    """Whether the plant step at `t` (s) is the first at or after a tick: one in
    (t - step, t]."""
    k, t_k = last_tick(t, rate, offset)
    return k >= 0 and t_k > t - step + TICK_TOLERANCE
