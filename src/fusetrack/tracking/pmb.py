r"""The track-oriented Poisson multi-Bernoulli filter (TOMB/P) of Williams 2015, "Marginal
multi-Bernoulli filters: RFS derivation of MHT, JIPDA and association-based MeMBer", IEEE Trans.
AES 51(3) (arXiv:1203.2995), with Gaussian single-target densities (Kalman, or
EKF-linearised).

The multi-target density is a Poisson point process of the targets never detected (a labelled
Gaussian-mixture intensity :class:`~fusetrack.filters.PhdIntensity`, as in the GM-PHD filter)
times independent Bernoullis, one per potentially detected target (existence ``r_i``, density
``N(x; m_i, P_i)``): :class:`PMBDensity`.

**Predict** (Williams' PMB prediction): the Poisson intensity is the GM-PHD prediction (``p_S w``,
Kalman-predicted components, the birth intensity appended); every Bernoulli ``r_i <- p_S r_i``
with its Gaussian predicted -- the GM-PHD prediction of a one-component "intensity" without
births, so both reuse :meth:`~fusetrack.filters.GMPHDFilter.predict`.

**Update** with one sensor's detections ``z_1..z_M`` (Williams' PMB update and its TOMB/P
algorithm)::

    Bernoulli i missed       w_i0 = 1 - r_i P_D,  r = r_i (1 - P_D) / (1 - r_i P_D),  N(m_i, P_i)
    Bernoulli i took z_j     w_ij = r_i P_D q_ij, r = 1,  the Kalman update of N(m_i, P_i)
    z_j not a track's        e_j  = kappa(z_j) + sum_c P_D w_c q_cj,
                             a new Bernoulli, r = (e_j - kappa(z_j)) / e_j, the Kalman-updated
                             Poisson components mixed with weights P_D w_c q_cj

with ``q = N(z; h(m), H P H^T + R)`` (:meth:`~fusetrack.filters.GMPHDFilter.detection_terms`).
The association problem is JPDA's with clutter ``kappa`` replaced by ``e_j``, so the marginal
probabilities ``beta_ij`` come from the JPDA marginals of the scores ``log w_ij``,
``log w_i0``, ``log e_j`` (:meth:`~fusetrack.association.JointProbabilisticDataAssociation.
marginals`: loopy belief propagation, Williams & Lau 2014, or exact enumeration on clusters
small enough); the measurement's "not a track's" marginal is ``1 - sum_i beta_ij``. Each
Bernoulli becomes its hypotheses' mixture (existence ``beta_i0 r_miss + sum_j beta_ij``, the
Gaussian moment-matched, :func:`~fusetrack.tracking.combine_hypotheses`), the new Bernoulli of
``z_j`` has existence ``(1 - sum_i beta_ij) (e_j - kappa) / e_j``, and the Poisson intensity
is scaled by ``1 - P_D`` then pruned and merged (Vo & Ma 2006, Table II). Bernoullis with
existence below ``existence_threshold`` are dropped.

Gating: a pair ``(i, j)`` enters only when ``(w_ij / e_j) / (w_ij / e_j + w_i0)`` -- a bound
on its marginal ``beta_ij`` (swap ``z_j`` for the miss in any event) -- exceeds
``gate_probability_floor`` (at ``P_D = 1`` and ``r_i = 1`` the missed weight is 0 and every
measurement is in the gate).

Several sensors in one scan are applied one after the other (exact for the PMB recursion up
to its approximations). A non-finite measurement says the sensor looked and saw nothing: only
the missed terms apply, and it is counted in ``stats.skipped_measurements``.

**Labels.** Every Bernoulli carries the integer label it was given when its measurement
created it (labels count up, scan by scan and in measurement order), and ``origins`` maps each
live label to ``(time, sensor_id, k)``: the scan and the sensor's ``k``-th detection in it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.special import logsumexp

from ..association import JointProbabilisticDataAssociation, ScanLikelihoods
from ..core import (
    ConfigError,
    Gaussian,
    Measurement,
    MotionModel,
    SensorModel,
    check_probability,
    invalid,
)
from ..filters import GMPHDFilter, PhdIntensity, prune_and_merge
from .mixing import combine_hypotheses

Array = NDArray[np.float64]
Origin = tuple[float, str, int]
Clutter = float | Callable[[Array], Any]

_LOG_TINY = float(np.log(np.finfo(float).tiny))
_LOG_MISS_FLOOR = float(np.log(1e-12))


@dataclass(frozen=True, eq=False)
class PMBDensity:
    """A Poisson multi-Bernoulli density: ``undetected`` the Poisson intensity of the targets
    never detected; ``tracks`` the Bernoullis, one component each (weight = existence ``r``,
    label = the Bernoulli's label, ``next_label`` the next one to give out); ``origins`` each
    Bernoulli's ``(time, sensor_id, k)`` (none for a Bernoulli given in the prior).

    As a :class:`~fusetrack.core.Belief`: ``mean`` and ``cov`` are the most probable
    Bernoulli's (NaN when there is none); :attr:`expected_count` the expected number of
    targets, ``sum_i r_i`` plus the Poisson mass."""

    undetected: PhdIntensity
    tracks: PhdIntensity
    origins: Mapping[int, Origin] = field(default_factory=dict)

    @classmethod
    def empty(cls, dim: int) -> PMBDensity:
        """No Bernoulli and no undetected target in a ``dim``-dimensional state space."""
        return cls(PhdIntensity.empty(dim), PhdIntensity.empty(dim))

    @property
    def existence(self) -> Array:
        """``(N,)``: every Bernoulli's probability of existence ``r_i``."""
        return self.tracks.weights

    @property
    def expected_count(self) -> float:
        return self.undetected.expected_count + self.tracks.expected_count

    @property
    def mean(self) -> Array:
        return self.tracks.mean

    @property
    def cov(self) -> Array:
        return self.tracks.cov


class PMBFilter:
    """The track-oriented PMB filter (Williams 2015; module doc) for any motion and sensor
    models the GM-PHD filter takes (exact Kalman updates for linear-Gaussian models, EKF
    linearisation otherwise).

    ``motion``, ``sensors``, ``birth``, ``survival_probability``, ``detection_probability``,
    ``clutter_intensity`` and the Poisson part's ``truncation_threshold``, ``merge_threshold``,
    ``max_components``, ``merge_rule`` are those of :class:`~fusetrack.filters.GMPHDFilter`.
    ``existence_threshold``: Bernoullis below it are dropped. ``gate_probability_floor``: the
    gate (module doc). ``max_exact_events``: clusters with at most that many joint events are
    enumerated exactly, larger ones by loopy belief propagation (``bp_iterations``,
    ``bp_tolerance``); 0 (default) is Williams' filter, belief propagation throughout.
    """

    def __init__(
        self,
        motion: MotionModel,
        sensors: Mapping[str, SensorModel] | Sequence[SensorModel],
        birth: PhdIntensity,
        *,
        survival_probability: float = 0.99,
        detection_probability: float | None = None,
        clutter_intensity: Clutter | Mapping[str, Clutter] = 0.0,
        existence_threshold: float = 1e-4,
        gate_probability_floor: float = 1e-9,
        max_exact_events: int = 0,
        bp_iterations: int = 200,
        bp_tolerance: float = 1e-10,
        truncation_threshold: float = 1e-5,
        merge_threshold: float = 4.0,
        max_components: int = 100,
        merge_rule: str = "mutual",
    ) -> None:
        common: dict[str, Any] = {
            "survival_probability": survival_probability,
            "detection_probability": detection_probability,
            "clutter_intensity": clutter_intensity,
        }
        self.undetected_filter = GMPHDFilter(
            motion,
            sensors,
            birth,
            truncation_threshold=truncation_threshold,
            merge_threshold=merge_threshold,
            max_components=max_components,
            merge_rule=merge_rule,
            **common,
        )
        self.track_filter = GMPHDFilter(motion, sensors, PhdIntensity.empty(motion.dim), **common)
        self.motion = motion
        self.sensors = self.undetected_filter.sensors
        self.stats = self.undetected_filter.stats
        self.existence_threshold = check_probability("existence_threshold", existence_threshold)
        self.gate_probability_floor = check_probability(
            "gate_probability_floor", gate_probability_floor
        )
        self.association = JointProbabilisticDataAssociation(
            max_exact_events=max_exact_events,
            bp_iterations=bp_iterations,
            bp_tolerance=bp_tolerance,
        )

    def __repr__(self) -> str:
        return f"PMBFilter(motion={self.motion!r}, sensors={sorted(self.sensors)})"

    def _check_belief(self, belief: PMBDensity) -> None:
        if not isinstance(belief, PMBDensity) or belief.tracks.dim != self.motion.dim:
            raise ConfigError(
                invalid("belief", belief, f"a PMBDensity of dimension {self.motion.dim}")
            )

    def predict(
        self, belief: PMBDensity, dt: float, rng: np.random.Generator | None = None
    ) -> PMBDensity:
        """The PMB prediction (module doc); ``rng`` is ignored."""
        self._check_belief(belief)
        return PMBDensity(
            self.undetected_filter.predict(belief.undetected, dt),
            self.track_filter.predict(belief.tracks, dt),
            belief.origins,
        )

    def update(
        self,
        belief: PMBDensity,
        measurements: Sequence[Measurement] | Measurement,
        rng: np.random.Generator | None = None,
    ) -> PMBDensity:
        """The posterior after one scan, each sensor in turn (module doc); ``rng`` is ignored."""
        self._check_belief(belief)
        ms = [measurements] if isinstance(measurements, Measurement) else list(measurements)
        scans = self.undetected_filter.sensor_scans(ms)
        times = {m.sensor_id: float(m.time) for m in ms}
        for sid, (values, covariances) in scans.items():
            belief = self._correct(belief, sid, values, covariances, times[sid])
        return belief

    def _correct(
        self,
        prior: PMBDensity,
        sid: str,
        values: Array,
        covariances: list[Array | None],
        time: float,
    ) -> PMBDensity:
        """One sensor's update (module doc)."""
        phd = self.undetected_filter
        tracks, poisson = prior.tracks, prior.undetected
        t_terms = phd.detection_terms(tracks, sid, values, covariances)
        u_terms = phd.detection_terms(poisson, sid, values, covariances)
        with np.errstate(divide="ignore"):
            log_born = np.log(u_terms.p_d * poisson.weights)[None, :] + u_terms.log_q  # (M, C)
            log_hit = (np.log(t_terms.p_d * tracks.weights)[None, :] + t_terms.log_q).T  # (N, M)
            log_miss = np.log1p(-t_terms.p_d * tracks.weights)
        with np.errstate(divide="ignore"):  # all -inf: no Poisson component can see z_j
            log_new = (
                logsumexp(log_born, axis=1)
                if poisson.n_components
                else np.full(len(values), -np.inf)
            )
        log_e = np.maximum(np.logaddexp(u_terms.log_kappa, log_new), _LOG_TINY)
        beta = self.marginals(log_hit, log_miss, log_e)
        posterior = _updated_tracks(tracks, t_terms, beta)
        new_r = np.clip(1.0 - beta[:, :-1].sum(axis=0), 0.0, 1.0) * np.exp(log_new - log_e)
        born = _new_tracks(poisson, u_terms, log_born, new_r, posterior.next_label)
        merged = _concat_tracks(posterior, born)
        keep = (merged.weights >= self.existence_threshold) & (merged.weights > 0.0)
        kept = PhdIntensity(
            merged.weights[keep],
            merged.means[keep],
            merged.covs[keep],
            merged.labels[keep],
            merged.next_label,
        )
        origins = {**prior.origins, **_origins(born, new_r, time, sid)}
        missed = PhdIntensity(
            (1.0 - u_terms.p_d) * poisson.weights,
            poisson.means,
            poisson.covs,
            poisson.labels,
            poisson.next_label,
        )
        return PMBDensity(
            prune_and_merge(missed, **phd.prune_kw),
            kept,
            {int(lab): origins[int(lab)] for lab in kept.labels if int(lab) in origins},
        )

    def marginals(self, log_hit: Array, log_miss: Array, log_new: Array) -> Array:
        """``beta`` ``(N, M + 1)`` of the PMB association problem (last column: missed) from
        the log weights of the hits ``(N, M)``, misses ``(N,)`` and of each measurement not
        being a track's (``log e_j``, ``(M,)``), gated (module doc)."""
        n, m = log_hit.shape
        if not (n and m):
            beta = np.zeros((n, m + 1))
            beta[:, -1] = 1.0
            return beta
        ratio = log_hit - log_new[None, :]
        with np.errstate(invalid="ignore"):
            bound = ratio - np.logaddexp(ratio, log_miss[:, None])
        gated = np.where(bound >= np.log(self.gate_probability_floor), log_hit, -np.inf)
        # belief propagation forms sum_{i' != i} mu_i'j as a difference, which cancels when a
        # track cannot be missed (P_D = r = 1, mu infinite): floor the miss at 1e-12 of the hit
        best = np.max(gated - log_new[None, :], axis=1)
        floor = np.where(np.isfinite(best), best + _LOG_MISS_FLOOR, -np.inf)
        scores = ScanLikelihoods(tuple(range(n)), gated, np.maximum(log_miss, floor), log_new)
        return self.association.marginals(scores)[0]


def _updated_tracks(tracks: PhdIntensity, terms: Any, beta: Array) -> PhdIntensity:
    """Every Bernoulli as the moment-matched mixture of its hypotheses (Williams' TOMB):
    existence ``beta_i0 r_miss + sum_j beta_ij``."""
    n, d = tracks.means.shape
    r, p_d = tracks.weights, terms.p_d
    with np.errstate(invalid="ignore", divide="ignore"):
        r_miss = np.nan_to_num(r * (1.0 - p_d) / (1.0 - r * p_d), nan=0.0)
    weights = np.concatenate([(beta[:, -1] * r_miss)[:, None], beta[:, :-1]], axis=1)
    existence = np.clip(weights.sum(axis=1), 0.0, 1.0)
    means, covs = np.empty((n, d)), np.empty((n, d, d))
    for i in range(n):
        prior = Gaussian(tracks.means[i], tracks.covs[i])
        if existence[i] <= 0.0:
            means[i], covs[i] = prior.mean, prior.cov
            continue
        hits = np.flatnonzero(weights[i, 1:] > 0.0)
        beliefs = [prior] + [
            Gaussian(terms.means[j, i], terms.covs[j if terms.covs.shape[0] > 1 else 0, i])
            for j in hits
        ]
        g = combine_hypotheses(beliefs, [weights[i, 0], *weights[i, 1 + hits]])
        means[i], covs[i] = g.mean, g.cov
    return PhdIntensity(existence, means, covs, tracks.labels, tracks.next_label)


def _new_tracks(
    poisson: PhdIntensity, terms: Any, log_born: Array, existence: Array, first_label: int
) -> PhdIntensity:
    """A Bernoulli per measurement ``z_j`` with existence ``existence[j]`` and the Poisson
    components updated with ``z_j``, moment-matched with weights ``P_D w_c q_cj``, labelled
    ``first_label + j`` (one with existence 0 gets a placeholder density, dropped after)."""
    m, d = len(existence), poisson.dim
    means, covs = np.zeros((m, d)), np.tile(np.eye(d), (m, 1, 1))
    alive = existence > 0.0
    for j in np.flatnonzero(alive):
        w = np.exp(log_born[j] - np.max(log_born[j]))
        used = np.flatnonzero(w > 0.0)
        beliefs = [
            Gaussian(terms.means[j, c], terms.covs[j if terms.covs.shape[0] > 1 else 0, c])
            for c in used
        ]
        g = combine_hypotheses(beliefs, w[used])
        means[j], covs[j] = g.mean, g.cov
    labels = np.arange(first_label, first_label + m, dtype=np.int64)
    return PhdIntensity(existence, means, covs, labels, first_label + m)


def _concat_tracks(a: PhdIntensity, b: PhdIntensity) -> PhdIntensity:
    return PhdIntensity(
        np.concatenate([a.weights, b.weights]),
        np.concatenate([a.means, b.means]),
        np.concatenate([a.covs, b.covs]),
        np.concatenate([a.labels, b.labels]),
        max(a.next_label, b.next_label),
    )


def _origins(born: PhdIntensity, existence: Array, time: float, sid: str) -> dict[int, Origin]:
    return {int(born.labels[j]): (time, sid, int(j)) for j in np.flatnonzero(existence > 0.0)}
