"""The generic filter loop: time-stamped measurements in, a :class:`~fusetrack.core.Track` out.

The loop is the same for every filter (Kalman family, particle filters, anything with
``predict(belief, dt, rng)`` and ``update(belief, measurements, rng)``)::

    belief = prior                                  (particle filters: filt.initialize(prior, rng))
    for each distinct time t (measurement times, plus the requested output `times`):
        belief = filt.predict(belief, t - t_prev, rng)        if t > t_prev
        belief = filt.update(belief, measurements at t, rng)  if there are any
        record belief.mean, belief.cov at t

Time steps may be irregular; measurements at the same time (within 1e-9 s) are applied together
(in the order given). Output times without measurements are predict-only steps.

``run_filter(..., smooth=True)`` keeps every step's belief and returns the smoothed track
instead (:mod:`~fusetrack.filters.smoothing` for the Kalman family,
:mod:`~fusetrack.filters.particle_smoothing` for particle filters), the filtered one in
``track.info["filtered"]``.

>>> import numpy as np
>>> from fusetrack.core import Gaussian, Measurement
>>> from fusetrack.filters import KalmanFilter
>>> from fusetrack.motion import ConstantVelocity
>>> from fusetrack.sensors import PositionFix
>>> kf = KalmanFilter(ConstantVelocity(q=0.1), [PositionFix("tag", cov=0.1 * np.eye(2))])
>>> zs = [Measurement(t, "tag", [t, 0.0]) for t in (0.0, 0.5, 1.5)]
>>> track = run_filter(kf, Gaussian(np.zeros(4), np.eye(4)), zs, times=[2.0])
>>> track.times
array([0. , 0.5, 1.5, 2. ])
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any, Literal, cast

import numpy as np
from numpy.typing import ArrayLike

from ..core import (
    ConfigError,
    Filter,
    Gaussian,
    LikelihoodFilter,
    Measurement,
    MeasurementError,
    Track,
    as_measurements,
    filter_step,
    group_by_time,
    invalid,
    order_by_time,
    step_with_likelihood,
)
from .kalman import GaussianFilter
from .particle import ParticleFilter
from .particle_smoothing import backward_simulation
from .smoothing import check_lag, rts_smoother, smoother_name
from .stats import validate_measurement

_TIME_TOLERANCE = 1e-9


def _steps(
    measurements: list[Measurement], times: ArrayLike | None
) -> list[tuple[float, list[Measurement]]]:
    """Merge measurement groups with the extra output times (predict-only steps)."""
    groups = list(group_by_time(measurements, tolerance=_TIME_TOLERANCE))
    if times is None:
        return groups
    extra = np.atleast_1d(np.asarray(times, dtype=float))
    if extra.ndim != 1 or not np.all(np.isfinite(extra)):
        raise ConfigError(invalid("times", times, "a 1-D sequence of finite times (seconds)"))
    steps: list[tuple[float, list[Measurement]]] = list(groups)
    group_times = np.array([t for t, _ in groups])
    for t in np.unique(extra):
        if group_times.size and np.min(np.abs(group_times - t)) <= _TIME_TOLERANCE:
            continue  # already an output time
        steps.append((float(t), []))
    steps.sort(key=lambda s: s[0])
    # two requested times closer than the tolerance collapse into one
    merged: list[tuple[float, list[Measurement]]] = []
    for t, group in steps:
        if merged and t - merged[-1][0] <= _TIME_TOLERANCE and not group:
            continue
        merged.append((t, group))
    return merged


def _batch_shape(measurements: list[Measurement]) -> tuple[int, ...]:
    shapes = [np.shape(m.value)[:-1] for m in measurements]
    try:
        return tuple(np.broadcast_shapes(*shapes)) if shapes else ()
    except ValueError:
        raise MeasurementError(
            invalid("measurement value batch shapes", sorted(set(shapes)), "shapes that broadcast")
        ) from None


def _check_options(filt: Filter[Any], order: str, log_likelihood: bool) -> None:
    """``order`` is known; ``log_likelihood`` only for filters that report it."""
    if order not in ("reject", "reorder"):
        raise ConfigError(invalid("order", order, "'reject' or 'reorder'"))
    if log_likelihood and not isinstance(filt, LikelihoodFilter):
        raise ConfigError(
            invalid(
                "log_likelihood",
                True,
                f"False for {type(filt).__name__}, which does not report log p(z_k | z_1:k-1) "
                "(no update_with_likelihood)",
            )
        )


def _initial_belief(
    filt: Filter[Any], prior: Any, rng: np.random.Generator | None, batch: tuple[int, ...]
) -> Any:
    """The belief to start from: a Gaussian prior becomes particles for a filter that samples
    (``initialize``), or is broadcast to the measurements' batch axes; other beliefs as given."""
    initialize = getattr(filt, "initialize", None)  # particle filters: a Gaussian prior -> samples
    is_sampler = callable(initialize)
    if is_sampler and rng is None:
        raise ConfigError(
            invalid(
                "rng",
                rng,
                f"a numpy Generator: {type(filt).__name__} draws random numbers "
                "(pass np.random.default_rng(seed))",
            )
        )
    belief = prior
    if isinstance(prior, Gaussian):
        if is_sampler:
            if batch and prior.mean.ndim == 1:
                belief = initialize(prior, rng, batch_shape=batch)  # type: ignore[misc]
            else:
                belief = initialize(prior, rng)  # type: ignore[misc]
        else:
            full = np.broadcast_shapes(prior.mean.shape[:-1], prior.cov.shape[:-2], batch)
            d = prior.dim
            belief = Gaussian(
                np.broadcast_to(prior.mean, (*full, d)).copy(),
                np.broadcast_to(prior.cov, (*full, d, d)).copy(),
            )
    return belief


