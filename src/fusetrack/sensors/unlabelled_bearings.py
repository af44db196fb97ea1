"""Unlabelled bearings from one acoustic sensor watching several objects (Lee 2009, Sec. 3.2).

Each audible object gives one bearing ``atan2(y - s_y, x - s_x) + noise``; the set is unordered.
Two objects closer in bearing than the sensor's resolution ``dz_critical`` give one merged
bearing (their mean direction plus noise), the acoustic resolution limit of [15, 50] (spec
choice: 2 degrees).
"""

from __future__ import annotations

import math

import numpy as np

from ..core import ConfigError, ShapeError, invalid

Array = np.ndarray


def true_bearings(positions: Array, sensor: tuple[float, float]) -> Array:
    p = np.asarray(positions, dtype=float)
    if p.ndim != 2 or p.shape[1] < 2:
        raise ShapeError(invalid("positions.shape", p.shape, "(objects, >= 2)"))
    return np.arctan2(p[:, 1] - sensor[1], p[:, 0] - sensor[0])


def merge_close(bearings: Array, dz_critical: float) -> Array:
    """Group bearings whose circular gaps are below ``dz_critical``; one circular mean per group."""
    b = np.sort(np.mod(np.asarray(bearings, float), 2 * math.pi))
    if b.size <= 1 or dz_critical <= 0:
        return b
    gaps = np.diff(np.append(b, b[0] + 2 * math.pi))
    if np.all(gaps < dz_critical):  # everything in one cluster around the circle
        return np.array([math.atan2(np.sin(b).sum(), np.cos(b).sum())])
    start = int(np.argmax(gaps >= dz_critical)) + 1  # begin just after a real gap
    order = np.concatenate((b[start:], b[:start]))  # np.roll(b, -start), without its overhead
    g = np.concatenate((gaps[start:], gaps[:start]))
    groups, cur = [], [order[0]]
    for k in range(1, len(order)):
        if g[k - 1] < dz_critical:
            cur.append(order[k])
        else:
            groups.append(cur)
            cur = [order[k]]
    groups.append(cur)
    return np.array([math.atan2(np.sin(gr).sum(), np.cos(gr).sum()) for gr in groups])


def simulate_bearings(
    positions: Array,
    audible: Array,
    sensor: tuple[float, float],
    sigma: float,
    rng: np.random.Generator,
    dz_critical: float = math.radians(2.0),
) -> Array:
    """The step's bearing set: audible objects' bearings, close ones merged, plus noise, shuffled."""
    if sigma < 0 or not math.isfinite(sigma):
        raise ConfigError(invalid("sigma", sigma, "a finite std >= 0 (rad)"))
    mask = np.asarray(audible, bool)
    b = merge_close(true_bearings(np.asarray(positions)[mask], sensor), dz_critical)
    z = b + sigma * rng.standard_normal(b.shape)
    z = np.arctan2(np.sin(z), np.cos(z))
    return rng.permutation(z)
