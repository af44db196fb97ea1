"""Accuracy and consistency metrics: RMSE, NEES/NIS, track loss (OSPA and other multi-target
metrics are in :mod:`.multi_target_metrics`).

Array layout (the :class:`~fusetrack.core.Track` convention): a state array is ``(T, ..., d)`` —
time first, then any number of Monte Carlo run axes (none for a single run), then the state.
Covariances are ``(T, ..., d, d)``. Pass ``time_axis=`` when time is elsewhere among the leading
axes (e.g. ``time_axis=1`` for a runner's ``(R, T, d)`` array).

Missing estimates. A filter that lost its target may report NaN. One *sample* is one
(step, run) pair; a sample is *missing* when any selected component of the estimate or of the
truth is not finite. ``nan_policy`` then decides:

* ``"propagate"`` (default) — every average that includes a missing sample is NaN, so a lost
  filter can never look accurate by accident;
* ``"omit"`` — missing samples are left out of each average (NaN only where nothing is left);
  report :func:`track_loss_rate` or the count of missing samples beside such numbers;
* ``"raise"`` — a missing sample raises :class:`~fusetrack.core.ConfigError`.

The same sample is dropped from every axis of a per-axis RMSE, so the axes stay comparable.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.stats import chi2

from ..core import ConfigError, ShapeError, check_positive, invalid

Array = NDArray[np.float64]
NanPolicy = Literal["propagate", "omit", "raise"]
Over = Literal["runs", "time", "all"]

_NAN_POLICIES = ("propagate", "omit", "raise")
_OVERS = ("runs", "time", "all")


# --------------------------------------------------------------------------------------------
# helpers


def _time_first(a: Array, time_axis: int, core_ndim: int, name: str) -> Array:
    """Move ``time_axis`` (counted among the leading, non-core axes) to position 0."""
    lead = a.ndim - core_ndim
    if lead < 1:
        valid = f"a time axis before the last {core_ndim} axes"
        raise ShapeError(invalid(f"{name}.shape", a.shape, valid))
    if not -lead <= time_axis < lead:
        raise ConfigError(invalid("time_axis", time_axis, f"an axis in [{-lead}, {lead})"))
    return np.moveaxis(a, time_axis % lead, 0)


def _select(a: Array, index: Sequence[int] | None, name: str) -> Array:
    if index is None:
        return a
    idx = tuple(int(i) for i in index)
    d = a.shape[-1]
    if not idx or any(not -d <= i < d for i in idx):
        valid = f"non-empty state indices below {d}"
        raise ConfigError(invalid(f"{name} index", tuple(index), valid))
    return a[..., list(idx)]


def _check_choice(field: str, value: str, valid: tuple[str, ...]) -> None:
    if value not in valid:
        raise ConfigError(invalid(field, value, "one of " + ", ".join(repr(v) for v in valid)))


def _errors(
    estimates: ArrayLike,
    truth: ArrayLike,
    index: Sequence[int] | None,
    time_axis: int,
) -> Array:
    """``estimates - truth`` restricted to ``index``, time first: ``(T, ..., k)``."""
    est = np.asarray(estimates, dtype=float)
    tru = np.asarray(truth, dtype=float)
    if est.ndim < 2:
        raise ShapeError(invalid("estimates.shape", est.shape, "(T, ..., d)"))
    try:
        tru = np.broadcast_to(tru, est.shape)
    except ValueError:
        raise ShapeError(
            invalid("truth.shape", tru.shape, f"broadcastable to estimates.shape {est.shape}")
        ) from None
    e = _select(est, index, "estimates") - _select(tru, index, "truth")
    return _time_first(e, time_axis, 1, "estimates")


def _reduce(
    values: Array, present: NDArray[np.bool_], over: str, nan_policy: str, name: str
) -> Array:
    """Mean of ``values`` ``(T, ..., *core)`` over the axes named by ``over``.

    ``present`` ``(T, ...)`` marks the samples that are not missing.
    """
    _check_choice("over", over, _OVERS)
    _check_choice("nan_policy", nan_policy, _NAN_POLICIES)
    lead = present.ndim
    core = values.ndim - lead
    if nan_policy == "raise" and not present.all():
        where = tuple(int(i[0]) for i in np.nonzero(~present))
        raise ConfigError(
            invalid(
                name,
                f"non-finite sample at (step, run...) {where}",
                "finite values (or nan_policy='propagate' / 'omit')",
            )
        )
    if over == "runs":
        axes = tuple(range(1, lead))
    elif over == "time":
        axes = (0,)
    else:
        axes = tuple(range(lead))
    if nan_policy == "omit":
        w = present.reshape(present.shape + (1,) * core)
        v = np.where(w, values, 0.0)
        n = np.broadcast_to(w, values.shape).sum(axis=axes)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(n > 0, v.sum(axis=axes) / np.maximum(n, 1), np.nan)
    v = np.where(present.reshape(present.shape + (1,) * core), values, np.nan)
    return v.mean(axis=axes)


def _scalar_or_array(a: Array) -> Array:
    return a[()] if a.ndim == 0 else a


# --------------------------------------------------------------------------------------------
# RMSE


def rmse(
    estimates: ArrayLike,
    truth: ArrayLike,
    index: Sequence[int] | None = None,
    *,
    joint: bool = False,
    over: Over = "runs",
    nan_policy: NanPolicy = "propagate",
    time_axis: int = 0,
) -> Array:
    """Root-mean-square error of ``estimates`` against ``truth`` (both ``(T, ..., d)``).

    ``index`` picks state components (default: all). With ``joint=False`` each component gets
    its own RMSE (last axis ``k = len(index)``); with ``joint=True`` the squared errors are summed
    over the components first, ``sqrt(E[|x_hat - x|^2])`` — the usual position or velocity RMSE.

    ``over`` names what the mean of the squared error runs over:

    * ``"runs"`` — ``RMSE(t) = sqrt(mean_runs e_t^2)``, one value per step: ``(T,)`` / ``(T, k)``;
    * ``"time"`` — ``RMSE_run = sqrt(mean_t e_t^2)``, one value per run: ``(...,)`` / ``(..., k)``;
    * ``"all"`` — time-averaged ``sqrt(mean_{runs, t} e_t^2)``: a scalar / ``(k,)``.

    ``truth`` broadcasts against ``estimates`` (one true trajectory ``(T, 1, d)`` for many runs).
    See the module docstring for ``nan_policy``.
    """
    e = _errors(estimates, truth, index, time_axis)
    present = np.all(np.isfinite(e), axis=-1)
    sq = e * e
    if joint:
        sq = sq.sum(axis=-1)
    out = _reduce(sq, present, over, nan_policy, "estimates")
    return _scalar_or_array(np.sqrt(out))


# --------------------------------------------------------------------------------------------
# NEES / NIS


def _mahalanobis(e: Array, cov: Array, name: str) -> Array:
    """``e^T C^-1 e`` over leading axes; NaN where ``e`` or ``C`` is not finite."""
    ok = np.all(np.isfinite(e), axis=-1) & np.all(np.isfinite(cov), axis=(-2, -1))
    k = e.shape[-1]
    eye = np.eye(k)
    c = np.where(ok[..., None, None], cov, eye)
    r = np.where(ok[..., None], e, 0.0)
    try:
        sol = np.linalg.solve(c, r[..., None])[..., 0]
    except np.linalg.LinAlgError:
        valid = "positive-definite covariances"
        raise ConfigError(invalid(name, "a singular matrix", valid)) from None
    return np.where(ok, np.sum(r * sol, axis=-1), np.nan)


def nees(
    estimates: ArrayLike,
    covariances: ArrayLike,
    truth: ArrayLike,
    *,
    index: Sequence[int] | None = None,
    time_axis: int = 0,
) -> Array:
    """Normalised estimation error squared ``e^T P^-1 e`` with ``e = x_hat - x``, ``(T, ...)``.

    ``covariances`` ``(T, ..., d, d)``; ``index`` restricts both the error and ``P`` to a
    sub-block (e.g. position NEES). For a consistent filter each value is chi-square with
    ``k = len(index)`` degrees of freedom, so its mean is ``k`` (Bar-Shalom, Li & Kirubarajan 2001,
    §5.4). Samples with a non-finite estimate, truth or covariance give NaN; average them with
    :func:`average`.
    """
    est = np.asarray(estimates, dtype=float)
    cov = np.asarray(covariances, dtype=float)
    want = (*est.shape, est.shape[-1])
    if cov.shape != want:
        raise ShapeError(invalid("covariances.shape", cov.shape, f"{want} to match estimates"))
    e = _errors(est, truth, index, time_axis)
    if index is not None:
        idx = [int(i) for i in index]
        cov = cov[..., idx, :][..., :, idx]
    cov = _time_first(cov, time_axis, 2, "covariances")
    return _mahalanobis(e, cov, "covariances")


def nis(
    innovations: ArrayLike,
    innovation_covariances: ArrayLike,
    *,
    time_axis: int = 0,
) -> Array:
    """NIS ``nu^T S^-1 nu``: ``(T, ..., m)``, ``(T, ..., m, m)`` -> ``(T, ...)``.

    Chi-square with ``m`` degrees of freedom for a consistent filter. Angle components of ``nu``
    must already be wrapped (use the sensor's ``residual``). Non-finite samples give NaN.
    """
    nu = np.asarray(innovations, dtype=float)
    s = np.asarray(innovation_covariances, dtype=float)
    want = (*nu.shape, nu.shape[-1])
    if s.shape != want:
        raise ShapeError(invalid("innovation_covariances.shape", s.shape, f"{want}"))
    nu = _time_first(nu, time_axis, 1, "innovations")
    s = _time_first(s, time_axis, 2, "innovation_covariances")
    return _mahalanobis(nu, s, "innovation_covariances")


def average(
    values: ArrayLike,
    *,
    over: Over = "runs",
    nan_policy: NanPolicy = "propagate",
    time_axis: int = 0,
) -> Array:
    """Mean of a per-sample metric ``(T, ...)`` (NEES, NIS, errors) over runs, time or both.

    ``over="runs"`` -> ``(T,)`` (e.g. the average NEES curve), ``"time"`` -> one value per run,
    ``"all"`` -> a scalar. NaN samples follow ``nan_policy`` (module docstring).
    """
    v = np.asarray(values, dtype=float)
    if v.ndim < 1:
        raise ShapeError(invalid("values.shape", v.shape, "(T, ...)"))
    v = _time_first(v, time_axis, 0, "values")
    return _scalar_or_array(_reduce(v, np.isfinite(v), over, nan_policy, "values"))


def chi2_interval(dof: int, n_runs: int, confidence: float = 0.95) -> tuple[float, float]:
    """Two-sided acceptance interval for the average of ``n_runs`` chi-square(``dof``) values.

    ``n_runs * mean ~ chi2(n_runs * dof)``, so the interval is
    ``[chi2.ppf(a/2, n dof) / n, chi2.ppf(1 - a/2, n dof) / n]`` with ``a = 1 - confidence``
    (Bar-Shalom, Li & Kirubarajan 2001, §5.4). For a time-averaged NEES pass the
    number of samples averaged, ``runs * steps`` (valid when the samples are independent).
    """
    dof_i = int(dof)
    n = int(n_runs)
    if dof_i < 1 or dof_i != dof:
        raise ConfigError(invalid("dof", dof, "an integer >= 1"))
    if n < 1 or n != n_runs:
        raise ConfigError(invalid("n_runs", n_runs, "an integer >= 1"))
    if not 0.0 < float(confidence) < 1.0:
        raise ConfigError(invalid("confidence", confidence, "a probability in (0, 1)"))
    a = 1.0 - float(confidence)
    lo, hi = chi2.ppf([a / 2.0, 1.0 - a / 2.0], n * dof_i)
    return float(lo) / n, float(hi) / n


# --------------------------------------------------------------------------------------------
# track loss


def position_error(
    estimates: ArrayLike,
    truth: ArrayLike,
    position_index: Sequence[int],
    *,
    time_axis: int = 0,
) -> Array:
    """Euclidean position error ``|p_hat - p|`` per sample, ``(T, ...)`` (NaN where missing)."""
    e = _errors(estimates, truth, position_index, time_axis)
    return np.sqrt(np.sum(e * e, axis=-1))


def track_loss_onset(
    errors: ArrayLike,
    *,
    threshold: float,
    k: int,
    lost_at_end: bool = True,
    time_axis: int = 0,
) -> NDArray[np.int64]:
    """Step at which each run's track was lost, or -1 if it was kept: ``(T, ...)`` -> ``(...)``.

    Definition (``errors`` ``(T, ...)``, e.g. from :func:`position_error`): a step is *bad* when
    its error exceeds ``threshold`` or is not finite (a NaN estimate means the filter lost the
    target). A run is *lost* when it has ``k`` or more consecutive bad steps; with
    ``lost_at_end=True`` it is also lost when its final steps are bad, however few (the track had
    not recovered when the run ended). The onset is the first step of the first such spell.
    """
    thr = check_positive("threshold", threshold, allow_zero=True)
    if int(k) != k or int(k) < 1:
        raise ConfigError(invalid("k", k, "an integer >= 1 (consecutive steps)"))
    kk = int(k)
    e = np.asarray(errors, dtype=float)
    if e.ndim < 1:
        raise ShapeError(invalid("errors.shape", e.shape, "(T, ...)"))
    e = _time_first(e, time_axis, 0, "errors")
    bad = ~(e <= thr)  # NaN counts as bad
    T = e.shape[0]
    onset = np.full(e.shape[1:], -1, dtype=np.int64)
    spell = np.zeros(e.shape[1:], dtype=np.int64)
    for t in range(T):  # loop over steps, vectorised over runs
        spell = np.where(bad[t], spell + 1, 0)
        hit = (spell >= kk) | (lost_at_end & (t == T - 1) & (spell > 0))
        new = hit & (onset < 0)
        onset = np.where(new, t - spell + 1, onset)
    return onset


def track_loss_rate(
    errors: ArrayLike,
    *,
    threshold: float,
    k: int,
    lost_at_end: bool = True,
    time_axis: int = 0,
) -> float:
    """Fraction of runs whose track was lost (definition in :func:`track_loss_onset`)."""
    onset = track_loss_onset(
        errors, threshold=threshold, k=k, lost_at_end=lost_at_end, time_axis=time_axis
    )
    return float(np.mean(onset >= 0)) if onset.size else 0.0
