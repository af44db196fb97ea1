r"""The Gaussian-mixture PHD filter (Vo & Ma 2006, IEEE TSP 54(11), "The Gaussian Mixture
Probability Hypothesis Density Filter"), with labelled components.

The belief is the *intensity* (first moment, PHD) ``v(x)`` of the multi-target state: a Gaussian
mixture ``v(x) = sum_j w_j N(x; m_j, P_j)`` whose integral ``sum_j w_j`` is the expected number
of targets (:class:`PhdIntensity`). The weights do not sum to 1, so it is not a
:class:`~fusetrack.core.GaussianMixture` (a probability density).

**Predict** (Vo & Ma, Table I steps 1-2, Eqs. 20-27), per scan::

    survivors   w' = p_S w,        m' = f(m, dt),          P' = F P F^T + Q(dt)
    spawned     w' = w w_b,        m' = F_b m + d_b,       P' = F_b P F_b^T + Q_b
    births      the user's birth intensity (Eq. 21), appended

with ``F`` the motion model's Jacobian at ``m`` (exact for a linear model; the extended-Kalman
PHD of Vo & Ma Sec. IV-A otherwise).

**Update** with one sensor's detections ``Z`` (Table I steps 3-4, Eqs. 28-33)::

    S_j = H_j P_j H_j^T + R,   K_j = P_j H_j^T S_j^-1,   P_j^+ = (I - K_j H_j) P_j (Joseph form)
    missed      w = (1 - p_D) w_j,  m_j,  P_j
    for z in Z  q_j(z) = N(z; h(m_j), S_j)
                w = p_D w_j q_j(z) / (kappa(z) + sum_l p_D w_l q_l(z))
                m = m_j + K_j r(z, h(m_j)),  P_j^+          (r = sensor.residual)

``H_j`` is the sensor Jacobian at ``m_j`` (exact for a linear sensor; the EK-PHD otherwise), and
``p_D`` a constant or ``sensor.detection_probability`` at ``m_j`` (the usual approximation of a
state-dependent ``p_D``, exact when it is constant over each component). Then the mixture is
pruned and merged (:func:`prune_and_merge`, Vo & Ma Table II).

**Several sensors in one scan** are applied one after the other, each with its own detections
(the iterated-corrector approximation of the multi-sensor PHD, Mahler 2007 Sec. 10.6: it
depends on the sensor order), with pruning and merging after each. The sensors of a scan are
those that appear in ``measurements``; a measurement with a NaN value says "this sensor looked
and saw nothing" (only the missed-detection term applies; counted in
``stats.skipped_measurements`` like every non-finite value). Every measurement is one detection
``(m,)``; batched values are refused.

**Log-likelihood.** The predicted measurement set of a PHD filter is Poisson with intensity
``kappa(z) + sum_j p_D w_j q_j(z)``, so ``log p(Z) = sum_z log(kappa(z) + sum_j p_D w_j q_j(z))
- sum_j p_D w_j - lambda_c`` (Mahler 2007, Eq. 16.169; the sum of the denominators above).
``lambda_c`` (the expected clutter count per scan) enters only when ``clutter_rate`` is given.

**Labels** (state extraction with track identity, after Panta, Clark & Vo 2009): every birth or
spawned component gets a fresh integer label (the intensity carries the next free one), updated
and predicted components keep their parent's label, and a merged component keeps the label of
its heaviest member. :func:`extract_states` (Table III) reads ``(label, mean, cov)`` off the
components with weight above 0.5.

The cardinalised variant (GM-CPHD, Vo, Vo & Cantoni 2007) on these components is
:mod:`fusetrack.filters.gm_cphd`.

Example::

    >>> import numpy as np
    >>> from fusetrack.core import Measurement
    >>> from fusetrack.motion import LinearGaussianMotion
    >>> from fusetrack.sensors import LinearGaussianSensor
    >>> motion = LinearGaussianMotion(F=[[1.0, 1.0], [0.0, 1.0]], Q=0.01 * np.eye(2))
    >>> sensor = LinearGaussianSensor("radar", H=[[1.0, 0.0]], R=[[0.5]])
    >>> birth = PhdIntensity([0.1], [[0.0, 0.0]], [np.diag([100.0, 4.0])])
    >>> phd = GMPHDFilter(motion, [sensor], birth, detection_probability=0.9,
    ...                   clutter_intensity=1e-3)
    >>> v = phd.update(phd.predict(PhdIntensity.empty(2), 1.0), [Measurement(1.0, "radar", [3.0])])
    >>> round(v.expected_count, 3)
    0.784
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree
from scipy.special import logsumexp

from ..core import (
    ConfigError,
    Measurement,
    MeasurementError,
    MotionModel,
    SensorModel,
    ShapeError,
    check_positive,
    check_probability,
    invalid,
)
from .stats import FilterStats, as_sensor_map, validate_measurement

Array = NDArray[np.float64]
Labels = NDArray[np.int64]
Clutter = float | Callable[[Array], ArrayLike]
"""A clutter intensity ``kappa(z)`` (reports per unit measurement volume): a constant, or a
function of the detections ``(n, m)`` returning ``(n,)``."""

_LOG_2PI = float(np.log(2.0 * np.pi))


def _t(a: NDArray[Any]) -> NDArray[Any]:
    return np.swapaxes(a, -1, -2)


def _sym(c: NDArray[Any]) -> NDArray[Any]:
    return 0.5 * (c + _t(c))


@dataclass(frozen=True, eq=False)
class PhdIntensity:
    """A labelled Gaussian-mixture intensity ``v(x) = sum_j w_j N(x; m_j, P_j)``.

    ``weights`` ``(J,)`` (non-negative, any sum), ``means`` ``(J, d)``, ``covs`` ``(J, d, d)``,
    ``labels`` ``(J,)`` integers (default ``0..J-1``) and ``next_label``, the first label not
    yet given out (default one more than the largest label). ``J`` may be 0.

    As a :class:`~fusetrack.core.Belief`: ``mean`` and ``cov`` are those of the highest-weight
    component (NaN when there is none) -- the most confident single target, not a moment of
    the intensity; :attr:`expected_count` is ``sum_j w_j``, the expected number of targets.
    """

    weights: Array
    means: Array
    covs: Array
    labels: Labels = None  # type: ignore[assignment]  # None: 0..J-1 (set in __post_init__)
    next_label: int = None  # type: ignore[assignment]  # None: one above the largest label

    def __post_init__(self) -> None:
        m = np.asarray(self.means, dtype=float)
        if m.ndim != 2:
            raise ShapeError(invalid("means.shape", m.shape, "(J, d): one row per component"))
        j, d = m.shape
        w = np.asarray(self.weights, dtype=float)
        c = np.asarray(self.covs, dtype=float)
        if w.shape != (j,):
            raise ShapeError(invalid("weights.shape", w.shape, f"({j},) to match means {m.shape}"))
        if c.shape != (j, d, d):
            raise ShapeError(invalid("covs.shape", c.shape, f"({j}, {d}, {d}) to match means"))
        if not (np.all(np.isfinite(w)) and np.all(w >= 0)):
            raise ConfigError(invalid("weights", w, "finite numbers >= 0"))
        if not (np.all(np.isfinite(m)) and np.all(np.isfinite(c))):
            raise ConfigError(invalid("(means, covs)", (m, c), "finite numbers"))
        labels = _labels(self.labels, j)
        top = int(labels.max()) + 1 if j else 0
        nxt = top if self.next_label is None else self.next_label
        if isinstance(nxt, bool) or not isinstance(nxt, int | np.integer) or nxt < top:
            raise ConfigError(
                invalid("next_label", nxt, f"an integer >= {top} (above every label)")
            )
        for name, value in (("weights", w), ("means", m), ("covs", c), ("labels", labels)):
            object.__setattr__(self, name, value)
        object.__setattr__(self, "next_label", int(nxt))

    @classmethod
    def empty(cls, dim: int, next_label: int = 0) -> PhdIntensity:
        """No components (no targets expected) in a ``dim``-dimensional state space."""
        no_labels = np.zeros(0, dtype=np.int64)
        return cls(np.zeros(0), np.zeros((0, dim)), np.zeros((0, dim, dim)), no_labels, next_label)

    @property
    def dim(self) -> int:
        return int(self.means.shape[1])

    @property
    def n_components(self) -> int:
        return int(self.weights.shape[0])

    @property
    def expected_count(self) -> float:
        """``sum_j w_j``: the expected number of targets (the integral of the intensity)."""
        return float(self.weights.sum())

    @property
    def mean(self) -> Array:
        """The highest-weight component's mean ``(d,)`` (NaN when there are no components)."""
        if not self.n_components:
            return np.full(self.dim, np.nan)
        return np.asarray(self.means[int(np.argmax(self.weights))])

    @property
    def cov(self) -> Array:
        """The highest-weight component's covariance ``(d, d)`` (NaN when there are none)."""
        if not self.n_components:
            return np.full((self.dim, self.dim), np.nan)
        return np.asarray(self.covs[int(np.argmax(self.weights))])


