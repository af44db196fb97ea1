r"""Rauch–Tung–Striebel smoothing for the Kalman family, and the fixed-lag windows every
smoother here shares.

A filter gives ``p(x_k | z_1:k)``; a smoother gives ``p(x_k | z_1:T)`` (fixed interval) or
``p(x_k | z_1:min(k+L, T))`` (fixed lag ``L``). For a Gaussian filter the backward pass needs,
at every step ``k``, the filtered ``N(m_k, P_k)``, the prediction ``N(m^-_{k+1}, P^-_{k+1})``
from it and the cross covariance ``D_{k+1} = Cov[x_k, x_{k+1} | z_1:k]``::

    G_k   = D_{k+1} [P^-_{k+1}]^-1                               smoother gain
    m^s_k = m_k + G_k (m^s_{k+1} - m^-_{k+1})
    P^s_k = P_k + G_k (P^s_{k+1} - P^-_{k+1}) G_k^T               (m^s_T = m_T, P^s_T = P_T)

(the Gaussian RTS smoother of Särkkä 2013, "Bayesian Filtering and Smoothing", Ch. 9). The
three filters differ only in ``D``, and :func:`rts_smoother` uses the one that matches how the
filter predicted:

* :class:`~fusetrack.filters.KalmanFilter`: ``D = P_k F^T`` with ``F = transition_matrix(dt)``,
  the RTS smoother (Rauch, Tung & Striebel 1965; Särkkä 2013, Thm 8.2), exact for
  linear-Gaussian models;
* :class:`~fusetrack.filters.ExtendedKalmanFilter`: ``D = P_k F^T`` with ``F`` the motion
  Jacobian at the filtered mean ``m_k``, the extended RTS smoother (Särkkä 2013, Alg. 9.1);
* :class:`~fusetrack.filters.UnscentedKalmanFilter`: ``D = sum_i Wc_i (X_i - m_k)
  (f(X_i) - m^-_{k+1})^T`` over the filter's sigma points ``X_i`` of ``N(m_k, P_k)``, the
  unscented RTS smoother for additive noise (Särkkä 2008, "Unscented Rauch-Tung-Striebel
  smoother", IEEE TAC 53(3), 845-849).

The prediction ``N(m^-, P^-)`` is recomputed with the filter's own ``predict`` (deterministic for
these filters), so the smoother needs only the filtered means and covariances, as
:func:`~fusetrack.filters.run_filter` records them. Leading batch axes (``(T, ..., d)``) are
smoothed all at once.

**Fixed lag.** :func:`fixed_lag` runs any backward pass over windows: the estimate at ``k``
comes from a backward pass started at ``min(k + L, T - 1)`` (the smoother of the data up to
``k + L``); the windows that reach the last step share one pass. ``L = 0`` is the filter,
``L >= T - 1`` (or None) the fixed-interval smoother. It costs ``O(T L)`` backward steps.

>>> import numpy as np
>>> from fusetrack.core import Gaussian, Measurement
>>> from fusetrack.filters import KalmanFilter, run_filter
>>> from fusetrack.motion import ConstantVelocity
>>> from fusetrack.sensors import PositionFix
>>> kf = KalmanFilter(ConstantVelocity(ndim=1, q=0.1), [PositionFix("gps", cov=[[0.5]])])
>>> zs = [Measurement(float(t), "gps", [0.9 * t]) for t in range(5)]
>>> track = run_filter(kf, Gaussian(np.zeros(2), np.eye(2)), zs)
>>> means, covs = rts_smoother(kf, track.means, track.covariances, np.diff(track.times))
>>> bool(np.all(covs[:, 0, 0] <= track.covariances[:, 0, 0]))
True
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol, TypeVar, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, Gaussian, ShapeError, invalid
from .kalman import ExtendedKalmanFilter, GaussianFilter, KalmanFilter, UnscentedKalmanFilter

Array = NDArray[np.float64]
X = TypeVar("X")

_METHODS: dict[Any, str] = {
    KalmanFilter.propagate_motion: "RTS smoother",
    ExtendedKalmanFilter.propagate_motion: "extended RTS smoother",
    UnscentedKalmanFilter.propagate_motion: "unscented RTS smoother",
}


class _LinearMotion(Protocol):
    def transition_matrix(self, dt: float) -> Array: ...


def _t(a: NDArray[Any]) -> NDArray[Any]:
    return np.swapaxes(a, -1, -2)


def check_lag(lag: int | None) -> int | None:
    """``lag`` as an int ``>= 0`` (or None: fixed interval); :class:`ConfigError` otherwise."""
    if lag is None:
        return None
    if isinstance(lag, bool) or not isinstance(lag, int | np.integer) or lag < 0:
        raise ConfigError(
            invalid("lag", lag, "an integer >= 0 (steps of look-ahead) or None (fixed interval)")
        )
    return int(lag)


def check_dts(dts: ArrayLike, n_steps: int, *, positive: bool = False) -> Array:
    """The ``T - 1`` time steps between consecutive estimates, finite and ``>= 0``
    (``> 0`` when ``positive``); :class:`ConfigError` otherwise."""
    d = np.atleast_1d(np.asarray(dts, dtype=float)) if n_steps > 1 else np.asarray(dts, float)
    if d.shape != (max(n_steps - 1, 0),):
        raise ShapeError(invalid("dts.shape", d.shape, f"({max(n_steps - 1, 0)},): T - 1 steps"))
    bad = ~np.isfinite(d) | (d <= 0 if positive else d < 0)
    if bad.any():
        what = "finite numbers > 0" if positive else "finite numbers >= 0"
        raise ConfigError(invalid("dts", d, f"{what} (seconds between consecutive steps)"))
    return d


def fixed_lag(n_steps: int, lag: int | None, backward: Callable[[int, int], list[X]]) -> list[X]:
    """The smoothed marginals ``0..T-1`` at lag ``lag``, from ``backward(a, b)``, a backward
    pass started at step ``b`` that returns the marginals at steps ``a..b`` (in time order).

    The marginal at ``k`` is the first of ``backward(k, k + lag)``, except that every step from
    ``T - 1 - lag`` on takes its marginal from the one pass ``backward(T - 1 - lag, T - 1)``.
    ``lag=None`` (or ``>= T - 1``) is the fixed-interval pass ``backward(0, T - 1)``.
    """
    lag = check_lag(lag)
    if n_steps == 0:
        return []
    if lag is None or lag >= n_steps - 1:
        return backward(0, n_steps - 1)
    last = n_steps - 1 - lag
    return [backward(k, k + lag)[0] for k in range(last)] + backward(last, n_steps - 1)


def smoother_name(filt: Any) -> str | None:
    """Which RTS smoother fits ``filt`` (by how it predicts), or None if none does."""
    if not isinstance(filt, GaussianFilter):
        return None
    return _METHODS.get(type(filt).propagate_motion)


def _cross_covariance(filt: GaussianFilter, mean: Array, cov: Array, dt: float) -> Array:
    """``D = Cov[x_k, x_{k+1}]`` under the filter's own approximation of the motion."""
    how = type(filt).propagate_motion
    if how is UnscentedKalmanFilter.propagate_motion:  # Särkkä 2008, additive noise
        ukf = cast(UnscentedKalmanFilter, filt)
        x = ukf.sigma_points(mean, cov)
        fx = np.asarray(ukf.motion.mean(x, dt), dtype=float)
        dfx = fx - np.einsum("k,...kd->...d", ukf.wm, fx)[..., None, :]
        return np.asarray(_t((x - mean[..., None, :]) * ukf.wc[:, None]) @ dfx)
    if how is ExtendedKalmanFilter.propagate_motion:
        f = np.asarray(filt.motion.jacobian(mean, dt), dtype=float)
    else:
        f = np.asarray(cast(_LinearMotion, filt.motion).transition_matrix(dt), dtype=float)
    return np.asarray(cov @ _t(f))


