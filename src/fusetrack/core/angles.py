"""Angles: wrapping and circular means (radians everywhere inside fusetrack)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

TWO_PI = 2.0 * math.pi


def wrap_angle_inplace(a: NDArray[np.float64]) -> NDArray[np.float64]:
    """Wrap the float array ``a`` to ``[-pi, pi)`` in place and return it.

    ``a - 2 pi round(a / 2 pi)`` (cheaper than ``np.mod``), then the few values that rounding
    leaves on ``pi`` or just below ``-pi`` are moved inside the half-open interval.
    """
    a = np.asarray(a)  # a NumPy scalar becomes a writable 0-d array
    a -= TWO_PI * np.rint(a / TWO_PI)
    a[a < -math.pi] += TWO_PI
    a[a >= math.pi] -= TWO_PI
    return a


def wrap_angle(a: ArrayLike) -> NDArray[np.float64]:
    """Angles wrapped to ``[-pi, pi)`` (a new array)."""
    return wrap_angle_inplace(np.array(a, dtype=float))


def angle_diff(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """Smallest signed difference ``a - b`` in [-pi, pi)."""
    return wrap_angle(np.asarray(a, dtype=float) - np.asarray(b, dtype=float))


def circular_mean(
    a: ArrayLike, weights: ArrayLike | None = None, axis: int = 0
) -> NDArray[np.float64]:
    """Weighted circular mean ``atan2(sum w sin a, sum w cos a)`` along ``axis``."""
    a = np.asarray(a, dtype=float)
    w = np.ones_like(a) if weights is None else np.broadcast_to(np.asarray(weights, float), a.shape)
    return np.arctan2((w * np.sin(a)).sum(axis=axis), (w * np.cos(a)).sum(axis=axis))