def _labels(labels: ArrayLike | None, j: int) -> Labels:
    if labels is None:
        return np.arange(j, dtype=np.int64)
    a = np.asarray(labels)
    if a.shape != (j,):
        raise ShapeError(invalid("labels.shape", a.shape, f"({j},): one label per component"))
    if j and not np.issubdtype(a.dtype, np.integer):
        raise ConfigError(invalid("labels", a, "integers"))
    return a.astype(np.int64)


def _fresh(weights: Array, means: Array, covs: Array, start: int) -> PhdIntensity:
    """Components labelled ``start, start + 1, ...``."""
    labels = np.arange(start, start + len(weights), dtype=np.int64)
    return PhdIntensity(weights, means, covs, labels, start + len(weights))


def _concat(parts: Sequence[PhdIntensity], dim: int) -> PhdIntensity:
    """The sum of intensities (their components side by side); the largest ``next_label``."""
    return PhdIntensity(
        np.concatenate([p.weights for p in parts]),
        np.concatenate([p.means for p in parts]).reshape(-1, dim),
        np.concatenate([p.covs for p in parts]).reshape(-1, dim, dim),
        np.concatenate([p.labels for p in parts]),
        max(p.next_label for p in parts),
    )


@dataclass(frozen=True, eq=False)
class SpawnComponent:
    """One term ``w_b N(x; F_b zeta + d_b, Q_b)`` of the spawn intensity ``beta(x | zeta)``
    (Vo & Ma Eq. 22): every target ``zeta`` spawns ``w_b`` new targets on average per scan."""

    weight: float
    F: ArrayLike
    offset: ArrayLike
    Q: ArrayLike
    _arrays: tuple[Array, Array, Array] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        check_positive("SpawnComponent.weight", self.weight, allow_zero=True)
        f = np.asarray(self.F, dtype=float)
        d = f.shape[0] if f.ndim == 2 else -1
        off = np.asarray(self.offset, dtype=float)
        q = np.asarray(self.Q, dtype=float)
        if f.shape != (d, d) or off.shape != (d,) or q.shape != (d, d):
            shapes = (f.shape, off.shape, q.shape)
            raise ShapeError(
                invalid("SpawnComponent (F, offset, Q) shapes", shapes, "(d, d), (d,), (d, d)")
            )
        object.__setattr__(self, "_arrays", (f, off, q))

    def spawn(self, parents: PhdIntensity, first_label: int) -> PhdIntensity:
        """The components ``parents`` spawn (Vo & Ma Eqs. 25-27), labelled from ``first_label``."""
        f, off, q = self._arrays
        if f.shape[0] != parents.dim:
            raise ShapeError(
                invalid("SpawnComponent.F.shape", f.shape, f"({parents.dim}, {parents.dim})")
            )
        covs = _sym(f @ parents.covs @ f.T + q)
        weights = parents.weights * float(self.weight)
        return _fresh(weights, parents.means @ f.T + off, covs, first_label)