def _gain(pred_cov: Array, cross: Array) -> Array:
    """``G = D P^-^-1`` (``P^-`` symmetric): ``(P^-^-1 D^T)^T``; pseudo-inverse if singular."""
    try:
        return np.asarray(_t(np.linalg.solve(pred_cov, _t(cross))))
    except np.linalg.LinAlgError:
        return np.asarray(cross @ np.linalg.pinv(pred_cov, hermitian=True))


def _check_gaussian_inputs(
    filt: GaussianFilter, means: ArrayLike, covs: ArrayLike, dts: ArrayLike
) -> tuple[Array, Array, Array]:
    if smoother_name(filt) is None:
        raise ConfigError(
            invalid(
                "filt",
                filt,
                "a KalmanFilter, ExtendedKalmanFilter or UnscentedKalmanFilter (or a subclass "
                "that predicts as one of them)",
            )
        )
    m = np.asarray(means, dtype=float)
    c = np.asarray(covs, dtype=float)
    if m.ndim < 2 or c.shape != (*m.shape, m.shape[-1]):
        raise ShapeError(
            invalid("(means.shape, covs.shape)", (m.shape, c.shape), "(T, ..., d), (T, ..., d, d)")
        )
    return m, c, check_dts(dts, m.shape[0])


def rts_smoother(
    filt: GaussianFilter,
    means: ArrayLike,
    covs: ArrayLike,
    dts: ArrayLike,
    *,
    lag: int | None = None,
) -> tuple[Array, Array]:
    """Smoothed means ``(T, ..., d)`` and covariances ``(T, ..., d, d)`` from the filtered ones.

    Parameters
    ----------
    filt:
        the :class:`KalmanFilter`, :class:`ExtendedKalmanFilter` or
        :class:`UnscentedKalmanFilter` that produced the estimates (its ``predict`` and motion
        model define the backward pass; see the module docstring).
    means, covs:
        the filtered ``m_k`` ``(T, ..., d)`` and ``P_k`` ``(T, ..., d, d)`` (a
        :class:`~fusetrack.core.Track`'s ``means`` and ``covariances`` from ``run_filter``).
    dts:
        ``(T - 1,)`` seconds from each estimate to the next (``np.diff(track.times)``).
    lag:
        None: fixed-interval smoothing (every estimate uses all data); an int ``L >= 0``: the
        estimate at ``k`` uses the data up to step ``k + L`` (:func:`fixed_lag`).
    """
    m, c, d = _check_gaussian_inputs(filt, means, covs, dts)
    check_lag(lag)
    pred_m: list[Array] = []
    pred_c: list[Array] = []
    gains: list[Array] = []
    for k, dt in enumerate(d):  # the forward quantities, once for every window
        pred = filt.predict(Gaussian(m[k], c[k]), float(dt))
        pred_m.append(pred.mean)
        pred_c.append(pred.cov)
        gains.append(_gain(pred.cov, _cross_covariance(filt, m[k], c[k], float(dt))))

    def backward(a: int, b: int) -> list[tuple[Array, Array]]:  # Särkkä 2013, Thm 8.2
        ms, ps = m[b], c[b]
        out = [(ms, ps)]
        for k in range(b - 1, a - 1, -1):
            g = gains[k]
            ms = m[k] + (g @ (ms - pred_m[k])[..., None])[..., 0]
            ps = c[k] + g @ (ps - pred_c[k]) @ _t(g)
            ps = 0.5 * (ps + _t(ps))
            out.append((ms, ps))
        return out[::-1]

    marginals = fixed_lag(m.shape[0], lag, backward)
    if not marginals:
        return m.copy(), c.copy()
    return np.stack([x for x, _ in marginals]), np.stack([p for _, p in marginals])