def _start_time(t0: float | None, steps: list[tuple[float, list[Measurement]]]) -> float:
    """The prior's time: ``t0`` (finite, not after the first step) or the first step's time."""
    if t0 is not None:
        t0 = float(t0)
        if not math.isfinite(t0):
            raise ConfigError(invalid("t0", t0, "a finite time (seconds) or None"))
        if steps and steps[0][0] < t0 - _TIME_TOLERANCE:
            raise MeasurementError(
                invalid("t0", t0, f"a time <= the first step's time {steps[0][0]}")
            )
    return t0 if t0 is not None else (steps[0][0] if steps else 0.0)


def _filter_loop(
    filt: Filter[Any],
    belief: Any,
    steps: list[tuple[float, list[Measurement]]],
    t_prev: float,
    rng: np.random.Generator | None,
    log_likelihood: bool,
    kept: list[tuple[Any, float]] | None = None,
) -> tuple[Any, list[float], list[np.ndarray], list[np.ndarray], Any]:
    """Predict and update at every step; the last belief, the estimates' times, means and
    covariances, and the summed log-likelihood increments (0 unless asked for). ``kept``
    (when given) receives every step's belief and the ``dt`` predicted over to reach it."""
    # a filter's own estimator (particle filters: one fused pass) beats the belief's generic one
    estimate = getattr(filt, "estimate", None)
    out_t: list[float] = []
    out_mean: list[np.ndarray] = []
    out_cov: list[np.ndarray] = []
    loglik: Any = 0.0
    for t, group in steps:
        dt = t - t_prev
        if dt > _TIME_TOLERANCE:
            t_prev = t
        else:
            dt = 0.0
        if log_likelihood and group:
            belief, increment = step_with_likelihood(filt, belief, dt, group, rng)  # type: ignore[arg-type]
            loglik = loglik + increment
        else:
            belief = filter_step(filt, belief, dt, group, rng)
        if kept is not None:
            kept.append((belief, dt))
        out_t.append(t)
        summary = estimate(belief) if estimate is not None else belief
        out_mean.append(np.asarray(summary.mean))
        out_cov.append(np.asarray(summary.cov))
    return belief, out_t, out_mean, out_cov, loglik


