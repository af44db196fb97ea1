"""One pass over the particles for a sampled detection function's log-likelihood.

:meth:`~fusetrack.sensors.DetectionFunctionSensor.log_likelihood` of an acoustic node (Kushwaha
2010, Eqs. 30 and 34): the bearing of each particle in the node's frame, the piecewise-linear
interpolation of the normalised beam values there, the floor, the log. The NumPy formulation
makes four passes over the particles with temporaries (arctan2, mod, a gathered interpolation,
log); this loop makes one, with the same operations in the same order (so the same numbers:
``atan2`` is the C library's in both, ``%`` on floats is NumPy's ``mod``).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


@numba.njit(cache=True, inline="always")
def _mod(a: float, b: float) -> float:  # pragma: no cover - jit
    """NumPy's ``mod(a, b)`` for ``b > 0``, without ``fmod`` in the usual ranges: for
    ``b <= a < 2b`` the difference ``a - b`` is exact (Sterbenz), as ``fmod``'s is; for
    ``-b <= a < 0`` NumPy adds ``b`` to ``fmod(a, b) = a`` as here."""
    if 0.0 <= a < b:
        return a
    if b <= a < 2.0 * b:
        return a - b
    if -b <= a < 0.0:
        return a + b
    return a % b


@numba.njit(cache=True)
def log_sampled_detection(
    xy: Array,
    px: float,
    py: float,
    heading: float,
    start: float,
    step: float,
    density: Array,
    periodic: bool,
    add: float,
) -> Array:  # pragma: no cover - jit
    """``log max(λ̃(θ(x)) + add, 1e-300)`` for positions ``xy (L, >= 2)``; ``density (n,)`` the
    normalised samples at ``start + i step`` (wrapping when ``periodic``, held at the ends when
    not), ``θ`` the bearing from ``(px, py)`` minus ``heading`` wrapped to ``[-π, π)``."""
    n = density.shape[0]
    out = np.empty(xy.shape[0])
    for i in range(xy.shape[0]):
        theta = math.atan2(xy[i, 1] - py, xy[i, 0] - px) - heading
        theta = _mod(theta + np.pi, 2 * np.pi) - np.pi
        u = (theta - start) / step
        if periodic:
            u = _mod(u, float(n))
            j = min(math.floor(u), n - 1)
            w = u - j
            val = (1 - w) * density[j] + w * density[(j + 1) % n]
        else:
            u = min(max(u, 0.0), n - 1.0)
            j = min(math.floor(u), n - 2)
            w = u - j
            val = (1 - w) * density[j] + w * density[j + 1]
        out[i] = math.log(max(val + add, 1e-300))
    return out