MERGE_RULES = ("mutual", "printed")


def prune_and_merge(
    intensity: PhdIntensity,
    truncation_threshold: float = 1e-5,
    merge_threshold: float = 4.0,
    max_components: int = 100,
    merge_rule: str = "mutual",
) -> PhdIntensity:
    """Vo & Ma 2006, Table II: drop components with ``w <= T``; then, heaviest first, merge
    every remaining component ``i`` with ``(m_i - m_j)^T P_i^-1 (m_i - m_j) <= U`` into the
    heaviest ``j`` by moment matching (``w = sum w_i``, ``m = sum w_i m_i / w``,
    ``P = sum w_i (P_i + (m - m_i)(m - m_i)^T) / w``; label of ``j``); keep the ``J_max``
    heaviest. The weights are not rescaled (the pruned mass is lost, as in the paper). The
    result is ordered by decreasing weight.

    ``merge_rule="printed"`` is Table II's test with the candidate's own ``P_i``. There a wide
    component (the missed-detection part of a wide birth term, every scan) lies within ``U`` of
    any target it covers, is merged into it and inflates the target's covariance (the GOSPA of
    ``benchmarks/multitarget.py``: 25.7 vs 22.0 m). ``"mutual"`` (default) also requires
    ``(m_i - m_j)^T P_j^-1 (m_i - m_j) <= U``, so only components that each lie within the other's
    spread are merged.

    The Mahalanobis tests are evaluated only on the pairs a k-d tree finds within the bound
    ``|m_i - m_j|^2 <= U / lambda_min(P_i^-1)`` (necessary under both rules), and the groups are
    moment-matched in one pass; :func:`prune_and_merge_reference` is the plain loop of Table II
    it equals."""
    u, mutual, kept = _pruned(
        intensity, truncation_threshold, merge_threshold, max_components, merge_rule
    )
    w, m, c, labels = kept
    if not len(w):
        return _merged(intensity, [])
    inv: Array = np.asarray(np.linalg.pinv(c, hermitian=True), dtype=float)
    group, heads = _merge_groups(w, m, inv, u, mutual)
    total: Array = np.asarray(np.bincount(group, weights=w), dtype=float)
    sums = np.stack([np.bincount(group, weights=w * m[:, i]) for i in range(m.shape[1])], 1)
    mean: Array = np.asarray(sums, dtype=float) / total[:, None]
    r = m - mean[group]
    spread = w[:, None, None] * (c + r[:, :, None] * r[:, None, :])
    order = np.argsort(group, kind="stable")
    starts = np.searchsorted(group[order], np.arange(len(heads)))
    cov = np.add.reduceat(spread[order], starts, axis=0) / total[:, None, None]
    ranked = np.argsort(-total, kind="stable")[:max_components]
    return PhdIntensity(
        total[ranked], mean[ranked], _sym(cov[ranked]), labels[heads][ranked], intensity.next_label
    )


