"""``log p(z_1:T | model)`` from any filter that reports it, with whole-run fast paths.

:func:`log_likelihood` is the sum of a :class:`~fusetrack.core.LikelihoodFilter`'s increments
``log p(z_k | z_1:k-1)`` over a run (:func:`~fusetrack.filters.run_filter` with
``log_likelihood=True``): exact for the Kalman filter on a linear-Gaussian model (the
prediction-error decomposition, Harvey 1989, Sec. 3.4), an unbiased estimate of the likelihood
(not of its log) for a particle filter (Del Moral 2004, Prop. 7.4.1; Doucet & Johansen 2009,
Eq. 47). :class:`LogLikelihood` prepares the measurements once and evaluates many models on them,
several at once with :meth:`LogLikelihood.many`.

Fast paths (the same numbers, without the per-step Python of the generic loop): a
:class:`~fusetrack.filters.KalmanFilter` or a :class:`~fusetrack.filters.BootstrapFilter`
(systematic resampling, ``degenerate="keep"``, a Gaussian prior) whose motion model offers
``fused_transition`` and whose sensors are :class:`~fusetrack.sensors.LinearGaussianSensor` s
runs in one Numba call (:mod:`.linear_gaussian`); the particle filter's draws are the same as
the generic loop's, so a seed gives the same estimate to rounding. Anything else runs
:func:`~fusetrack.filters.run_filter`. :meth:`LogLikelihood.path` tells which.

>>> import numpy as np
>>> from fusetrack.core import Gaussian, Measurement
>>> from fusetrack.filters import KalmanFilter
>>> from fusetrack.motion import LinearGaussianMotion
>>> from fusetrack.sensors import LinearGaussianSensor
>>> kf = KalmanFilter(LinearGaussianMotion(F=[[1.0]], Q=[[0.5]]),
...                   [LinearGaussianSensor("s", H=[[1.0]], R=[[1.0]])])
>>> zs = [Measurement(float(t), "s", [z]) for t, z in enumerate([0.1, 0.4, -0.2])]
>>> round(log_likelihood(kf, Gaussian(np.zeros(1), np.eye(1)), zs), 6)  # by hand: S_k = 2
-3.874818
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from ..core import ConfigError, Filter, Gaussian, Measurement, invalid
from ..filters import BootstrapFilter, KalmanFilter, ParticleFilter, RunStreams, run_filter
from .linear_gaussian import bootstrap_log_likelihoods, kalman_log_likelihood
from .series import LinearGaussianArrays, Series, linear_gaussian_arrays, prepare_series

Array = NDArray[np.float64]
Route = Literal["bootstrap kernel", "kalman kernel", "run_filter"]

__all__ = ["LogLikelihood", "log_likelihood"]


def _sqrt_factor(cov: Array) -> Array:
    """``D D^T = cov``: Cholesky, or ``V sqrt(S)`` for a singular ``cov`` (as the filter)."""
    try:
        return np.asarray(np.linalg.cholesky(cov), dtype=np.float64)
    except np.linalg.LinAlgError:
        s, v = np.linalg.eigh(0.5 * (cov + cov.T))
        return np.asarray(v * np.sqrt(np.clip(s, 0.0, None)), dtype=float)


def _bootstrap_eligible(filt: Any) -> bool:
    """A plain bootstrap filter the kernel reproduces (systematic, ESS policy, "keep")."""
    return (
        type(filt) in (BootstrapFilter, ParticleFilter)
        and filt.proposal is None
        and filt.resampler == "systematic"
        and filt.degenerate == "keep"
    )


class LogLikelihood:
    """``log p(z_1:T | model)`` on one measurement series, for many models (module docstring).

    ``measurements`` as :func:`~fusetrack.filters.run_filter` takes them (in time order) or a
    prepared :class:`~.series.Series`; ``t0`` the prior's time (default: the first
    measurement's).
    """

    def __init__(
        self,
        measurements: Iterable[Measurement | tuple[Any, ...]] | Series,
        t0: float | None = None,
    ) -> None:
        self.series = prepare_series(measurements, t0)
        self._streams: RunStreams | None = None

    def _arrays(self, filt: Any, prior: Any) -> LinearGaussianArrays | None:
        if not isinstance(prior, Gaussian):
            return None
        return linear_gaussian_arrays(filt.motion, filt.sensors, prior, self.series)

    def path(self, filt: Filter[Any], prior: Any) -> Route:
        """Which evaluation ``filt`` and ``prior`` get: a whole-run kernel or the generic loop."""
        return self._route(filt, prior)[0]

    def _route(self, filt: Any, prior: Any) -> tuple[Route, LinearGaussianArrays | None]:
        if type(filt) is KalmanFilter or _bootstrap_eligible(filt):
            arrays = self._arrays(filt, prior)
            if arrays is not None:
                kind: Route = "kalman kernel" if type(filt) is KalmanFilter else "bootstrap kernel"
                return kind, arrays
        return "run_filter", None

    def __call__(
        self, filt: Filter[Any], prior: Any, rng: np.random.Generator | None = None
    ) -> float:
        """``log p(z_1:T)`` under ``filt`` started from ``prior`` (``rng``: the generator a
        particle filter draws from)."""
        return float(self.many([(filt, prior)], None if rng is None else [rng])[0])

    def _streams_of(self, rngs: Sequence[np.random.Generator]) -> RunStreams:
        streams = self._streams
        if streams is None or not streams.matches(rngs):
            if not all(isinstance(g, np.random.Generator) for g in rngs):
                raise ConfigError(
                    invalid("rng", rngs, "numpy Generators (np.random.default_rng(seed))")
                )
            streams = self._streams = RunStreams(rngs)
        return streams

    def many(
        self,
        models: Sequence[tuple[Filter[Any], Any]],
        rngs: Sequence[np.random.Generator] | None = None,
        *,
        threads: bool = False,
    ) -> Array:
        """``log p(z_1:T)`` for each ``(filter, prior)`` of ``models``, model ``p`` drawing from
        ``rngs[p]`` (distinct generators; needed for particle filters). Bootstrap filters with
        the same settings go through the kernel in one call (``threads``: on Numba's threads);
        others one by one. Returns ``(P,)``."""
        if rngs is not None and len(rngs) != len(models):
            raise ConfigError(invalid("rngs", f"{len(rngs)} generators", f"{len(models)}"))
        routes = [self._route(f, p) for f, p in models]
        out = np.empty(len(models))
        groups: dict[tuple[Any, ...], list[int]] = {}  # one kernel call per group
        for i, (kind, arrays) in enumerate(routes):
            if kind == "bootstrap kernel":
                assert arrays is not None
                key = (*self._pf_settings(models[i][0]), arrays.mean0.shape, arrays.Wz.shape)
                groups.setdefault(key, []).append(i)
        if groups and rngs is None:
            raise ConfigError(invalid("rng", None, "a numpy Generator for a particle filter"))
        for key, batch in groups.items():
            assert rngs is not None
            arrays_of = [routes[i][1] for i in batch]
            out[batch] = self._bootstrap(
                [a for a in arrays_of if a is not None], [rngs[i] for i in batch], key[:3], threads
            )
        for i, (kind, arrays) in enumerate(routes):
            if kind == "kalman kernel":
                assert arrays is not None
                out[i] = kalman_log_likelihood(
                    arrays.mean0, arrays.cov0, arrays.F, arrays.G, arrays.step_dt,
                    arrays.WH, arrays.Wz, arrays.c,
                )  # fmt: skip
            elif kind == "run_filter":
                out[i] = self._generic(*models[i], None if rngs is None else rngs[i])
        return out

    @staticmethod
    def _pf_settings(filt: Any) -> tuple[int, float, float]:
        return filt.n_particles, filt.ess_threshold, filt.min_log_evidence

    def _bootstrap(
        self,
        arrays: list[LinearGaussianArrays],
        rngs: list[np.random.Generator],
        settings: tuple[int, float, float],
        threads: bool,
    ) -> Array:
        """One kernel call for bootstrap filters of the same settings and shapes."""

        def stack(name: str) -> Array:
            return np.ascontiguousarray(np.stack([getattr(a, name) for a in arrays]))

        L0 = np.stack([_sqrt_factor(a.cov0) for a in arrays])
        return bootstrap_log_likelihoods(
            self._streams_of(rngs), stack("mean0"), L0, stack("F"), stack("G"),
            arrays[0].step_dt, stack("WH"), stack("Wz"), stack("c"), *settings, threads,
        )  # fmt: skip

    def _generic(self, filt: Filter[Any], prior: Any, rng: np.random.Generator | None) -> float:
        track = run_filter(
            filt, prior, self.series.measurements, rng=rng, t0=self.series.t0, log_likelihood=True
        )
        value = np.asarray(track.info["log_likelihood"], dtype=float)
        if value.ndim:
            raise ConfigError(
                invalid("measurements", f"batched values {value.shape}", "one run per series")
            )
        return float(value)


def log_likelihood(
    filt: Filter[Any],
    prior: Any,
    measurements: Iterable[Measurement | tuple[Any, ...]] | Series,
    rng: np.random.Generator | None = None,
    *,
    t0: float | None = None,
) -> float:
    """``log p(z_1:T)`` of ``measurements`` under ``filt`` from ``prior`` at ``t0`` (module
    docstring): exact for a Kalman filter, a particle filter's estimate drawn from ``rng``."""
    return LogLikelihood(measurements, t0)(filt, prior, rng)
