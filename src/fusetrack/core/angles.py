"""Angles: wrapping and circular means (radians everywhere inside fusetrack)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


def wrap_angle(a: ArrayLike) -> NDArray[np.float64]:
    """Wrap angles to [-pi, pi)."""
    a = np.asarray(a, dtype=float)
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def angle_diff(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """Smallest signed difference ``a - b`` in [-pi, pi)."""
    return wrap_angle(np.asarray(a, dtype=float) - np.asarray(b, dtype=float))


def circular_mean(a: ArrayLike, weights: ArrayLike | None = None, axis: int = 0) -> NDArray[np.float64]:
    """Weighted circular mean ``atan2(sum w sin a, sum w cos a)`` along ``axis``."""
    a = np.asarray(a, dtype=float)
    w = np.ones_like(a) if weights is None else np.broadcast_to(np.asarray(weights, float), a.shape)
    return np.arctan2((w * np.sin(a)).sum(axis=axis), (w * np.cos(a)).sum(axis=axis))
