r"""The Gaussian-mixture cardinalised PHD filter (Vo, Vo & Cantoni 2007, IEEE TSP 55(7),
"Analytic Implementations of the Cardinalized Probability Hypothesis Density Filter").

The PHD filter (:mod:`fusetrack.filters.gm_phd`) carries only the intensity, so its target
count is implicitly Poisson and jumps after every missed detection. The CPHD filter also
carries the distribution of the number of targets ``p(n)``, ``n = 0..N`` (:class:`CphdBelief`);
the intensity's components, labels, Kalman updates, pruning and merging are the PHD filter's.

**Predict** (Sec. III-A; no spawning in the CPHD recursion)::

    p'(n) = sum_{j=0}^{n} p_b(n - j) sum_{l >= j} C(l, j) p_S^j (1 - p_S)^(l - j) p(l)

with ``p_b`` Poisson with the birth intensity's mass as mean, truncated at ``N`` and
renormalised; the intensity is predicted as in the PHD filter.

**Update** (Sec. III-B, Eqs. 25-29) with Poisson clutter of intensity ``kappa(z)``, for which the
clutter factors ``(|Z| - j)! p_K(|Z| - j)`` and ``<1, kappa> / kappa(z)`` reduce to a common
constant and ``1 / kappa(z)``. With ``W = sum_j w_j``, ``a = sum_j (1 - p_D,j) w_j``,
``x_z = sum_j p_D,j w_j q_j(z) / kappa(z)`` and ``e_i`` the elementary symmetric functions::

    U^u[Z](n) = sum_{i=0}^{min(|Z|, n-u)} n! / (n - i - u)! a^(n-i-u) / W^n e_i(x_Z)
    p(n)      = U^0[Z](n) p'(n) / <U^0[Z], p'>
    missed    w_j (1 - p_D,j) <U^1[Z], p'> / <U^0[Z], p'>
    detected  p_D,j w_j q_j(z) / kappa(z) <U^1[Z - {z}], p'> / <U^0[Z], p'>

``log p(Z) = log <U^0[Z], p'> + sum_z log kappa(z) - lambda_c`` (with a Poisson ``p'`` this is
the PHD filter's Poisson scan likelihood, and the update is the PHD update). ``kappa(z)`` must be
positive at every detection. Several sensors are applied in turn (iterated corrector), as in
the PHD filter. Everything is computed in logs; ``e_i`` by the recursion
``e_i(x_1..x_k) = e_i(x_1..x_{k-1}) + x_k e_{i-1}(x_1..x_{k-1})`` on ``x / max(x)``, whose terms
are all positive (no cancellation).

Example::

    >>> import numpy as np
    >>> from fusetrack.core import Measurement
    >>> from fusetrack.motion import LinearGaussianMotion
    >>> from fusetrack.sensors import LinearGaussianSensor
    >>> motion = LinearGaussianMotion(F=[[1.0, 1.0], [0.0, 1.0]], Q=0.01 * np.eye(2))
    >>> sensor = LinearGaussianSensor("radar", H=[[1.0, 0.0]], R=[[0.5]])
    >>> birth = PhdIntensity([0.1], [[0.0, 0.0]], [np.diag([100.0, 4.0])])
    >>> cphd = GMCPHDFilter(motion, [sensor], birth, detection_probability=0.9,
    ...                     clutter_intensity=1e-3)
    >>> b = cphd.predict(CphdBelief.empty(2, max_count=20), 1.0)
    >>> b = cphd.update(b, [Measurement(1.0, "radar", [3.0])])
    >>> b.map_count, round(b.expected_count, 3)
    (1, 0.784)
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.special import gammaln, logsumexp
from scipy.stats import binom, poisson

from ..core import (
    ConfigError,
    Measurement,
    MeasurementError,
    MotionModel,
    SensorModel,
    ShapeError,
    invalid,
)
from .gm_phd import (
    Clutter,
    GMPHDFilter,
    PhdIntensity,
    corrected_intensity,
    prune_and_merge,
)
from .stats import FilterStats

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class CphdBelief:
    """A labelled Gaussian-mixture intensity and the target-count distribution ``p(n)``,
    ``cardinality`` ``(N + 1,)`` for ``n = 0..N`` (non-negative, summing to 1).

    ``mean`` and ``cov`` are the intensity's (its heaviest component); ``expected_count`` is
    ``sum_n n p(n)`` and ``map_count`` the most probable number of targets.
    """

    intensity: PhdIntensity
    cardinality: Array

    def __post_init__(self) -> None:
        if not isinstance(self.intensity, PhdIntensity):
            raise ConfigError(invalid("intensity", self.intensity, "a PhdIntensity"))
        p = np.asarray(self.cardinality, dtype=float)
        if p.ndim != 1 or p.size == 0:
            raise ShapeError(invalid("cardinality.shape", p.shape, "(N + 1,) with N >= 0"))
        if not (np.all(np.isfinite(p)) and np.all(p >= 0) and abs(p.sum() - 1.0) < 1e-9):
            raise ConfigError(invalid("cardinality", p, "probabilities summing to 1"))
        object.__setattr__(self, "cardinality", p / p.sum())

    @classmethod
    def poisson(cls, intensity: PhdIntensity, max_count: int) -> CphdBelief:
        """``intensity`` with a Poisson count of mean ``sum_j w_j`` (truncated at ``max_count``):
        the belief a PHD filter implies."""
        n = np.arange(_check_max_count(max_count) + 1)
        p = poisson.pmf(n, intensity.expected_count)
        return cls(intensity, p / p.sum())

    @classmethod
    def empty(cls, dim: int, max_count: int) -> CphdBelief:
        """No targets, for certain, in a ``dim``-dimensional state space."""
        p = np.zeros(_check_max_count(max_count) + 1)
        p[0] = 1.0
        return cls(PhdIntensity.empty(dim), p)

    @property
    def max_count(self) -> int:
        return int(self.cardinality.size - 1)

    @property
    def expected_count(self) -> float:
        return float(np.arange(self.cardinality.size) @ self.cardinality)

    @property
    def map_count(self) -> int:
        return int(np.argmax(self.cardinality))

    @property
    def mean(self) -> Array:
        return self.intensity.mean

    @property
    def cov(self) -> Array:
        return self.intensity.cov


def _check_max_count(max_count: Any) -> int:
    if isinstance(max_count, bool) or not isinstance(max_count, int | np.integer) or max_count < 0:
        raise ConfigError(invalid("max_count", max_count, "an integer >= 0"))
    return int(max_count)


def extract_cphd_states(belief: CphdBelief) -> list[tuple[int, Array, Array]]:
    """Vo, Vo & Cantoni 2007, Sec. IV-C: the ``map_count`` heaviest components as
    ``(label, mean, cov)``, heaviest first."""
    order = np.argsort(-belief.intensity.weights, kind="stable")[: belief.map_count]
    v = belief.intensity
    return [(int(v.labels[i]), v.means[i].copy(), v.covs[i].copy()) for i in order]


def predict_cardinality(
    cardinality: Array, survival_probability: float, birth_mass: float
) -> Array:
    """``p'(n)``: binomial thinning by ``p_S`` convolved with a Poisson(``birth_mass``) birth
    count (Vo, Vo & Cantoni 2007, Eq. 24), truncated to the same ``N`` and renormalised."""
    n = np.arange(cardinality.size)
    thinning = binom.pmf(n[:, None], n[None, :], survival_probability)  # [j, l] = P(j of l)
    predicted = np.convolve(thinning @ cardinality, poisson.pmf(n, birth_mass))[: n.size]
    return np.asarray(predicted / predicted.sum())


def _log_esf(log_x: Array) -> Array:
    """``log e_i(x)``, ``i = 0..len(x)``, of non-negative ``x`` given as logs."""
    e = np.zeros(log_x.size + 1)
    e[0] = 1.0
    shift = float(log_x.max()) if log_x.size and np.isfinite(log_x.max()) else 0.0
    for xi in np.exp(log_x - shift):
        e[1:] = e[1:] + xi * e[:-1]
    with np.errstate(divide="ignore"):
        return np.asarray(np.log(e) + shift * np.arange(e.size))


def _log_upsilon(log_e: Array, u: int, log_a: float, log_w: float, max_count: int) -> Array:
    """``log U^u[Z](n)`` for ``n = 0..N`` (module doc) from ``log e_i(x_Z)``."""
    n = np.arange(max_count + 1)[:, None]
    i = np.arange(log_e.size)[None, :]
    k = n - i - u  # the exponent of a: targets not detected
    with np.errstate(invalid="ignore"):
        a_term = np.where(k == 0, 0.0, k * log_a)  # a^0 = 1 even when a = 0
    terms = gammaln(n + 1) - gammaln(np.maximum(k, 0) + 1) + a_term - n * log_w + log_e[None, :]
    terms = np.where(k >= 0, terms, -np.inf)
    return np.asarray(logsumexp(terms, axis=1))


class GMCPHDFilter:
    """The Gaussian-mixture CPHD filter (Vo, Vo & Cantoni 2007) with labelled components.

    The parameters are those of :class:`~fusetrack.filters.GMPHDFilter` (no spawning); the
    clutter is Poisson with intensity ``clutter_intensity`` (positive at every detection) and
    ``clutter_rate`` enters only the log-likelihood. The count range ``0..N`` is the belief's
    (:meth:`CphdBelief.poisson`, :meth:`CphdBelief.empty`).
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
        clutter_rate: float | Mapping[str, float] | None = None,
        truncation_threshold: float = 1e-5,
        merge_threshold: float = 4.0,
        max_components: int = 100,
    ) -> None:
        self.phd = GMPHDFilter(
            motion,
            sensors,
            birth,
            survival_probability=survival_probability,
            detection_probability=detection_probability,
            clutter_intensity=clutter_intensity,
            clutter_rate=clutter_rate,
            truncation_threshold=truncation_threshold,
            merge_threshold=merge_threshold,
            max_components=max_components,
        )

    def __repr__(self) -> str:
        return f"GMCPHDFilter(motion={self.phd.motion!r}, sensors={sorted(self.phd.sensors)})"

    @property
    def stats(self) -> FilterStats:
        return self.phd.stats

    def predict(
        self, belief: CphdBelief, dt: float, rng: np.random.Generator | None = None
    ) -> CphdBelief:
        """The PHD prediction of the intensity and :func:`predict_cardinality`."""
        _check_belief(belief)
        intensity = self.phd.predict(belief.intensity, dt)
        p_s, born = self.phd.survival_probability, self.phd.birth.expected_count
        card = predict_cardinality(belief.cardinality, p_s, born)
        return CphdBelief(intensity, card)

    def update(
        self,
        belief: CphdBelief,
        measurements: Sequence[Measurement] | Measurement,
        rng: np.random.Generator | None = None,
    ) -> CphdBelief:
        """The posterior after one scan (each sensor in turn, pruned and merged after each)."""
        return self.update_with_likelihood(belief, measurements, rng)[0]

    def update_with_likelihood(
        self,
        belief: CphdBelief,
        measurements: Sequence[Measurement] | Measurement,
        rng: np.random.Generator | None = None,
    ) -> tuple[CphdBelief, Array]:
        """:meth:`update` and ``log p(Z)`` of the scan (module doc), summed over the sensors."""
        _check_belief(belief)
        shape, d = belief.intensity.means.shape, self.phd.motion.dim
        if shape[1] != d:
            raise ShapeError(invalid("belief.intensity.means.shape", shape, f"(J, {d})"))
        batch = [measurements] if isinstance(measurements, Measurement) else measurements
        loglik = 0.0
        for sid, (values, covariances) in self.phd.sensor_scans(batch).items():
            belief, ll = self._correct(belief, sid, values, covariances)
            intensity = prune_and_merge(belief.intensity, **self.phd.prune_kw)
            belief = CphdBelief(intensity, belief.cardinality)
            loglik += ll
        return belief, np.asarray(loglik)

    def _correct(
        self, belief: CphdBelief, sid: str, values: Array, covariances: list[Array | None]
    ) -> tuple[CphdBelief, float]:
        """One sensor's CPHD corrector (Vo, Vo & Cantoni 2007, Eqs. 25-29)."""
        prior, log_p = belief.intensity, _log(belief.cardinality)
        terms = self.phd.detection_terms(prior, sid, values, covariances)
        if not np.all(np.isfinite(terms.log_kappa)):
            raise ConfigError(
                invalid(f"clutter_intensity[{sid!r}](z)", np.exp(terms.log_kappa), "> 0 (CPHD)")
            )
        clutter = float(terms.log_kappa.sum()) - self.phd.clutter_rate[sid]
        total = prior.expected_count
        if total == 0.0:  # nothing to detect: no target can exist
            return CphdBelief(prior, np.eye(1, belief.max_count + 1)[0]), clutter + float(log_p[0])
        log_pw = _log(terms.p_d * prior.weights)
        log_x = logsumexp(log_pw + terms.log_q, axis=1) - terms.log_kappa  # (n,)
        log_a = float(_log(np.asarray((1.0 - terms.p_d) @ prior.weights)))
        args = (log_a, float(np.log(total)), belief.max_count)
        log_e = _log_esf(log_x)
        log_u0 = _log_upsilon(log_e, 0, *args)
        norm = float(logsumexp(log_u0 + log_p))
        if not np.isfinite(norm):
            raise MeasurementError(
                f"sensor {sid!r}: a scan of {len(values)} detections has probability 0 under "
                "the predicted cardinality and detection probability (p(Z) = 0)"
            )
        missed = np.exp(logsumexp(_log_upsilon(log_e, 1, *args) + log_p) - norm)
        log_factor = np.array(
            [
                logsumexp(_log_upsilon(_log_esf(np.delete(log_x, z)), 1, *args) + log_p)
                for z in range(len(log_x))
            ]
        ).reshape(-1)
        detected = np.exp(log_pw + terms.log_q + (log_factor - norm - terms.log_kappa)[:, None])
        weights = (1.0 - terms.p_d) * prior.weights * missed
        intensity = corrected_intensity(prior, terms, weights, detected)
        return CphdBelief(intensity, np.exp(log_u0 + log_p - norm)), norm + clutter


def _log(x: Array) -> Array:
    with np.errstate(divide="ignore"):
        return np.asarray(np.log(x))


def _check_belief(belief: Any) -> None:
    if not isinstance(belief, CphdBelief):
        raise ConfigError(invalid("belief", belief, "a CphdBelief"))
