"""Grid-based sequential Bayesian estimation (SBE) of a 2-D position (Kushwaha 2010, Ch. III).

The posterior lives on a regular grid of cells (35 m × 20 m with 0.5 m cells in the paper: 2800
cells). One step is (Kushwaha 2010, Eq. 28)

    p(x_{t+1} | z_{1:t+1}) ∝ p(z_{t+1} | x_{t+1}) Σ_{x_t} p(x_{t+1} | x_t) p(x_t | z_{1:t}),

with the "directional" motion model x_{t+1} = x_t + v + U[-δ, δ] (Eq. 29), i.e. a shift of the
grid by v followed by a convolution with a uniform box, and a likelihood fused from several
sensors by product (Eq. 30) or by quality-weighted sum (Eq. 31), either over all sensors at once
(*centralized*) or per modality cluster whose posteriors are then combined (*hybrid*, Eqs. 36–37).

Probabilities are kept as plain arrays normalised to 1 each step (no log domain is needed: every
likelihood is floored, see :func:`fusetrack.sensors.detection_function.normalize_likelihood`).
:meth:`GridSpec.belief` converts to :class:`fusetrack.core.GridBelief` for the rest of the library.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.ndimage import shift as nd_shift
from scipy.ndimage import uniform_filter1d

from ..core.beliefs import GridBelief
from ..core.errors import ConfigError, ShapeError, invalid

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

    @property
    def x(self) -> NDArray[np.float64]:
        return np.asarray(self.x0 + self.cell * (np.arange(self.shape[0]) + 0.5), dtype=np.float64)

    @property
    def y(self) -> NDArray[np.float64]:
        return np.asarray(self.y0 + self.cell * (np.arange(self.shape[1]) + 0.5), dtype=np.float64)

    @property
    def centres(self) -> NDArray[np.float64]:
        """Cell centres ``(size, 2)`` in C order of ``shape`` (x index slow, y index fast)."""
        xx, yy = np.meshgrid(self.x, self.y, indexing="ij")
        return np.stack([xx.ravel(), yy.ravel()], axis=1)

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

    def belief(self, prob: ArrayLike) -> GridBelief:
        p = np.asarray(prob, float).reshape(self.shape)
        with np.errstate(divide="ignore"):
            return GridBelief((self.x, self.y), np.log(p))

    def mean_cov(self, prob: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Posterior mean and covariance Σ p_i (c_i - x̂)(c_i - x̂)^T (spec 003 §2.5 step 4)."""
        p = np.asarray(prob, float).ravel()
        c = self.centres
        m = p @ c
        r = c - m
        return m, (r * p[:, None]).T @ r


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
    """The per-cell likelihoods of one fusion step: ``values (K, n)``, ``quality (K,)`` and the
    modality (cluster) of each sensor (``"audio"``/``"video"``)."""

    values: NDArray[np.float64]
    quality: NDArray[np.float64]
    modality: tuple[str, ...]

    def __post_init__(self) -> None:
        v = np.atleast_2d(np.asarray(self.values, float))
        q = np.asarray(self.quality, float).ravel()
        if not (v.shape[0] == q.size == len(self.modality)):
            raise ShapeError(
                invalid(
                    "values/quality/modality",
                    (v.shape, q.size, len(self.modality)),
                    "one row, quality and modality per sensor",
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
        )


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


@dataclass
class GridTracker:
    """The SBE tracker: motion prediction with a velocity from smoothed posterior-mean
    displacements (spec 003 §2.5, [C]: v ← 0.5 v + 0.5 (x̂_t - x̂_{t-1}); δ doubled at the first
    prediction) and one :func:`sbe_update` per fusion step. ``estimates`` and ``covariances``
    collect the posterior mean and covariance (the paper reports det Σ as uncertainty)."""

    grid: GridSpec
    fusion: Fusion
    architecture: Architecture = "centralized"
    motion: DirectionalMotion = field(default_factory=DirectionalMotion)
    first_delta: float = 3.0
    max_step: float = 5.0  # |v| per step is clipped here (20 m/s at 4 Hz)
    hybrid_alpha: float = 0.5
    hybrid_divide_prior: bool = False
    prob: NDArray[np.float64] | None = None
    velocity: NDArray[np.float64] = field(default_factory=lambda: np.zeros(2))
    estimates: list[NDArray[np.float64]] = field(default_factory=list)
    covariances: list[NDArray[np.float64]] = field(default_factory=list)

    def initialize(self, prior: ArrayLike) -> None:
        """Start from a given prior (Kushwaha 2010: from the audio detections at track start)."""
        p = np.asarray(prior, float).ravel()
        if p.shape != (self.grid.size,) or not p.sum() > 0:
            raise ShapeError(invalid("prior", p.shape, f"({self.grid.size},) with positive mass"))
        self.prob = p / p.sum()

    def step(self, lik: SensorLikelihoods) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        if self.prob is None:
            predicted = self.grid.uniform()
        else:
            first = len(self.estimates) < 2
            predicted = self.motion.predict(
                self.grid, self.prob, self.velocity, self.first_delta if first else None
            )
        self.prob = sbe_update(
            predicted,
            lik,
            self.fusion,
            self.architecture,
            self.hybrid_alpha,
            self.hybrid_divide_prior,
        )
        mean, cov = self.grid.mean_cov(self.prob)
        if self.estimates:
            step = mean - self.estimates[-1]
            v = step if len(self.estimates) == 1 else 0.5 * self.velocity + 0.5 * step
            speed = float(np.hypot(*v))
            self.velocity = v if speed <= self.max_step else v * (self.max_step / speed)
        self.estimates.append(mean)
        self.covariances.append(cov)
        return mean, cov

    def coast(self) -> None:
        """A step with no measurement at all: predict only."""
        self.step(SensorLikelihoods(np.empty((0, self.grid.size)), np.empty(0), ()))
