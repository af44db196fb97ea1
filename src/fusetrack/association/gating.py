"""Validation gates and the scan's association scores.

A measurement ``z`` falls in a track's gate when its squared Mahalanobis distance from the
predicted measurement is below the ``P_G`` quantile of the chi-square distribution with ``m``
degrees of freedom (the ellipsoidal validation gate; Blackman & Popoli 1999, Ch. 6;
Bar-Shalom, Daum & Huang 2009)::

    y = z - h(x^-)             (sensor.residual: angle components wrapped)
    S = H P^- H^T + R          H = dh/dx at x^-, R = sensor.noise_cov(x^-) (or z's own covariance)
    d^2 = y^T S^-1 y <= chi2.ppf(P_G, m)

For a non-linear sensor this is the linearised (EKF) gate whatever the track's filter; any belief
with ``mean`` ``(d,)`` and ``cov`` ``(d, d)`` (Gaussian, particles, mixture) can be gated.

:func:`mahalanobis_squared` gates all the (track, measurement) pairs of a sensor in a few batched
array operations; :func:`scan_likelihoods` builds a :class:`~fusetrack.association.ScanLikelihoods`
for one scan from the tracks' predicted beliefs and their filter, paying a filter update only for
the pairs inside the gate (one batched call per sensor for the Kalman family, :mod:`.batch`), so a
scan of thousands of clutter points costs a few array operations per track.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, Literal, cast, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import chdtr, chdtri

from ..core import (
    Belief,
    ConfigError,
    Filter,
    Gaussian,
    Measurement,
    MeasurementError,
    SensorModel,
    ShapeError,
    check_positive,
    invalid,
)
from .base import Array, ScanLikelihoods
from .batch import PairPosteriors, batchable, stack_gaussians, update_pairs, update_stacked

_LOG_2PI = math.log(2.0 * math.pi)


def _moments(belief: Belief) -> tuple[Array, Array]:
    """``(mean (d,), cov (d, d))`` of one (unbatched) belief, or :class:`ShapeError`."""
    mean = np.asarray(belief.mean, dtype=float)
    cov = np.asarray(belief.cov, dtype=float)
    if mean.ndim != 1 or cov.shape != (mean.size, mean.size):
        raise ShapeError(
            invalid(
                "belief (mean.shape, cov.shape)",
                (mean.shape, cov.shape),
                "one belief: mean (d,) and cov (d, d), no batch axes",
            )
        )
    return mean, cov


def check_gate_probability(probability: float) -> float:
    """``float(probability)`` or :class:`ConfigError` unless it is in ``(0, 1]``."""
    try:
        p = float(probability)
    except (TypeError, ValueError):
        p = math.nan
    if not 0.0 < p <= 1.0:
        raise ConfigError(invalid("gate probability", probability, "a probability in (0, 1]"))
    return p


def gate_threshold(probability: float, dim: int) -> float:
    """The squared-distance gate ``chi2.ppf(P_G, m)`` (``inf`` for ``P_G = 1``: no gating)."""
    p = check_gate_probability(probability)
    return math.inf if p == 1.0 else float(chdtri(dim, 1.0 - p))  # = scipy.stats.chi2.ppf


def gate_probability(threshold: float, dim: int) -> float:
    """``P_G = chi2.cdf(threshold, m)``: the probability that a target's own measurement falls in
    a gate of squared Mahalanobis size ``threshold`` (the inverse of :func:`gate_threshold`)."""
    g = check_positive("threshold", threshold)
    return float(chdtr(dim, g))  # = scipy.stats.chi2.cdf


def predicted_measurement(
    belief: Belief, sensor: SensorModel, noise_cov: ArrayLike | None = None
) -> tuple[Array, Array]:
    """``(z_pred (m,), S (m, m))``: ``h(x^-)`` and ``H P^- H^T + R``, linearised at the mean.

    ``noise_cov`` overrides ``R = sensor.noise_cov(mean)`` (a measurement's own covariance).
    """
    mean, cov = _moments(belief)
    z_pred = np.asarray(sensor.predict(mean), dtype=float)
    h = np.asarray(sensor.jacobian(mean), dtype=float)
    r = np.asarray(sensor.noise_cov(mean) if noise_cov is None else noise_cov, dtype=float)
    m = z_pred.shape[-1]
    if h.shape != (m, mean.size) or r.shape != (m, m):
        raise ShapeError(
            invalid(
                f"sensor {sensor.sensor_id!r} (jacobian.shape, noise_cov.shape)",
                (h.shape, r.shape),
                f"({m}, {mean.size}) and ({m}, {m}) for a state of size {mean.size}",
            )
        )
    s = h @ cov @ h.T + r
    return z_pred, 0.5 * (s + s.T)


def _value_and_cov(z: ArrayLike | Measurement) -> tuple[Array, Array | None]:
    if isinstance(z, Measurement):
        cov = None if z.covariance is None else np.asarray(z.covariance, dtype=float)
        return np.asarray(z.value, dtype=float), cov
    return np.asarray(z, dtype=float), None


def innovation(
    belief: Belief, sensor: SensorModel, z: ArrayLike | Measurement
) -> tuple[Array, Array]:
    """``(y, S)``: the residual ``sensor.residual(z, h(x^-))`` and its covariance. A
    :class:`~fusetrack.core.Measurement` with its own ``covariance`` uses it as ``R``."""
    value, cov = _value_and_cov(z)
    z_pred, s = predicted_measurement(belief, sensor, cov)
    if value.shape != z_pred.shape:
        raise MeasurementError(
            invalid("z.shape", value.shape, f"{z_pred.shape}, sensor {sensor.sensor_id!r}'s size")
        )
    return np.asarray(sensor.residual(value, z_pred), dtype=float), s


def mahalanobis_distance(belief: Belief, sensor: SensorModel, z: ArrayLike | Measurement) -> float:
    """Squared Mahalanobis distance ``y^T S^-1 y`` of ``z`` from the predicted measurement."""
    y, s = innovation(belief, sensor, z)
    return float(y @ np.linalg.solve(s, y))


def mahalanobis_gate(
    belief: Belief, sensor: SensorModel, z: ArrayLike | Measurement, probability: float = 0.99
) -> bool:
    """True when ``z`` is inside the ``probability`` (``P_G``) gate of the track."""
    threshold = gate_threshold(probability, sensor.dim)
    return mahalanobis_distance(belief, sensor, z) <= threshold


def gaussian_log_density(y: Array, s: Array) -> float:
    """``log N(y; 0, S) = -(y^T S^-1 y + log det S + m log 2 pi) / 2``."""
    maha = float(y @ np.linalg.solve(s, y))
    return -0.5 * (maha + float(np.linalg.slogdet(s)[1]) + y.size * _LOG_2PI)


def _per_track(name: str, value: float | Sequence[float], n: int) -> Array:
    """A probability in ``(0, 1]`` (one, or one per track) as an ``(n,)`` array."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        a = np.array(math.nan)
    a = np.broadcast_to(a, (n,)) if a.ndim == 0 else a
    if a.shape != (n,) or not ((a > 0) & (a <= 1)).all():
        raise ConfigError(invalid(name, value, f"a probability in (0, 1], or {n} of them"))
    return np.asarray(a)


def _vector(z: Measurement) -> None:
    """:class:`MeasurementError` unless ``z`` has one vector value ``(m,)`` (a gate needs one)."""
    if not isinstance(z.value, np.ndarray) or z.value.ndim != 1:
        shown = getattr(z.value, "shape", type(z.value).__name__)
        raise MeasurementError(
            invalid(f"value (sensor {z.sensor_id!r}, time={z.time})", shown, "a vector (m,)")
        )


def _clutter_of(clutter_density: float | Mapping[str, float], sensor_id: str) -> float:
    if isinstance(clutter_density, Mapping):
        if sensor_id not in clutter_density:
            raise ConfigError(
                invalid("clutter_density", dict(clutter_density), f"a density for {sensor_id!r}")
            )
        return check_positive(f"clutter_density[{sensor_id!r}]", clutter_density[sensor_id])
    return check_positive("clutter_density", clutter_density)


def mahalanobis_squared(
    sensor: SensorModel, beliefs: Sequence[Belief], measurements: Sequence[Measurement]
) -> Array:
    """``(T, M)``: ``y^T S^-1 y`` of each measurement (all of ``sensor``, vector values
    ``(m,)``) against each belief, in a few batched array operations: the gate of
    :func:`mahalanobis_distance` for all pairs at once (``R`` the measurement's own covariance
    when it has one; a singular ``S`` is solved by least squares)."""
    if not len(beliefs) or not len(measurements):
        return np.zeros((len(beliefs), len(measurements)))
    moments = [_moments(b) for b in beliefs]
    means = np.array([m for m, _ in moments])  # (T, d) (np.stack without its overhead)
    covs = np.array([c for _, c in moments])  # (T, d, d)
    return _mahalanobis_stacked(sensor, means, covs, measurements)


def _mahalanobis_stacked(
    sensor: SensorModel, means: Array, covs: Array, measurements: Sequence[Measurement]
) -> Array:
    """:func:`mahalanobis_squared` of the stacked moments ``means`` ``(T, d)``, ``covs``
    ``(T, d, d)``."""
    if not means.shape[0] or not len(measurements):
        return np.zeros((means.shape[0], len(measurements)))
    h = np.asarray(sensor.jacobian(means), float)  # (T, m, d)
    z_pred = np.asarray(sensor.predict(means), float)  # (T, m)
    hph = h @ covs @ np.swapaxes(h, -1, -2)  # (T, m, m)
    r_sensor = np.broadcast_to(np.asarray(sensor.noise_cov(means), float), hph.shape)
    values = np.array([np.asarray(z.value, float) for z in measurements])  # (M, m)
    y = np.asarray(sensor.residual(values[None, :, :], z_pred[:, None, :]), float)  # (T, M, m)
    if all(z.covariance is None for z in measurements):  # one S per track
        return _quadratic_forms((hph + r_sensor)[:, None], y)
    s = hph[:, None] + np.stack([_noise(z, r_sensor) for z in measurements], axis=1)
    return _quadratic_forms(s, y)


def _quadratic_forms(s: Array, y: Array) -> Array:
    """``y^T S^-1 y`` for ``S`` ``(T, 1 or M, m, m)`` and ``y`` ``(T, M, m)``: closed form
    for ``m <= 2`` (the 2x2 inverse ``[[d, -b], [-c, a]] / det``), else through ``S^-1``; by
    least squares (the pseudo-inverse) when some ``S`` is singular (no noise, no
    uncertainty)."""
    m = y.shape[-1]
    if m == 1:
        det = s[..., 0, 0]
        if np.all(np.isfinite(det) & (det != 0.0)):
            return np.asarray(y[..., 0] ** 2 / det)
    elif m == 2:
        a, b, c, d = s[..., 0, 0], s[..., 0, 1], s[..., 1, 0], s[..., 1, 1]
        det = a * d - b * c
        if np.all(np.isfinite(det) & (det != 0.0)):
            y0, y1 = y[..., 0], y[..., 1]
            return np.asarray((d * y0 * y0 - (b + c) * y0 * y1 + a * y1 * y1) / det)
    try:
        s_inv = np.linalg.inv(s)
    except np.linalg.LinAlgError:
        s_inv = np.linalg.pinv(s, hermitian=True)
    return np.asarray(np.einsum("tmi,tmij,tmj->tm", y, np.broadcast_to(s_inv, (*y.shape, m)), y))


def _noise(z: Measurement, sensor_noise: Array) -> Array:
    """``z``'s own covariance when it has one, else the sensor's, as ``(T, m, m)``."""
    if z.covariance is None:
        return sensor_noise
    return np.broadcast_to(np.asarray(z.covariance, float), sensor_noise.shape)


def _pair_scores(
    filt: Filter[Any],
    beliefs: Sequence[Belief],
    sensor: SensorModel,
    pairs: Sequence[tuple[int, Measurement]],
    rng: np.random.Generator | None,
    keep_posteriors: bool,
) -> list[tuple[float, Any]]:
    """``(log p(z | track), posterior or None)`` of every gated pair ``(row, z)``: the filter's
    own increment (batched, :func:`.batch.update_pairs`) when it has ``update_with_likelihood``,
    else the linearised Gaussian innovation density."""
    if callable(getattr(filt, "update_with_likelihood", None)):
        updates = update_pairs(filt, [beliefs[i] for i, _ in pairs], [z for _, z in pairs], rng)
        return [(ll, post) for post, ll in updates]
    out = []
    for i, z in pairs:
        y, s = innovation(beliefs[i], sensor, z)
        post = filt.update(beliefs[i], [z], rng) if keep_posteriors else None
        out.append((gaussian_log_density(y, s), post))
    return out


@overload
def scan_likelihoods(
    track_ids: Sequence[int],
    beliefs: Sequence[Belief] | Gaussian,
    measurements: Sequence[Measurement],
    sensors: Mapping[str, SensorModel] | Sequence[SensorModel],
    filt: Filter[Any],
    p_detect: float | Sequence[float],
    clutter_density: float | Mapping[str, float],
    gate_probability: float = 0.99,
    rng: np.random.Generator | None = None,
    *,
    keep_posteriors: Literal[False] = False,
    validated: bool = False,
) -> ScanLikelihoods: ...


@overload
def scan_likelihoods(
    track_ids: Sequence[int],
    beliefs: Sequence[Belief] | Gaussian,
    measurements: Sequence[Measurement],
    sensors: Mapping[str, SensorModel] | Sequence[SensorModel],
    filt: Filter[Any],
    p_detect: float | Sequence[float],
    clutter_density: float | Mapping[str, float],
    gate_probability: float = 0.99,
    rng: np.random.Generator | None = None,
    *,
    keep_posteriors: Literal[True],
    validated: bool = False,
) -> tuple[ScanLikelihoods, Mapping[tuple[int, int], Any]]: ...


def scan_likelihoods(
    track_ids: Sequence[int],
    beliefs: Sequence[Belief] | Gaussian,
    measurements: Sequence[Measurement],
    sensors: Mapping[str, SensorModel] | Sequence[SensorModel],
    filt: Filter[Any],
    p_detect: float | Sequence[float],
    clutter_density: float | Mapping[str, float],
    gate_probability: float = 0.99,
    rng: np.random.Generator | None = None,
    *,
    keep_posteriors: bool = False,
    validated: bool = False,
) -> ScanLikelihoods | tuple[ScanLikelihoods, Mapping[tuple[int, int], Any]]:
    """The :class:`ScanLikelihoods` of one scan (and, with ``keep_posteriors``, the updates).

    ``beliefs[i]`` is track ``track_ids[i]``'s predicted belief at the scan time (``beliefs``
    may also be one batched Gaussian ``(T, d)``, a row per track: stacked already). For every
    measurement ``j`` inside track ``i``'s ``gate_probability`` gate, ``log_likelihood[i, j] =
    log P_D,i + log p(z_j | track i)``: the increment of ``filt.update_with_likelihood(belief,
    [z_j], rng)`` when the filter is a :class:`~fusetrack.core.LikelihoodFilter`, else the
    Gaussian innovation density :func:`gaussian_log_density` of the linearised gate; ``-inf``
    outside the gate, when ``z_j`` is not finite (a report that saw nothing) or when the
    filter's increment is not finite. ``log P_D`` is
    included so that the scores alone give the association posterior (see
    :mod:`fusetrack.association.scores`). ``log_missed[i] = log(1 - P_D,i P_G)``;
    ``log_clutter[j] = log(clutter_density)`` of ``z_j``'s sensor (one density for all sensors or
    a mapping ``sensor_id -> density``, per unit of measurement space per scan).

    ``p_detect``: one probability in ``(0, 1]`` or one per track. Returns ``scores``, or
    ``(scores, posteriors)`` with ``keep_posteriors=True``: ``posteriors[(i, j)]`` the belief
    of track row ``i`` updated with measurement ``j`` alone, for every gated pair (for the
    Kalman family a :class:`~fusetrack.association.PairPosteriors`, whose batched arrays hold
    them all: the beliefs are stacked once and every sensor's gated pairs updated in one call). A
    measurement from a sensor not in ``sensors`` raises
    :class:`~fusetrack.core.UnknownSensorError` (a :class:`MeasurementError`).
    ``validated=True``: the caller has already checked every measurement (a vector value of a
    known sensor, :func:`~fusetrack.filters.validate_measurement`) and passes only usable
    (finite) ones, so they are not checked again.
    """
    from ..filters import as_sensor_map, validate_measurement  # here: importing filters is slow

    n = len(track_ids)
    stack: Gaussian | None = None
    each: Sequence[Belief]  # the beliefs one by one, for the per-track path
    if isinstance(beliefs, Gaussian) and beliefs.mean.ndim == 2:  # one batch, a row per track
        count = int(beliefs.mean.shape[0])
        stack = beliefs if batchable(filt, ()) else None
        each = () if stack is not None else beliefs.unstack()
    else:
        each = cast(Sequence[Belief], beliefs)
        count = len(each)
    if count != n:
        raise ShapeError(invalid("len(beliefs)", count, f"{n}, one per track id"))
    pg = check_gate_probability(gate_probability)
    pd = _per_track("p_detect", p_detect, n)
    sensor_map = as_sensor_map(sensors)
    if validated:
        usable = [True] * len(measurements)
    else:
        for z in measurements:
            _vector(z)
        usable = [bool(validate_measurement(z, sensor_map).usable) for z in measurements]
    log_kappa = {  # one density per sensor
        sid: math.log(_clutter_of(clutter_density, sid))
        for sid in dict.fromkeys(z.sensor_id for z in measurements)
    }
    log_clutter = np.array([log_kappa[z.sensor_id] for z in measurements], dtype=float)
    ll = np.full((n, len(measurements)), -np.inf)
    log_pd = np.array([math.log(p) for p in pd.tolist()])  # math.log: the scalar path's digits
    if stack is None:
        stack = _stacked_prior(filt, each)
    posteriors: dict[tuple[int, int], Any] = {}
    stacked_parts: list[tuple[Any, Any, Gaussian]] = []
    by_sensor: dict[str, list[int]] = {}
    for j, ok in enumerate(usable):
        if ok:
            by_sensor.setdefault(measurements[j].sensor_id, []).append(j)
    for sid, cols in by_sensor.items():
        sensor = sensor_map[sid]
        chosen = [measurements[j] for j in cols]
        if stack is None:
            d2 = mahalanobis_squared(sensor, each, chosen)
        else:
            d2 = _mahalanobis_stacked(sensor, stack.mean, stack.cov, chosen)
        rows, ks = np.nonzero(d2 <= gate_threshold(pg, sensor.dim))
        if not rows.size:
            continue
        at = np.asarray(cols, dtype=np.intp)[ks]  # the pairs' measurement indices
        pairs = [chosen[k] for k in ks.tolist()]
        if stack is None:
            found = _pair_scores(
                filt, each, sensor, list(zip(rows.tolist(), pairs)), rng, keep_posteriors
            )
            pair_ll = np.array([f for f, _ in found], dtype=float)
            if keep_posteriors:
                posteriors.update(zip(zip(rows.tolist(), at.tolist()), (p for _, p in found)))
        else:
            post, pair_ll = _stacked_pair_scores(filt, stack, rows, pairs, rng)
            stacked_parts.append((rows, at, post))
        ll[rows, at] = np.where(np.isfinite(pair_ll), log_pd[rows] + pair_ll, -np.inf)
    with np.errstate(divide="ignore"):
        log_missed = np.log1p(-pd * pg)
    scores = ScanLikelihoods(tuple(int(t) for t in track_ids), ll, log_missed, log_clutter)
    if not keep_posteriors:
        return scores
    if stack is not None:
        return scores, _pair_posteriors(stacked_parts, stack.dim)
    return scores, posteriors


def _stacked_prior(filt: Filter[Any], beliefs: Sequence[Belief]) -> Gaussian | None:
    """The beliefs as one batched Gaussian when the filter updates them in one call
    (:func:`.batch.batchable`), else None (the per-track path)."""
    if not len(beliefs) or not callable(getattr(filt, "update_with_likelihood", None)):
        return None
    return stack_gaussians(cast(Sequence[Gaussian], beliefs)) if batchable(filt, beliefs) else None


def _stacked_pair_scores(
    filt: Filter[Any],
    stack: Gaussian,
    rows: NDArray[np.intp],
    measurements: Sequence[Measurement],
    rng: np.random.Generator | None,
) -> tuple[Gaussian, Array]:
    """``(posteriors (P, d), log p(z | track) (P,))`` of the gated pairs ``(rows[p],
    measurements[p])`` of one sensor, from the stacked prior: one batched filter call (one
    unbatched call for a lone pair, as :func:`.batch.update_pairs` does)."""
    if rows.size == 1:
        r = int(rows[0])
        post, ll = filt.update_with_likelihood(  # type: ignore[attr-defined]
            Gaussian(stack.mean[r], stack.cov[r]), [measurements[0]], rng
        )
        return Gaussian(post.mean[None], post.cov[None]), np.array([float(np.asarray(ll))])
    return update_stacked(filt, Gaussian(stack.mean[rows], stack.cov[rows]), measurements, rng)


def _pair_posteriors(parts: Sequence[tuple[Any, Any, Gaussian]], dim: int) -> PairPosteriors:
    """The :class:`.batch.PairPosteriors` of every sensor's gated pairs, in one stack."""
    if not parts:
        empty = np.zeros(0, np.intp)
        return PairPosteriors(empty, empty, Gaussian(np.zeros((0, dim)), np.zeros((0, dim, dim))))
    return PairPosteriors(
        np.concatenate([r for r, _, _ in parts]),
        np.concatenate([c for _, c, _ in parts]),
        Gaussian(
            np.concatenate([g.mean for _, _, g in parts]),
            np.concatenate([g.cov for _, _, g in parts]),
        ),
    )
