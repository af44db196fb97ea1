"""Score one scan: the :class:`~fusetrack.association.ScanLikelihoods` of some tracks against
some measurements, computed with the tracks' own filter, and the posteriors that go with it.

For every pair (track ``i``, measurement ``j``) inside the gate the filter's
``update_with_likelihood(prediction_i, [z_j], rng)`` gives the single-measurement posterior and
``log p(z_j | track i)``, so any :class:`~fusetrack.core.LikelihoodFilter` (Kalman family,
particle filters) scores with its own belief and each measurement's own sensor. The scores
follow the parametric JPDA convention (Bar-Shalom, Daum & Huang 2009, "The probabilistic data
association filter", IEEE Control Systems 29(6); Blackman & Popoli 1999, Ch. 6)::

    log_likelihood[i, j] = log P_D + log p(z_j | track i)      (-inf outside the gate)
    log_missed[i]        = log(1 - P_D P_G)
    log_clutter[j]       = log(clutter density of z_j's sensor)   (lambda c(z), per unit volume)

so that a joint association event ``theta`` has posterior
``prod_{(i,j) in theta} exp(l_ij) / kappa_j  prod_{i missed} (1 - P_D P_G)`` from the scores
alone. (``log P_D`` is part of ``log_likelihood``, as the GNN and JPDA associators written
alongside this module expect; ``association/base.py`` describes the bare
``log p(z_j | track i)``, which is ``log_likelihood - log P_D`` here.)

The gate (Bar-Shalom, Willett & Tian 2011, Sec. 3.2) is the Mahalanobis distance of the
innovation on the Gaussian approximation of the belief (its ``mean`` and ``cov``, whatever the
belief is), linearised at the mean: ``y = residual(z, h(x))``, ``S = H P H^T + R``,
``y^T S^-1 y <= chi2_m^-1(P_G)``. It is computed for all pairs in a few batched array
operations; only the pairs inside it pay for a filter update (one batched call per sensor for
the Kalman family, :mod:`.batch`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2

from ..association import ScanLikelihoods
from ..core import Measurement, SensorModel
from .batch import update_pairs

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class ScoredScan:
    """The scores of one scan and, for each gated pair ``(i, j)`` (row and column of the
    scores), the filter's single-measurement posterior of track ``i`` given ``z_j``."""

    scores: ScanLikelihoods
    posteriors: Mapping[tuple[int, int], Any]


def gate_threshold(gate_probability: float, dim: int) -> float:
    """``chi2_dim^-1(P_G)``: the squared Mahalanobis distance that holds a fraction ``P_G`` of
    the measurements of a track (``inf`` for ``P_G = 1``: no gate)."""
    if gate_probability >= 1.0:
        return float("inf")
    return float(chi2.ppf(gate_probability, dim))


def mahalanobis_squared(
    sensor: SensorModel, beliefs: Sequence[Any], measurements: Sequence[Measurement]
) -> Array:
    """``(T, M)``: ``y^T S^-1 y`` of each measurement (all of ``sensor``) against each belief's
    Gaussian approximation, linearised at its mean (``S = H P H^T + R``, ``R`` the measurement's
    own covariance when it has one). Non-vector reports (read only by their sensor) get 0."""
    n_t, n_m = len(beliefs), len(measurements)
    out = np.zeros((n_t, n_m))
    vector = [j for j, m in enumerate(measurements) if isinstance(m.value, np.ndarray)]
    if not n_t or not vector:
        return out
    means = np.stack([np.asarray(b.mean, float) for b in beliefs])  # (T, d)
    covs = np.stack([np.asarray(b.cov, float) for b in beliefs])  # (T, d, d)
    h = np.asarray(sensor.jacobian(means), float)  # (T, m, d)
    z_pred = np.asarray(sensor.predict(means), float)  # (T, m)
    hph = h @ covs @ np.swapaxes(h, -1, -2)  # (T, m, m)
    r_sensor = np.broadcast_to(np.asarray(sensor.noise_cov(means), float), hph.shape)
    values = np.stack([measurements[j].value for j in vector])  # (M', m)
    r = np.stack([_noise(measurements[j], r_sensor) for j in vector], axis=1)  # (T, M', m, m)
    s = hph[:, None] + r
    y = np.asarray(sensor.residual(values[None, :, :], z_pred[:, None, :]), float)  # (T, M', m)
    try:
        s_inv_y = np.linalg.solve(s, y[..., None])[..., 0]
    except np.linalg.LinAlgError:  # a singular S (no noise, no uncertainty): least squares
        s_inv_y = (np.linalg.pinv(s, hermitian=True) @ y[..., None])[..., 0]
    out[:, vector] = np.einsum("tmi,tmi->tm", y, s_inv_y)
    return out


def _noise(measurement: Measurement, sensor_noise: Array) -> Array:
    """The measurement's own covariance when it has one, else the sensor's, as ``(T, m, m)``."""
    if measurement.covariance is None:
        return sensor_noise
    return np.broadcast_to(np.asarray(measurement.covariance, float), sensor_noise.shape)


def score_scan(
    filt: Any,
    sensors: Mapping[str, SensorModel],
    track_ids: Sequence[int],
    predictions: Sequence[Any],
    measurements: Sequence[Measurement],
    *,
    p_detect: float,
    clutter_density: float,
    gate_probability: float,
    rng: np.random.Generator | None = None,
) -> ScoredScan:
    """Score ``measurements`` (all from sensors with detection probability ``p_detect`` and
    clutter density ``clutter_density``) against the tracks' ``predictions`` (module docstring).

    ``filt`` must have ``update_with_likelihood`` (a :class:`~fusetrack.core.LikelihoodFilter`).
    """
    n_t, n_m = len(predictions), len(measurements)
    log_lik = np.full((n_t, n_m), -np.inf)
    posteriors: dict[tuple[int, int], Any] = {}
    by_sensor: dict[str, list[int]] = {}
    for j, m in enumerate(measurements):
        by_sensor.setdefault(m.sensor_id, []).append(j)
    log_pd = float(np.log(p_detect))
    for sid, cols in by_sensor.items():
        sensor = sensors[sid]
        d2 = mahalanobis_squared(sensor, predictions, [measurements[j] for j in cols])
        inside = d2 <= gate_threshold(gate_probability, int(sensor.dim))
        pairs = [(int(i), cols[int(c)]) for i, c in zip(*np.nonzero(inside))]
        updates = update_pairs(
            filt, [predictions[i] for i, _ in pairs], [measurements[j] for _, j in pairs], rng
        )
        for (i, j), (post, ll) in zip(pairs, updates):
            posteriors[(i, j)] = post
            score = log_pd + ll
            log_lik[i, j] = score if not np.isnan(score) else -np.inf  # a degenerate update
    missed = (
        float(np.log1p(-p_detect * gate_probability))
        if p_detect * gate_probability < 1
        else -np.inf
    )
    scores = ScanLikelihoods(
        track_ids=tuple(int(t) for t in track_ids),
        log_likelihood=log_lik,
        log_missed=np.full(n_t, missed),
        log_clutter=np.full(n_m, float(np.log(clutter_density))),
    )
    return ScoredScan(scores, posteriors)
