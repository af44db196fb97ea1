"""Many tracks through one filter call: the Kalman family's batch axes, used when they apply.

A :class:`~fusetrack.filters.GaussianFilter` (Kalman, extended, unscented) runs a belief with
leading batch axes ``(K, d)`` as ``K`` independent filters, in a handful of array operations
instead of ``K`` Python calls. So a tracker predicts all its Gaussian tracks at once
(:func:`predict_many`) and :func:`~fusetrack.association.scan_likelihoods` updates all the gated
(track, measurement) pairs of a sensor at once (:func:`update_pairs`). Any other filter (or a
subclass that overrides ``predict`` / ``update_with_likelihood``, which might not keep the
batch semantics) goes one call per track; both give the same numbers (to rounding: the batched
products may sum in another order).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..core import Gaussian, Measurement


def batchable(filt: Any, beliefs: Sequence[Any]) -> bool:
    """True when ``filt`` is a Gaussian filter with its own batched ``predict`` and
    ``update_with_likelihood`` and every belief is one (unbatched) Gaussian."""
    from ..filters import GaussianFilter  # here: importing filters is slow (Numba)

    kind = type(filt)
    return (
        isinstance(filt, GaussianFilter)
        and kind.predict is GaussianFilter.predict
        and kind.update_with_likelihood is GaussianFilter.update_with_likelihood
        and all(isinstance(b, Gaussian) and b.mean.ndim == 1 for b in beliefs)
    )


def stack_gaussians(beliefs: Sequence[Gaussian]) -> Gaussian:
    """One batched Gaussian ``(K, d)`` / ``(K, d, d)`` of ``K`` (unbatched) ones."""
    # np.array of equal-shape arrays is np.stack's result, without its per-call checks
    return Gaussian(np.array([b.mean for b in beliefs]), np.array([b.cov for b in beliefs]))


class PairPosteriors(Mapping[tuple[int, int], Gaussian]):
    """The posteriors of a scan's gated (track row, measurement) pairs, kept as one batched
    Gaussian: row ``p`` of ``stacked`` is pair ``(rows[p], cols[p])``. A read-only mapping
    ``(row, col) -> Gaussian`` like the per-pair dict of the unbatched path, whose arrays a
    tracker can also use whole (:func:`fusetrack.tracking.mixing.combine_stacked`)."""

    def __init__(self, rows: NDArray[np.intp], cols: NDArray[np.intp], stacked: Gaussian) -> None:
        self.rows, self.cols, self.stacked = rows, cols, stacked
        self._pairs: dict[tuple[int, int], int] | None = None  # built when first looked up

    @property
    def _index(self) -> dict[tuple[int, int], int]:
        """``(row, col) -> p``."""
        if self._pairs is None:
            pairs = zip(self.rows.tolist(), self.cols.tolist(), strict=True)
            self._pairs = {pair: p for p, pair in enumerate(pairs)}
        return self._pairs

    def restrict(
        self, rows: Sequence[int], cols: Sequence[int], shape: tuple[int, int]
    ) -> PairPosteriors:
        """The pairs of the sub-block ``rows`` x ``cols`` (of a ``shape`` scan), renumbered
        as rows and columns of the block (both in increasing order: the pairs keep theirs)."""
        row_of = np.full(shape[0], -1, dtype=np.intp)
        row_of[np.asarray(rows, dtype=np.intp)] = np.arange(len(rows))
        col_of = np.full(shape[1], -1, dtype=np.intp)
        col_of[np.asarray(cols, dtype=np.intp)] = np.arange(len(cols))
        new_rows, new_cols = row_of[self.rows], col_of[self.cols]
        keep = (new_rows >= 0) & (new_cols >= 0)
        kept = Gaussian(self.stacked.mean[keep], self.stacked.cov[keep])
        return PairPosteriors(new_rows[keep], new_cols[keep], kept)

    def __getitem__(self, pair: tuple[int, int]) -> Gaussian:
        p = self._index[pair]
        return Gaussian(self.stacked.mean[p], self.stacked.cov[p])

    def __iter__(self) -> Iterator[tuple[int, int]]:
        return iter(self._index)

    def __len__(self) -> int:
        return len(self._index)


def predict_many(
    filt: Any, beliefs: Sequence[Any], dt: float, rng: np.random.Generator | None
) -> list[Any]:
    """``[filt.predict(b, dt, rng) for b in beliefs]``, batched when :func:`batchable`."""
    stacked = predict_stacked(filt, beliefs, dt, rng)
    if stacked is not None:
        return stacked.unstack()
    return [filt.predict(b, dt, rng) for b in beliefs]


def predict_stacked(
    filt: Any, beliefs: Sequence[Any], dt: float, rng: np.random.Generator | None
) -> Gaussian | None:
    """The predictions of two or more :func:`batchable` beliefs as one batched Gaussian
    ``(K, d)`` (one filter call), else None."""
    if len(beliefs) > 1 and batchable(filt, beliefs):
        return filt.predict(stack_gaussians(beliefs), dt, rng)
    return None


def update_pairs(
    filt: Any,
    beliefs: Sequence[Any],
    measurements: Sequence[Measurement],
    rng: np.random.Generator | None,
) -> list[tuple[Any, float]]:
    """``filt.update_with_likelihood(beliefs[k], [measurements[k]], rng)`` for every ``k`` as
    ``(posterior, log-likelihood)``. Batched when :func:`batchable` and the measurements are
    vectors of one sensor: their values stacked ``(K, m)``, their covariances too when any has
    its own (the others take the sensor's ``R`` at the belief's mean; :func:`update_stacked`)."""
    same_sensor = len({m.sensor_id for m in measurements}) == 1
    vectors = all(isinstance(m.value, np.ndarray) and m.value.ndim == 1 for m in measurements)
    if len(beliefs) < 2 or not (same_sensor and vectors and batchable(filt, beliefs)):
        out = []
        for b, m in zip(beliefs, measurements):
            post, ll = filt.update_with_likelihood(b, [m], rng)
            out.append((post, float(np.asarray(ll))))
        return out
    post, ll = update_stacked(filt, stack_gaussians(beliefs), measurements, rng)
    return list(zip(post.unstack(), ll.tolist()))


def update_stacked(
    filt: Any,
    prior: Gaussian,
    measurements: Sequence[Measurement],
    rng: np.random.Generator | None,
) -> tuple[Gaussian, NDArray[np.float64]]:
    """``filt.update_with_likelihood`` of the batched ``prior`` ``(K, d)``, row ``k`` with
    ``measurements[k]`` (vectors of one sensor), in one call: ``(posterior (K, d), log
    likelihoods (K,))``. The filter must be :func:`batchable`. The values are stacked
    ``(K, m)``, their covariances too when any has its own (the others take the sensor's ``R``
    at the row's mean)."""
    first = measurements[0]
    cov = None
    if any(m.covariance is not None for m in measurements):
        sensor = filt.sensors[first.sensor_id]
        cov = np.stack(
            [
                np.asarray(sensor.noise_cov(mean) if m.covariance is None else m.covariance)
                for mean, m in zip(prior.mean, measurements)
            ]
        )
    stacked = Measurement(
        first.time, first.sensor_id, np.array([m.value for m in measurements]), cov
    )
    post, ll = filt.update_with_likelihood(prior, [stacked], rng)
    return post, np.asarray(ll, dtype=float).reshape(len(measurements))
