"""Many one-bearing Kalman steps in one Numba loop: predict to each reading's time, update with it.

A fusion node that fuses every reading at its own time (``alignment: all``) makes one EKF step
per reading: ~250 a tick at 1000 readings per second, each a predict and a scalar update of a few
dozen small NumPy calls (~170-280 us of Python a step, ~70 ms a tick). :func:`ekf_bearing_steps`
does the same steps for a :class:`~fusetrack.filters.KalmanFilter` or
:class:`~fusetrack.filters.ExtendedKalmanFilter` on a linear motion model (``F(dt)``, ``Q(dt)``:
``transition_matrix`` and ``noise_cov``) and plain :class:`~fusetrack.sensors.Bearing` sensors,
with the filter's own equations (Bar-Shalom et al. 2001, Eqs. 5.2.3-5 to 5.2.3-18)::

    x = F x,   P = sym(F P F^T + Q)                    (when the reading is later than the belief)
    d = x[position] - s,   z^ = wrap(atan2(d_y, d_x) - heading),   r^2 = max(|d|^2, MIN_RANGE_SQ)
    H = [-d_y, d_x] / r^2 (at the position entries),   S = H P H^T + sigma^2,   K = P H^T / S
    x = x + K wrap(z - z^),   P = sym((I - K H) P (I - K H)^T + sigma^2 K K^T)   (Joseph form)

one reading after another in registers. The numbers equal the filter's ``predict``/``update``
to rounding (another order of operations); anything else (another filter or sensor, a reading
with its own covariance, a non-finite value, a batch of beliefs, ``S <= 0``) gives None and the
caller steps the filter as usual.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numba
import numpy as np
from numpy.typing import NDArray

from ..core import Gaussian, Measurement
from ..sensors import MIN_RANGE_SQ, Bearing
from .kalman import ExtendedKalmanFilter, KalmanFilter

Array = NDArray[np.float64]


@numba.njit(cache=True, nogil=True)
def _wrap(a: float) -> float:  # pragma: no cover - jit
    """``wrap_angle``: ``a - 2 pi rint(a / 2 pi)`` into ``[-pi, pi)``."""
    two_pi = 2.0 * math.pi
    a = a - two_pi * np.rint(a / two_pi)
    if a < -math.pi:
        a += two_pi
    if a >= math.pi:
        a -= two_pi
    return a


@numba.njit(cache=True, nogil=True)
def _steps(x, p, f, q, predict, sensor, ix, iy, z, var):  # pragma: no cover - jit
    """The steps of the module docstring, in place on ``x`` (d,) and ``p`` (d, d); False when an
    innovation variance is not positive and finite (the caller then redoes it all the usual
    way)."""
    d = x.shape[0]
    for i in range(z.shape[0]):
        if predict[i]:
            x[:] = f[i] @ x
            fp = f[i] @ p @ f[i].T + q[i]
            p[:, :] = 0.5 * (fp + fp.T)
        dx, dy = x[ix[i]] - sensor[i, 0], x[iy[i]] - sensor[i, 1]
        z_pred = _wrap(math.atan2(dy, dx) - sensor[i, 2])
        r2 = max(dx * dx + dy * dy, MIN_RANGE_SQ)
        h = np.zeros(d)
        h[ix[i]] = -dy / r2
        h[iy[i]] = dx / r2
        pht = p @ h
        s = h @ pht + var[i]
        if not (s > 0.0 and math.isfinite(s)):
            return False
        k = pht / s
        x += k * _wrap(z[i] - z_pred)
        ikh = np.eye(d) - np.outer(k, h)
        joseph = ikh @ p @ ikh.T + var[i] * np.outer(k, k)
        p[:, :] = 0.5 * (joseph + joseph.T)
    return True


def ekf_bearing_steps(
    filt: object,
    belief: Gaussian,
    time: float,
    measurements: Sequence[Measurement],
    tolerance: float,
) -> tuple[Gaussian, float] | None:
    """``belief`` (at ``time``) stepped through ``measurements`` one by one, each a predict to
    its time (skipped within ``tolerance`` of the belief's time, as
    :class:`~fusetrack.tracking.SingleTargetTracker` does) and an update; ``(belief, its
    time)``, or None when the fast loop does not apply (module docstring)."""
    if type(filt) not in (KalmanFilter, ExtendedKalmanFilter):
        return None
    assert isinstance(filt, KalmanFilter)
    motion = filt.motion
    transition = getattr(motion, "transition_matrix", None)
    mean, cov = np.asarray(belief.mean, dtype=float), np.asarray(belief.cov, dtype=float)
    n, d = len(measurements), mean.shape[-1]
    if not callable(transition) or mean.shape != (d,) or cov.shape != (d, d):
        return None
    f, q = np.empty((n, d, d)), np.empty((n, d, d))
    predict = np.zeros(n, dtype=np.bool_)
    sensor, z, var = np.empty((n, 3)), np.empty(n), np.empty(n)
    ix, iy = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64)
    for i, m in enumerate(measurements):
        s = filt.sensors.get(m.sensor_id)
        value = m.value
        plain = isinstance(s, Bearing) and type(s) is Bearing  # a subclass may differ
        if not plain or m.covariance is not None or np.shape(value) != (1,):
            return None
        assert isinstance(s, Bearing)
        if m.time - time > tolerance:
            dt = m.time - time
            f[i], q[i], predict[i], time = transition(dt), motion.noise_cov(dt), True, m.time
        position = np.asarray(s.position, dtype=float)
        sensor[i] = (position[0], position[1], s.heading)
        ix[i], iy[i] = s.position_index[0], s.position_index[1]
        z[i], var[i] = value[0], s.sigma**2
    if not np.isfinite(z).all():
        return None
    x, p = mean.copy(), cov.copy()
    if not _steps(x, p, f, q, predict, sensor, ix, iy, z, var):
        return None
    return Gaussian(x, p), time


def compile_bearing_steps() -> None:
    """Compile the loop now (a few seconds to a minute on first use, then cached on disk): a
    node calls it before it serves, so that its first ticks are not held up by the compiler."""
    d = 4
    _steps(np.zeros(d), np.eye(d), np.eye(d)[None], np.zeros((1, d, d)), np.ones(1, np.bool_),
           np.array([[1.0, 1.0, 0.0]]), np.zeros(1, np.int64), np.ones(1, np.int64),
           np.zeros(1), np.ones(1))  # fmt: skip


__all__ = ["compile_bearing_steps", "ekf_bearing_steps"]