def run_filter(
    filt: Filter[Any],
    prior: Any,
    measurements: Iterable[Measurement | tuple[Any, ...]],
    *,
    rng: np.random.Generator | None = None,
    order: Literal["reject", "reorder"] = "reject",
    times: ArrayLike | None = None,
    t0: float | None = None,
    log_likelihood: bool = False,
    smooth: bool = False,
    lag: int | None = None,
) -> Track:
    """Run ``filt`` from ``prior`` over ``measurements`` and return the filtered track.

    Parameters
    ----------
    filt:
        any :class:`~fusetrack.core.Filter`: ``predict(belief, dt, rng)`` and
        ``update(belief, measurements, rng)``, or its own ``step`` when it has one
        (:func:`~fusetrack.core.filter_step`).
        If it also has ``initialize(prior, rng[, batch_shape])`` (particle filters) and
        ``prior`` is a :class:`~fusetrack.core.Gaussian`, the prior is turned into particles
        with it.
    prior:
        the belief at time ``t0``: a Gaussian (Kalman filters; particle filters) or the
        filter's own belief type (e.g. :class:`~fusetrack.core.Particles`). It may carry batch
        axes; an unbatched prior is broadcast to the measurements' batch axes ``(R, m)``.
    measurements:
        :class:`~fusetrack.core.Measurement` objects or ``(time, sensor_id, value[, cov])``
        tuples, in time order.
    rng:
        the random generator; required for filters that draw (those with ``initialize``).
    order:
        ``"reject"`` raises :class:`~fusetrack.core.MeasurementError` at the first timestamp
        that goes backwards; ``"reorder"`` sorts the measurements by time (stable).
    times:
        extra output times; where no measurement falls the step is predict-only.
    t0:
        the time of ``prior``; default the first step's time (no prediction before the first
        update). Steps before ``t0`` raise :class:`~fusetrack.core.MeasurementError`.

    log_likelihood:
        also sum the filter's log-likelihood increments ``log p(z_k | z_1:k-1)`` into
        ``track.info["log_likelihood"]`` (per batch entry); the filter must be a
        :class:`~fusetrack.core.LikelihoodFilter`.
    smooth:
        return the smoothed track instead: the RTS smoother for
        :class:`KalmanFilter`, :class:`ExtendedKalmanFilter` and :class:`UnscentedKalmanFilter`
        (:func:`~fusetrack.filters.rts_smoother`), backward simulation for the
        :class:`ParticleFilter` family (:func:`~fusetrack.filters.backward_simulation`, drawing
        from ``rng``, which must then be one Generator; as many trajectories as particles).
        Other filters raise :class:`~fusetrack.core.ConfigError` before any work. The
        filtering itself is unchanged (the same draws as without ``smooth``).
    lag:
        with ``smooth``: None for fixed-interval smoothing (every estimate uses every
        measurement), an int ``L >= 0`` for fixed-lag smoothing (the estimate at step ``k`` uses
        the measurements up to step ``k + L``).

    Returns
    -------
    Track
        ``times`` ``(T,)``, ``means`` ``(T, ..., d)``, ``covariances`` ``(T, ..., d, d)`` — the
        belief after the update at each step. ``info["stats"]`` holds how much each of
        ``filt.stats``'s counters grew during this run. With ``smooth=True`` the smoothed
        estimates at the same times; ``info`` keeps the filtered track's entries and adds
        ``"filtered"`` (the filtered track), ``"smoother"`` (the method's name), ``"lag"`` and,
        for particle filters, ``"samples"`` ``(T, ..., M, d)``: the backward draws the
        smoothed means and covariances are taken from (joint trajectories for ``lag=None``).
    """
    _check_options(filt, order, log_likelihood)
    _check_smoothing(filt, smooth, lag, rng)
    ms = order_by_time(as_measurements(measurements), order)
    sensors = getattr(filt, "sensors", None)
    if isinstance(sensors, Mapping):  # unknown sensors and wrong sizes fail before any work
        for m in ms:
            validate_measurement(m, sensors)
    steps = _steps(ms, times)
    belief = _initial_belief(filt, prior, rng, _batch_shape(ms))
    stats = getattr(filt, "stats", None)
    before = stats.as_dict() if stats is not None else {}
    t_prev = _start_time(t0, steps)
    kept: list[tuple[Any, float]] | None = [] if smooth else None
    belief, out_t, out_mean, out_cov, loglik = _filter_loop(
        filt, belief, steps, t_prev, rng, log_likelihood, kept
    )

    info: dict[str, Any] = {"filter": type(filt).__name__}
    if log_likelihood:
        info["log_likelihood"] = loglik
    if stats is not None:
        after = stats.as_dict()
        info["stats"] = {k: after[k] - before.get(k, 0) for k in after}
    track = _as_track(type(filt).__name__, belief, out_t, out_mean, out_cov, info)
    if kept is None:
        return track
    return _smoothed(filt, track, kept, rng, lag)