def _merge_groups(
    w: Array, m: Array, inv: Array, u: float, mutual: bool
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Table II's grouping: every component's group number (``(J,)``, numbered in the order
    the groups are formed) and each group's heaviest component (``(G,)``)."""
    near = _within_threshold(m, inv, u, mutual)
    group = np.full(len(w), -1, dtype=np.intp)
    heads: list[int] = []
    for j in np.argsort(-w, kind="stable"):  # argmax picks the first of equal weights too
        if group[j] >= 0:
            continue
        members = near[j]
        group[members[group[members] < 0]] = len(heads)
        group[j] = len(heads)
        heads.append(int(j))
    return group, np.array(heads, dtype=np.intp)


def _within_threshold(m: Array, inv: Array, u: float, mutual: bool) -> list[NDArray[np.intp]]:
    """For every component ``j`` the components ``i`` that pass the merge test with ``j`` as
    the heaviest. ``(m_i - m_j)^T P_i^-1 (m_i - m_j) >= lambda_min(P_i^-1) |m_i - m_j|^2``, so
    only the pairs a k-d tree finds within ``sqrt(U / lambda_min)`` of ``m_i`` are tested."""
    lam = np.linalg.eigvalsh(inv)[:, 0]
    span = float(np.sqrt(np.sum((m.max(0) - m.min(0)) ** 2)))
    with np.errstate(divide="ignore"):
        radius = np.sqrt(u / np.maximum(lam, 0.0)) * (1.0 + 1e-6) + 1e-9 * (1.0 + span)
    radius = np.minimum(radius, 2.0 * span + 1.0)  # no bound: every component
    found = cKDTree(m).query_ball_point(m, radius)
    cand = np.fromiter((i for lst in found for i in lst), dtype=np.intp)
    own = np.repeat(np.arange(len(m)), [len(lst) for lst in found])  # the i of each pair
    diff = m[own] - m[cand]  # m_i - m_j with j = cand
    maha = np.einsum("ki,kij,kj->k", diff, inv[own], diff)
    if mutual:
        maha = np.maximum(maha, np.einsum("ki,kij,kj->k", diff, inv[cand], diff))
    ok = maha <= u
    own, cand = own[ok], cand[ok]
    by_head = np.argsort(cand, kind="stable")
    bounds = np.searchsorted(cand[by_head], np.arange(len(m) + 1))
    members = own[by_head]
    return [members[bounds[k] : bounds[k + 1]] for k in range(len(m))]


def prune_and_merge_reference(
    intensity: PhdIntensity,
    truncation_threshold: float = 1e-5,
    merge_threshold: float = 4.0,
    max_components: int = 100,
    merge_rule: str = "mutual",
) -> PhdIntensity:
    """:func:`prune_and_merge` as the plain loop of Vo & Ma Table II (every group tests every
    remaining component); kept to check the fast version against."""
    u, mutual, (w, m, c, labels) = _pruned(
        intensity, truncation_threshold, merge_threshold, max_components, merge_rule
    )
    inv = np.linalg.pinv(c, hermitian=True) if len(w) else c
    left = np.ones(len(w), dtype=bool)
    out: list[tuple[float, Array, Array, int]] = []
    while left.any():
        j = int(np.flatnonzero(left)[np.argmax(w[left])])
        diff = m - m[j]
        maha = np.einsum("ki,kij,kj->k", diff, inv, diff)
        if mutual:
            maha = np.maximum(maha, np.einsum("ki,ij,kj->k", diff, inv[j], diff))
        group = left & (maha <= u)
        group[j] = True
        wg = w[group]
        total = float(wg.sum())
        mean = wg @ m[group] / total
        r = m[group] - mean
        cov = np.einsum("k,kij->ij", wg, c[group] + r[:, :, None] * r[:, None, :]) / total
        out.append((total, mean, _sym(cov), int(labels[j])))
        left &= ~group
    out.sort(key=lambda comp: -comp[0])
    return _merged(intensity, out[:max_components])


def _pruned(
    intensity: PhdIntensity,
    truncation_threshold: float,
    merge_threshold: float,
    max_components: int,
    merge_rule: str,
) -> tuple[float, bool, tuple[Array, Array, Array, Labels]]:
    """The checked ``U``, whether the rule is mutual, and the components with ``w > T``."""
    t = check_positive("truncation_threshold", truncation_threshold, allow_zero=True)
    u = check_positive("merge_threshold", merge_threshold, allow_zero=True)
    if (
        isinstance(max_components, bool)
        or not isinstance(max_components, int)
        or max_components < 1
    ):
        raise ConfigError(invalid("max_components", max_components, "an integer >= 1"))
    if merge_rule not in MERGE_RULES:
        raise ConfigError(invalid("merge_rule", merge_rule, f"one of {MERGE_RULES}"))
    keep = np.flatnonzero(intensity.weights > t)
    kept = intensity.weights[keep], intensity.means[keep], intensity.covs[keep]
    return u, merge_rule == "mutual", (*kept, intensity.labels[keep])


def _merged(intensity: PhdIntensity, out: list[tuple[float, Array, Array, int]]) -> PhdIntensity:
    d = intensity.dim
    return PhdIntensity(
        np.array([o[0] for o in out]),
        np.array([o[1] for o in out]).reshape(-1, d),
        np.array([o[2] for o in out]).reshape(-1, d, d),
        np.array([o[3] for o in out], dtype=np.int64),
        intensity.next_label,
    )


def extract_states(
    intensity: PhdIntensity, threshold: float = 0.5
) -> list[tuple[int, Array, Array]]:
    """Vo & Ma 2006, Table III: ``(label, mean, cov)`` of every component with weight above
    ``threshold``, repeated ``round(w)`` times (a component of weight 1.8 stands for two
    targets, both with its label), heaviest first."""
    threshold = check_positive("threshold", threshold, allow_zero=True)
    order = np.argsort(-intensity.weights, kind="stable")
    labels = intensity.labels
    states: list[tuple[int, Array, Array]] = []
    for i in order:
        w = float(intensity.weights[i])
        if w <= threshold:
            break
        for _ in range(int(np.floor(w + 0.5))):
            states.append((int(labels[i]), intensity.means[i].copy(), intensity.covs[i].copy()))
    return states


class DetectionTerms(NamedTuple):
    """One sensor's detections against a prior intensity of ``J`` components: ``p_d`` ``(J,)``
    at the component means, ``log_kappa`` ``(n,)`` the clutter intensity at each detection,
    ``log_q`` ``(n, J)`` = ``log N(z; h(m_j), S_j)``, and the Kalman-updated ``means``
    ``(n, J, d)`` and ``covs`` ``(1 or n, J, d, d)``."""

    p_d: Array
    log_kappa: Array
    log_q: Array
    means: Array
    covs: Array


def corrected_intensity(
    prior: PhdIntensity,
    terms: DetectionTerms,
    missed: Array,
    detected: Array,
    above: float = -np.inf,
) -> PhdIntensity:
    """The updated mixture: the prior components with weights ``missed`` ``(J,)``, then one
    Kalman-updated copy per detection and component with weights ``detected`` ``(n, J)``;
    every copy keeps its parent's label. Only the components with weight ``> above`` are
    built (in the same order): the truncation of :func:`prune_and_merge` done early."""
    n, (j, d) = detected.shape[0], prior.means.shape
    weights = np.concatenate([missed, detected.ravel()])
    idx = np.flatnonzero(weights > above)
    stays, moved = idx[idx < j], idx[idx >= j] - j
    det, comp = np.divmod(moved, j)
    covs = terms.covs[det if terms.covs.shape[0] > 1 else 0, comp]
    return PhdIntensity(
        weights[idx],
        np.concatenate([prior.means[stays], terms.means.reshape(n * j, d)[moved]]),
        np.concatenate([prior.covs[stays], covs.reshape(-1, d, d)]),
        np.concatenate([prior.labels[stays], prior.labels[comp]]),
        prior.next_label,
    )


def _per_sensor(name: str, value: Any, sensor_ids: Sequence[str]) -> dict[str, Any]:
    """``value`` for every sensor: a mapping must name each sensor exactly once."""
    if not isinstance(value, Mapping):
        return dict.fromkeys(sensor_ids, value)
    if set(value) != set(sensor_ids):
        raise ConfigError(invalid(name, dict(value), f"one entry per sensor {sorted(sensor_ids)}"))
    return dict(value)


def _value_size(sensor: SensorModel) -> int:
    return int(getattr(sensor, "value_size", sensor.dim))


def _check_clutter(sid: str, kappa: Clutter) -> Clutter:
    if callable(kappa):
        return kappa
    return check_positive(f"clutter_intensity[{sid!r}]", kappa, allow_zero=True)


class GMPHDFilter:
    """The Gaussian-mixture PHD filter (Vo & Ma 2006) for linear-Gaussian models, and its
    extended-Kalman form for any differentiable motion and sensor models (see the module doc).

    Parameters
    ----------
    motion:
        a :class:`~fusetrack.core.MotionModel` (``mean``, ``jacobian``, ``noise_cov``, ``dim``),
        e.g. ``LinearGaussianMotion(F, Q)``.
    sensors:
        sensor models (a sequence keyed by ``sensor_id``, or a mapping).
    birth:
        the birth intensity added at every :meth:`predict` (its labels are ignored: every
        birth component gets a fresh label each scan).
    survival_probability:
        ``p_S`` in [0, 1].
    detection_probability:
        ``p_D`` in [0, 1], or None to use ``sensor.detection_probability`` at each component's
        mean.
    clutter_intensity:
        ``kappa(z)`` per unit measurement volume (``lambda_c / V`` for ``lambda_c`` uniform
        false alarms in a region of volume ``V``): a number or a function of the detections
        ``(n, m) -> (n,)``; a mapping ``sensor_id -> kappa`` for one per sensor.
    clutter_rate:
        ``lambda_c``, the expected number of false alarms per scan (or a mapping per sensor);
        used only by :meth:`update_with_likelihood` (None: the constant ``-lambda_c`` is left
        out of the log-likelihood).
    spawn:
        :class:`SpawnComponent` terms of the spawn intensity (none by default).
    truncation_threshold, merge_threshold, max_components, merge_rule:
        ``T``, ``U`` and ``J_max`` of :func:`prune_and_merge` (Vo & Ma's 1e-5, 4, 100), and
        which covariances the merge test uses (``"mutual"``, or Table II's ``"printed"``).

    Attributes
    ----------
    stats:
        a :class:`~fusetrack.filters.FilterStats` counting the non-finite ("saw nothing")
        measurements.
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
        spawn: Sequence[SpawnComponent] = (),
        truncation_threshold: float = 1e-5,
        merge_threshold: float = 4.0,
        max_components: int = 100,
        merge_rule: str = "mutual",
    ) -> None:
        self.motion = motion
        self.sensors = as_sensor_map(sensors)
        if not isinstance(birth, PhdIntensity) or birth.dim != motion.dim:
            raise ConfigError(invalid("birth", birth, f"a PhdIntensity of dimension {motion.dim}"))
        self.birth = birth
        self.survival_probability = check_probability("survival_probability", survival_probability)
        self.detection_probability = (
            None
            if detection_probability is None
            else check_probability("detection_probability", detection_probability)
        )
        ids = list(self.sensors)
        kappas = _per_sensor("clutter_intensity", clutter_intensity, ids)
        self.clutter_intensity = {sid: _check_clutter(sid, k) for sid, k in kappas.items()}
        rates = _per_sensor("clutter_rate", clutter_rate, ids)
        self.clutter_rate = {
            sid: 0.0 if r is None else check_positive(f"clutter_rate[{sid!r}]", r, allow_zero=True)
            for sid, r in rates.items()
        }
        self.spawn = tuple(spawn)
        for s in self.spawn:
            if not isinstance(s, SpawnComponent):
                raise ConfigError(invalid("spawn", s, "SpawnComponent terms"))
        self.prune_kw: dict[str, Any] = {
            "truncation_threshold": truncation_threshold,
            "merge_threshold": merge_threshold,
            "max_components": max_components,
            "merge_rule": merge_rule,
        }
        prune_and_merge(PhdIntensity.empty(motion.dim), **self.prune_kw)  # checks the values
        self.stats = FilterStats()

    def __repr__(self) -> str:
        return f"GMPHDFilter(motion={self.motion!r}, sensors={sorted(self.sensors)})"

    def _check_belief(self, belief: PhdIntensity) -> None:
        if not isinstance(belief, PhdIntensity):
            raise ConfigError(invalid("belief", belief, "a PhdIntensity"))
        if belief.dim != self.motion.dim:
            raise ShapeError(
                invalid("belief.means.shape", belief.means.shape, f"(J, {self.motion.dim})")
            )

    def predict(
        self, belief: PhdIntensity, dt: float, rng: np.random.Generator | None = None
    ) -> PhdIntensity:
        """Survivors, spawned targets and births (Vo & Ma Eqs. 20-27); ``rng`` is ignored."""
        dt = check_positive("dt", dt, allow_zero=True)
        self._check_belief(belief)
        d = belief.dim
        parts = [belief]
        if belief.n_components:
            x = belief.means
            f = np.asarray(self.motion.jacobian(x, dt), dtype=float)
            f = np.broadcast_to(f, (len(x), d, d))
            q = np.asarray(self.motion.noise_cov(dt), dtype=float)
            parts[0] = PhdIntensity(
                self.survival_probability * belief.weights,
                np.asarray(self.motion.mean(x, dt), dtype=float).reshape(-1, d),
                _sym(f @ belief.covs @ _t(f) + q),
                belief.labels,
                belief.next_label,
            )
        first = belief.next_label
        for term in self.spawn:
            parts.append(term.spawn(belief, first))
            first = parts[-1].next_label
        parts.append(_fresh(self.birth.weights, self.birth.means, self.birth.covs, first))
        return _concat(parts, d)

    def update(
        self,
        belief: PhdIntensity,
        measurements: Sequence[Measurement] | Measurement,
        rng: np.random.Generator | None = None,
    ) -> PhdIntensity:
        """The posterior intensity after one scan (each sensor in turn, pruned and merged after
        each); ``measurements`` holds one detection per entry. ``rng`` is ignored."""
        return self.update_with_likelihood(belief, measurements, rng)[0]

    def update_with_likelihood(
        self,
        belief: PhdIntensity,
        measurements: Sequence[Measurement] | Measurement,
        rng: np.random.Generator | None = None,
    ) -> tuple[PhdIntensity, Array]:
        """:meth:`update` and ``log p(Z)`` of the scan under the Poisson predicted measurement
        process (module doc), summed over the sensors in the order they are applied."""
        self._check_belief(belief)
        scans = self.sensor_scans(
            [measurements] if isinstance(measurements, Measurement) else measurements
        )
        loglik = 0.0
        for sid, (values, covariances) in scans.items():
            belief, ll = self._correct(belief, sid, values, covariances)
            belief = prune_and_merge(belief, **self.prune_kw)
            loglik += ll
        return belief, np.asarray(loglik)

    def sensor_scans(
        self, measurements: Sequence[Measurement]
    ) -> dict[str, tuple[Array, list[Array | None]]]:
        """Each sensor's detections ``(n, m)`` and their own covariances, in order of the
        sensors' first appearance; a non-finite value adds the sensor with no detection."""
        found: dict[str, tuple[list[Array], list[Array | None]]] = {}
        for meas in measurements:
            checked = validate_measurement(meas, self.sensors, self.stats)
            if checked.value.ndim != 1:
                raise MeasurementError(
                    invalid(
                        f"value.shape (sensor {meas.sensor_id!r}, time={meas.time})",
                        checked.value.shape,
                        f"({checked.value.shape[-1]},): one detection per Measurement",
                    )
                )
            cov = checked.covariance
            m = checked.value.shape[0]
            if cov is not None and cov.shape != (m, m):
                raise MeasurementError(
                    invalid(
                        f"covariance.shape (sensor {meas.sensor_id!r})", cov.shape, f"({m}, {m})"
                    )
                )
            values, covs = found.setdefault(meas.sensor_id, ([], []))
            if checked.usable:
                values.append(checked.value)
                covs.append(checked.covariance)
        return {
            sid: (np.array(v, dtype=float).reshape(len(v), _value_size(self.sensors[sid])), c)
            for sid, (v, c) in found.items()
        }

    def _correct(
        self, prior: PhdIntensity, sid: str, values: Array, covariances: list[Array | None]
    ) -> tuple[PhdIntensity, float]:
        """One sensor's corrector (Vo & Ma Eqs. 28-33) and its log-likelihood term."""
        terms = self.detection_terms(prior, sid, values, covariances)
        with np.errstate(divide="ignore"):
            log_num = np.log(terms.p_d * prior.weights) + terms.log_q  # log p_D w_j q_j(z)
        log_den = logsumexp(np.concatenate([terms.log_kappa[:, None], log_num], axis=1), axis=1)
        seen = np.isfinite(log_den)  # False: z is impossible under the model (weights 0)
        weights = np.exp(log_num - np.where(seen, log_den, 0.0)[:, None]) * seen[:, None]
        missed = (1.0 - terms.p_d) * prior.weights
        floor = self.prune_kw["truncation_threshold"]  # pruned next anyway
        posterior = corrected_intensity(prior, terms, missed, weights, floor)
        expected = float(terms.p_d @ prior.weights) + self.clutter_rate[sid]  # Poisson scan
        return posterior, float(log_den.sum()) - expected

    def detection_terms(
        self, prior: PhdIntensity, sid: str, values: Array, covariances: list[Array | None]
    ) -> DetectionTerms:
        """What a PHD or CPHD corrector needs of sensor ``sid``'s detections ``values``
        ``(n, m)`` (and their own covariances, None for the sensor's) given ``prior``."""
        n, (j, d) = len(values), prior.means.shape
        p_d = self._detection_probability(sid, prior.means)
        log_kappa = self._log_clutter(sid, values)
        if not (n and j):
            return DetectionTerms(
                p_d, log_kappa, np.zeros((n, j)), np.zeros((n, j, d)), np.zeros((1, j, d, d))
            )
        log_q, means, covs = _kalman_update(self.sensors[sid], prior, values, covariances)
        return DetectionTerms(p_d, log_kappa, log_q, means, covs)

    def _detection_probability(self, sid: str, x: Array) -> Array:
        """``p_D`` at every component mean, ``(J,)``."""
        if self.detection_probability is not None:
            return np.full(len(x), self.detection_probability)
        if not len(x):
            return np.zeros(0)
        p = np.asarray(self.sensors[sid].detection_probability(x), dtype=float)
        p = np.broadcast_to(p, (len(x),))
        if not np.all((p >= 0.0) & (p <= 1.0)):
            raise ConfigError(
                invalid(f"sensor {sid!r} detection_probability(x)", p, "probabilities in [0, 1]")
            )
        return p

    def _log_clutter(self, sid: str, values: Array) -> Array:
        """``log kappa(z)`` for every detection, ``(n,)``."""
        kappa = self.clutter_intensity[sid]
        n = len(values)
        k = np.asarray(kappa(values) if callable(kappa) else np.full(n, kappa), dtype=float)
        if k.shape != (n,) or not np.all(np.isfinite(k) & (k >= 0.0)):
            raise ConfigError(
                invalid(f"clutter_intensity[{sid!r}](z)", k, f"({n},) finite numbers >= 0")
            )
        with np.errstate(divide="ignore"):
            return np.asarray(np.log(k))


def _noise(sensor: SensorModel, x: Array, m: int, covariances: list[Array | None]) -> Array:
    """``R`` per detection and component: ``(1, J, m, m)``, or ``(n, J, m, m)`` when some
    detection carries its own covariance."""
    shape = (len(x), m, m)
    base = np.broadcast_to(np.asarray(sensor.noise_cov(x), dtype=float), shape)
    if all(c is None for c in covariances):
        return base[None]
    return np.stack([base if c is None else np.broadcast_to(c, shape) for c in covariances])


def _kalman_update(
    sensor: SensorModel, prior: PhdIntensity, values: Array, covariances: list[Array | None]
) -> tuple[Array, Array, Array]:
    """Every component updated with every detection (the EKF linearised at each component
    mean): ``log q_j(z) = log N(r(z, h(m_j)); 0, S_j)`` ``(n, J)``, the updated means
    ``(n, J, d)`` and the Joseph-form covariances ``(1 or n, J, d, d)``."""
    x, p = prior.means, prior.covs
    j, d = x.shape
    z_pred = np.asarray(sensor.predict(x), dtype=float).reshape(j, -1)
    y = np.asarray(sensor.residual(values[:, None, :], z_pred[None]), dtype=float)
    m = y.shape[-1]
    h = np.broadcast_to(np.asarray(sensor.jacobian(x), dtype=float), (j, m, d))
    r = _noise(sensor, x, m, covariances)
    pht = p @ _t(h)
    s = _sym(h @ pht + r)
    try:
        chol = np.linalg.cholesky(s)
    except np.linalg.LinAlgError:
        raise MeasurementError(
            invalid(
                f"innovation covariance H P H^T + R of sensor {sensor.sensor_id!r}",
                "not positive definite",
                "a positive definite R (the sensor's noise_cov or the measurement's covariance)",
            )
        ) from None
    kt = np.linalg.solve(s, np.broadcast_to(_t(pht), (*s.shape[:-2], m, d)))
    k = _t(kt)
    ikh = np.eye(d) - k @ h
    covs = _sym(ikh @ p @ _t(ikh) + k @ r @ kt)  # Joseph form (Bucy & Joseph 1968)
    white = (np.linalg.inv(chol) @ y[..., None])[..., 0]  # one inverse per component
    log_det = 2.0 * np.log(np.diagonal(chol, axis1=-2, axis2=-1)).sum(-1)
    log_q = -0.5 * (np.sum(white * white, axis=-1) + log_det + m * _LOG_2PI)
    means = x[None] + (k @ y[..., None])[..., 0]
    return log_q, means, covs
