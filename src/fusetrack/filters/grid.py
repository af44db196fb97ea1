"""Grid-based sequential Bayesian estimation (SBE) of a 2-D position (Kushwaha 2010, Ch. III).

The posterior lives on a regular grid of cells (35 m × 20 m with 0.5 m cells in the paper: 2800
cells). One step is (Kushwaha 2010, Eq. 28)

    p(x_{t+1} | z_{1:t+1}) ∝ p(z_{t+1} | x_{t+1}) Σ_{x_t} p(x_{t+1} | x_t) p(x_t | z_{1:t}),

with the "directional" motion model x_{t+1} = x_t + v + U[-δ, δ] (Eq. 29), i.e. a shift of the
grid by v followed by a convolution with a uniform box, and a likelihood fused from several
sensors by product (Eq. 30) or by quality-weighted sum (Eq. 31), either over all sensors at once
(*centralized*) or per modality cluster whose posteriors are then combined (*hybrid*, Eqs. 36–37).

:class:`GridFilter` is the pure filter: its belief, :class:`DirectionalGridBelief`, is a
:class:`fusetrack.core.GridBelief` that also carries the motion model's velocity estimate; its
measurements are likelihood maps read by
:class:`~fusetrack.sensors.likelihood_map.LikelihoodMapSensor`. Inside a step the probabilities
are plain arrays normalised to 1 (every likelihood is floored, see
:func:`fusetrack.sensors.detection_function.normalize_likelihood`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.ndimage import shift as nd_shift
from scipy.ndimage import uniform_filter1d

from ..core import ConfigError, GridBelief, Measurement, ShapeError, UnknownSensorError, invalid
from ..sensors import LikelihoodMapSensor

Fusion = Literal["product", "sum"]
Architecture = Literal["centralized", "hybrid"]


@dataclass(frozen=True)
class GridSpec:
    """A rectangular field ``[x0, x1] × [y0, y1]`` cut into square cells of side ``cell``."""

    x0: float = 0.0
    x1: float = 35.0
    y0: float = 0.0
    y1: float = 20.0
    cell: float = 0.5

    def __post_init__(self) -> None:
        if not (self.x1 > self.x0 and self.y1 > self.y0 and self.cell > 0):
            raise ConfigError(invalid("grid", self, "x1 > x0, y1 > y0 and cell > 0"))

    @property
    def shape(self) -> tuple[int, int]:
        return (round((self.x1 - self.x0) / self.cell), round((self.y1 - self.y0) / self.cell))

    @property
    def size(self) -> int:
        return self.shape[0] * self.shape[1]

    @cached_property
    def x(self) -> NDArray[np.float64]:
        return _frozen(self.x0 + self.cell * (np.arange(self.shape[0]) + 0.5))

    @cached_property
    def y(self) -> NDArray[np.float64]:
        return _frozen(self.y0 + self.cell * (np.arange(self.shape[1]) + 0.5))

    @cached_property
    def centres(self) -> NDArray[np.float64]:
        """Cell centres ``(size, 2)`` in C order of ``shape`` (x index slow, y index fast)."""
        xx, yy = np.meshgrid(self.x, self.y, indexing="ij")
        return _frozen(np.stack([xx.ravel(), yy.ravel()], axis=1))

    def contains(self, xy: ArrayLike) -> NDArray[np.bool_]:
        p = np.asarray(xy, float)
        return (
            (p[..., 0] >= self.x0)
            & (p[..., 0] <= self.x1)
            & (p[..., 1] >= self.y0)
            & (p[..., 1] <= self.y1)
        )

    def uniform(self) -> NDArray[np.float64]:
        return np.full(self.size, 1.0 / self.size)


def _frozen(a: ArrayLike) -> NDArray[np.float64]:
    """A read-only float array (cached geometry is shared by every caller)."""
    out = np.array(a, dtype=np.float64)
    out.flags.writeable = False
    return out


@dataclass(frozen=True)
class DirectionalMotion:
    """x_{t+1} = x_t + v + U[-δ, δ] per axis (Kushwaha 2010, Eq. 29) as a grid operation.

    The shift by ``v`` is bilinear (sub-cell shifts allowed); mass leaving the field is dropped;
    the uniform noise is a separable box of half-width δ (``2δ/cell + 1`` cells per axis).
    """

    delta: float = 1.5

    def predict(
        self, grid: GridSpec, prob: ArrayLike, v: ArrayLike, delta: float | None = None
    ) -> NDArray[np.float64]:
        p = np.asarray(prob, float).reshape(grid.shape)
        d = np.asarray(v, float) / grid.cell
        if np.any(np.abs(d) > 1e-9):
            p = nd_shift(p, d, order=1, mode="constant", cval=0.0, prefilter=False)
        half = round((self.delta if delta is None else delta) / grid.cell)
        if half > 0:
            size = 2 * half + 1
            p = uniform_filter1d(p, size, axis=0, mode="constant")
            p = uniform_filter1d(p, size, axis=1, mode="constant")
        p = np.maximum(p.ravel(), 0.0)
        total = p.sum()
        return p / total if total > 0 else grid.uniform()


def fuse_product(likelihoods: ArrayLike) -> NDArray[np.float64]:
    """p(z | x) = Π_k p_k(z | x) (Kushwaha 2010, Eq. 30), computed as a normalised log-sum."""
    lk = np.asarray(likelihoods, float)
    if lk.shape[0] == 0:
        return np.full(lk.shape[-1], 1.0 / lk.shape[-1])
    log = np.log(np.maximum(lk, 1e-300)).sum(axis=0)
    p = np.exp(log - log.max())
    return p / p.sum()


def fuse_weighted_sum(likelihoods: ArrayLike, quality: ArrayLike) -> NDArray[np.float64]:
    """p(z | x) = Σ_k q_k p_k(z | x) / Σ_k q_k (Kushwaha 2010, Eq. 31)."""
    lk = np.asarray(likelihoods, float)
    q = np.asarray(quality, float)
    if lk.shape[0] == 0 or not np.sum(q) > 0:
        return np.full(lk.shape[-1], 1.0 / lk.shape[-1])
    p = q @ lk / q.sum()
    return p / p.sum()


def fuse(likelihoods: ArrayLike, quality: ArrayLike, rule: Fusion) -> NDArray[np.float64]:
    if rule == "product":
        return fuse_product(likelihoods)
    if rule == "sum":
        return fuse_weighted_sum(likelihoods, quality)
    raise ConfigError(invalid("fusion", rule, "'product' or 'sum'"))


@dataclass(frozen=True)
class SensorLikelihoods:
    """The per-cell likelihoods of one fusion step: ``values (K, n)``, ``quality (K,)``, the
    modality (cluster) of each sensor (``"audio"``/``"video"``) and, when known, the sensor ids."""

    values: NDArray[np.float64]
    quality: NDArray[np.float64]
    modality: tuple[str, ...]
    sensor_ids: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        v = np.atleast_2d(np.asarray(self.values, float))
        q = np.asarray(self.quality, float).ravel()
        ids_ok = not self.sensor_ids or len(self.sensor_ids) == q.size
        if not (v.shape[0] == q.size == len(self.modality)) or not ids_ok:
            raise ShapeError(
                invalid(
                    "values/quality/modality/sensor_ids",
                    (v.shape, q.size, len(self.modality), len(self.sensor_ids)),
                    "one row, quality and modality (and id, if any) per sensor",
                )
            )
        object.__setattr__(self, "values", v)
        object.__setattr__(self, "quality", q)

    def select(self, modalities: Sequence[str]) -> SensorLikelihoods:
        keep = np.array([m in modalities for m in self.modality], bool)
        return SensorLikelihoods(
            self.values[keep].reshape(-1, self.values.shape[-1]),
            self.quality[keep],
            tuple(m for m in self.modality if m in modalities),
            tuple(s for s, k in zip(self.sensor_ids, keep) if k),
        )

    def measurements(
        self, time: float, modalities: Sequence[str] | None = None
    ) -> list[Measurement]:
        """One likelihood-map :class:`~fusetrack.core.Measurement` per row (of ``modalities``,
        default all), its quality in ``metadata["quality"]``, for :class:`GridFilter` (the id is
        the modality when unknown)."""
        ids = self.sensor_ids or self.modality
        return [
            Measurement(time, sid, row, metadata={"quality": float(q)})
            for sid, row, q, m in zip(ids, self.values, self.quality, self.modality)
            if modalities is None or m in modalities
        ]


def sbe_update(
    predicted: ArrayLike,
    lik: SensorLikelihoods,
    fusion: Fusion,
    architecture: Architecture = "centralized",
    hybrid_alpha: float = 0.5,
    hybrid_divide_prior: bool = False,
) -> NDArray[np.float64]:
    """One measurement update of the grid posterior.

    *centralized*: posterior ∝ fuse(all sensors) × predicted (Kushwaha 2010, Eqs. 28, 30/31).
    *hybrid*: one posterior per modality from the same predicted prior, then their product
    (``fusion="product"``) or the α-weighted sum (``fusion="sum"``) (Kushwaha 2010, Eqs. 36–37).
    The paper writes the combination with likelihood symbols but says the cluster *posteriors*
    are combined; we combine posteriors. Their product counts the prior twice;
    ``hybrid_divide_prior`` divides it out once (which makes hybrid-product equal centralized-product).
    """
    prior = np.asarray(predicted, float)
    if architecture == "centralized" or len(set(lik.modality)) < 2:
        post = fuse(lik.values, lik.quality, fusion) * prior
        return _normalise(post, prior)
    if architecture != "hybrid":
        raise ConfigError(invalid("architecture", architecture, "'centralized' or 'hybrid'"))
    clusters = sorted(set(lik.modality))
    posts = []
    for m in clusters:
        sub = lik.select([m])
        posts.append(_normalise(fuse(sub.values, sub.quality, fusion) * prior, prior))
    if fusion == "product":
        log = np.sum(np.log(np.maximum(posts, 1e-300)), axis=0)
        if hybrid_divide_prior:
            log = log - (len(posts) - 1) * np.log(np.maximum(prior, 1e-300))
        return _normalise(np.exp(log - log.max()), prior)
    weights = (
        np.array([hybrid_alpha, 1 - hybrid_alpha])
        if len(posts) == 2
        else np.full(len(posts), 1 / len(posts))
    )
    return _normalise(weights @ np.array(posts), prior)


def _normalise(p: NDArray[np.float64], fallback: NDArray[np.float64]) -> NDArray[np.float64]:
    total = p.sum()
    if not np.isfinite(total) or total <= 0:
        return fallback / fallback.sum()
    return p / total


@dataclass(frozen=True, eq=False)
class DirectionalGridBelief(GridBelief):
    """A grid posterior and what the directional motion model carries from step to step:
    ``velocity`` (m/s, from smoothed posterior-mean displacements), ``last_estimate`` (the mean
    of the latest posterior; None before the first update), ``updates`` (posteriors so far) and
    ``elapsed`` (seconds predicted since the latest posterior).

    ``linear`` keeps the probabilities per cell (flat, C order, summing to 1) exactly as the
    filter computed them (``log_prob`` is their log), and ``centres`` the cell centres ``(n, 2)``:
    ``prob``, ``mean`` and ``cov`` read them directly (no round trip through the log, no meshgrid).
    """

    velocity: NDArray[np.float64] = field(default_factory=lambda: np.zeros(2))
    last_estimate: NDArray[np.float64] | None = None
    updates: int = 0
    elapsed: float = 0.0
    linear: NDArray[np.float64] | None = field(default=None, repr=False)
    centres: NDArray[np.float64] | None = field(default=None, repr=False)

    @property
    def prob(self) -> NDArray[np.float64]:
        if self.linear is None:
            return super().prob
        return self.linear.reshape(self.log_prob.shape)

    def _flat(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        c = self.points.reshape(-1, self.dim) if self.centres is None else self.centres
        return self.prob.ravel(), c

    @property
    def mean(self) -> NDArray[np.float64]:
        """Σ p_i c_i."""
        p, c = self._flat()
        return np.asarray(p @ c, dtype=np.float64)

    @property
    def cov(self) -> NDArray[np.float64]:
        """Σ p_i (c_i - x̂)(c_i - x̂)^T (spec 003 §2.5 step 4: the paper reports det Σ)."""
        p, c = self._flat()
        r = c - p @ c
        return np.asarray((r * p[:, None]).T @ r, dtype=np.float64)


@dataclass(frozen=True, eq=False)
class GridFilter:
    """Grid SBE as a pure :class:`~fusetrack.core.Filter` (Kushwaha 2010, Eq. 28).

    ``predict`` shifts the grid by the belief's velocity × dt and spreads it by the directional
    box (Eq. 29; δ = ``first_delta`` for the first two predictions, spec 003 §2.5 [C]).
    ``update`` multiplies by the fused likelihood maps of the measurements (Eqs. 30/31, hybrid
    Eqs. 36–37, :func:`sbe_update`); each measurement's value is a likelihood map interpreted by
    its sensor in ``sensors`` (:class:`~fusetrack.sensors.likelihood_map.LikelihoodMapSensor`,
    which also names its modality), its quality q_k is ``metadata["quality"]`` (default 1). An
    update then re-estimates the velocity: v ← 0.5 v + 0.5 (x̂_t − x̂_{t−1}) / dt (the first
    displacement as is), clipped at ``max_speed`` (spec 003 §2.5 [C]). An update without
    measurements keeps the predicted density (a coasting step) and still re-estimates the
    velocity, so :meth:`step` always updates.
    """

    grid: GridSpec
    sensors: Mapping[str, LikelihoodMapSensor]
    fusion: Fusion = "product"
    architecture: Architecture = "centralized"
    motion: DirectionalMotion = field(default_factory=DirectionalMotion)
    first_delta: float = 3.0
    max_speed: float = 20.0  # m/s (5 m per step at 4 Hz)
    hybrid_alpha: float = 0.5
    hybrid_divide_prior: bool = False

    def __post_init__(self) -> None:
        if self.fusion not in ("product", "sum"):
            raise ConfigError(invalid("fusion", self.fusion, "'product' or 'sum'"))
        if self.architecture not in ("centralized", "hybrid"):
            raise ConfigError(
                invalid("architecture", self.architecture, "'centralized' or 'hybrid'")
            )

    def initial(self, prior: ArrayLike | None = None) -> DirectionalGridBelief:
        """The belief before any step: ``prior`` per cell (normalised; default uniform)
        (Kushwaha 2010: from the audio detections at track start)."""
        if prior is None:
            p = self.grid.uniform()
        else:
            p = np.asarray(prior, float).ravel()
            if p.shape != (self.grid.size,) or not p.sum() > 0:
                raise ShapeError(
                    invalid("prior", p.shape, f"({self.grid.size},) with positive mass")
                )
            p = p / p.sum()
        return self._belief(p)

    def predict(
        self, belief: DirectionalGridBelief, dt: float, rng: np.random.Generator | None = None
    ) -> DirectionalGridBelief:
        delta = self.first_delta if belief.updates < 2 else None
        p = self.motion.predict(self.grid, belief.prob, belief.velocity * dt, delta)
        return self._belief(
            p, belief.velocity, belief.last_estimate, belief.updates, belief.elapsed + dt
        )

    def update(
        self,
        belief: DirectionalGridBelief,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> DirectionalGridBelief:
        post = sbe_update(
            belief.prob.ravel(),
            self.likelihoods(measurements),
            self.fusion,
            self.architecture,
            self.hybrid_alpha,
            self.hybrid_divide_prior,
        )
        mean = post @ self.grid.centres  # the posterior mean, as DirectionalGridBelief.mean
        return self._belief(post, self._velocity(belief, mean), mean, belief.updates + 1, 0.0)

    def step(
        self,
        belief: DirectionalGridBelief,
        dt: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> DirectionalGridBelief:
        """Predict by ``dt`` (when > 0), then update, also without measurements."""
        predicted = self.predict(belief, dt) if dt > 0 else belief
        return self.update(predicted, measurements)

    def likelihoods(self, measurements: Sequence[Measurement]) -> SensorLikelihoods:
        """The measurements' likelihood maps, qualities and modalities, in their order."""
        rows, quality, modality = [], [], []
        for m in measurements:
            sensor = self.sensors.get(m.sensor_id)
            if sensor is None:
                raise UnknownSensorError(
                    invalid("sensor_id", m.sensor_id, f"one of {sorted(self.sensors)}")
                )
            rows.append(sensor.cell_likelihood(m.value))
            quality.append(float(m.metadata.get("quality", 1.0)))
            modality.append(sensor.modality)
        return SensorLikelihoods(
            np.array(rows).reshape(-1, self.grid.size), np.array(quality), tuple(modality)
        )

    def _velocity(
        self, belief: DirectionalGridBelief, mean: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        if belief.last_estimate is None or not belief.elapsed > 0:
            return belief.velocity
        step = (mean - belief.last_estimate) / belief.elapsed
        v = step if belief.updates == 1 else 0.5 * belief.velocity + 0.5 * step
        speed = float(np.hypot(*v))
        return v if speed <= self.max_speed else v * (self.max_speed / speed)

    def _belief(
        self,
        prob: NDArray[np.float64],
        velocity: NDArray[np.float64] | None = None,
        last_estimate: NDArray[np.float64] | None = None,
        updates: int = 0,
        elapsed: float = 0.0,
    ) -> DirectionalGridBelief:
        prob.flags.writeable = False  # the belief is a value: its arrays are never changed
        with np.errstate(divide="ignore"):
            log_prob = np.log(prob).reshape(self.grid.shape)
        return DirectionalGridBelief(
            (self.grid.x, self.grid.y),
            log_prob,
            np.zeros(2) if velocity is None else velocity,
            last_estimate,
            updates,
            elapsed,
            prob,
            self.grid.centres,
        )


def map_sensors(
    grid: GridSpec, sensor_ids: Sequence[str], modality: Callable[[str], str] | None = None
) -> dict[str, LikelihoodMapSensor]:
    """One :class:`LikelihoodMapSensor` per id on ``grid`` (``modality(id)``, default "all")."""
    return {
        sid: LikelihoodMapSensor(
            sid, (grid.x, grid.y), "all" if modality is None else modality(sid)
        )
        for sid in sensor_ids
    }