def _as_track(
    label: str,
    belief: Any,
    times: list[float],
    means: list[Any],
    covs: list[Any],
    info: dict[str, Any],
) -> Track:
    """The filtered estimates as a :class:`~fusetrack.core.Track` (empty: shaped like ``belief``)."""
    if not times:
        mean0 = np.asarray(belief.mean)
        empty = np.empty((0, *mean0.shape))
        return Track(np.empty(0), empty, np.empty((*empty.shape, mean0.shape[-1])), label, info)
    return Track(np.array(times), np.stack(means), np.stack(covs), label, info)


def _check_smoothing(
    filt: Filter[Any], smooth: bool, lag: int | None, rng: np.random.Generator | None
) -> None:
    """``smooth`` is a bool, ``lag`` only with it, and ``filt`` is a filter we can smooth."""
    if not isinstance(smooth, bool | np.bool_):
        raise ConfigError(invalid("smooth", smooth, "True or False"))
    if not smooth:
        if lag is not None:
            raise ConfigError(invalid("lag", lag, "None unless smooth=True"))
        return
    check_lag(lag)
    if smoother_name(filt) is not None:
        return
    if isinstance(filt, ParticleFilter) and callable(getattr(filt.motion, "log_density", None)):
        if not isinstance(rng, np.random.Generator):
            raise ConfigError(
                invalid(
                    "rng",
                    rng,
                    "one numpy Generator with smooth=True: the backward simulation draws from it",
                )
            )
        return
    raise ConfigError(
        invalid(
            "smooth",
            True,
            f"False for {type(filt).__name__}: smoothing is implemented for KalmanFilter, "
            "ExtendedKalmanFilter, UnscentedKalmanFilter (RTS) and the ParticleFilter family "
            "(BootstrapFilter, RegularizedParticleFilter, AuxiliaryParticleFilter; backward "
            "simulation)",
        )
    )


def _smoothed(
    filt: Filter[Any],
    filtered: Track,
    kept: list[tuple[Any, float]],
    rng: np.random.Generator | None,
    lag: int | None,
) -> Track:
    """The smoothed track at the filtered track's times; ``info`` adds ``"filtered"`` (the
    filtered track), ``"smoother"`` (its name), ``"lag"`` and, for particle filters,
    ``"samples"`` ``(T, ..., M, d)`` (the backward draws: joint trajectories for
    ``lag=None``, draws of each step's fixed-lag marginal otherwise)."""
    name = smoother_name(filt) or "backward simulation"
    info: dict[str, Any] = {**filtered.info, "filtered": filtered, "smoother": name, "lag": lag}
    if not kept:
        return Track(filtered.times, filtered.means, filtered.covariances, filtered.label, info)
    beliefs = [b for b, _ in kept]
    dts = np.array([dt for _, dt in kept[1:]])
    if isinstance(filt, ParticleFilter):
        samples = backward_simulation(
            filt.motion, beliefs, dts, cast(np.random.Generator, rng), lag=lag
        )
        info["samples"] = samples
        means = samples.mean(axis=-2)
        r = samples - means[..., None, :]
        covs = np.einsum("...mi,...mj->...ij", r, r) / samples.shape[-2]
    else:
        means, covs = rts_smoother(
            cast(GaussianFilter, filt),
            np.stack([b.mean for b in beliefs]),
            np.stack([b.cov for b in beliefs]),
            dts,
            lag=lag,
        )
    return Track(filtered.times, means, covs, f"{filtered.label} ({name})", info)
