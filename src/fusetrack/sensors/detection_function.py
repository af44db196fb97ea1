"""Angular detection functions and their per-cell likelihoods on a 2-D grid (Kushwaha 2010, Ch. III).

A direction-finding node reports a *detection function* λ(θ): beam energies of a microphone array
(36 values, 10° apart, all round) or foreground-pixel counts per angle bin of a camera (160 values
over its field of view). The grid filter needs, for every cell, one number: the mean of λ over
the angular interval [φ_A, φ_B] the cell subtends at the sensor (Kushwaha 2010, Eq. 32,
``p_k(x_i, y_i) = 1/(φ_B - φ_A) Σ_{φ_A ≤ θ ≤ φ_B} λ_k(θ)``).

Because λ between samples is piecewise linear (Kushwaha 2010, Eq. 34, "w λ(θ_{i-1}) + (1-w) λ(θ_i)"),
that mean is a *linear* function of the samples. :func:`arc_mean_matrix` computes it exactly
(integral of the interpolant, not a 0.5° sum) as a matrix ``W`` with ``cell_means = W @ λ``, built
once per sensor: a fusion step is then one small matrix-vector product per sensor.
Video detection functions are Gaussian mixtures (Kushwaha 2010, Eq. 35); their arc means are
closed form (:func:`mixture_arc_mean`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import ndtr

from ..core import ConfigError, ShapeError, invalid

TWO_PI = 2.0 * np.pi


@dataclass(frozen=True, eq=False)
class AngularSampling:
    """Where a detection function is sampled, in the sensor's own frame (radians).

    ``start`` is the first sample's angle, ``step`` the spacing and ``size`` the number of samples.
    ``periodic`` functions (a microphone array's beams, ``size * step == 2π``) wrap around; the
    others (a camera's bins) are held constant beyond their ends.
    """

    start: float
    step: float
    size: int
    periodic: bool

    def __post_init__(self) -> None:
        if not self.step > 0:
            raise ConfigError(invalid("step", self.step, "a positive angle in radians"))
        if self.size < 2:
            raise ConfigError(invalid("size", self.size, "at least 2 samples"))
        if self.periodic and not np.isclose(self.size * self.step, TWO_PI):
            raise ConfigError(
                invalid("size*step", self.size * self.step, "2π for a periodic function")
            )

    @classmethod
    def beams(cls, n_beams: int = 36) -> AngularSampling:
        """``n_beams`` beams θ_i = i·2π/n_beams (Kushwaha 2010, Ch. III: 36 beams, 10°)."""
        return cls(0.0, TWO_PI / n_beams, n_beams, True)

    @classmethod
    def camera_bins(cls, fov: float, n_bins: int = 160) -> AngularSampling:
        """Bin centres over a field of view [-fov/2, fov/2] (Kushwaha 2010, Eq. 23, M = 160)."""
        step = fov / n_bins
        return cls(-fov / 2 + step / 2, step, n_bins, False)

    @property
    def angles(self) -> NDArray[np.float64]:
        return np.asarray(self.start + self.step * np.arange(self.size), dtype=np.float64)

    def check(self, values: ArrayLike, field: str = "detection function") -> NDArray[np.float64]:
        v = np.asarray(values, float)
        if v.shape[-1:] != (self.size,):
            raise ShapeError(invalid(f"{field}.shape", v.shape, f"(..., {self.size})"))
        return v


def interpolate(
    sampling: AngularSampling, values: ArrayLike, theta: ArrayLike
) -> NDArray[np.float64]:
    """λ(θ) by piecewise-linear interpolation of the samples (Kushwaha 2010, Eq. 34)."""
    v = sampling.check(values)
    u = (np.asarray(theta, float) - sampling.start) / sampling.step
    if sampling.periodic:
        u = np.mod(u, sampling.size)
        j = np.minimum(np.floor(u).astype(int), sampling.size - 1)
        w = u - j
        return (1 - w) * v[..., j] + w * v[..., (j + 1) % sampling.size]
    u = np.clip(u, 0, sampling.size - 1)
    j = np.minimum(np.floor(u).astype(int), sampling.size - 2)
    w = u - j
    return (1 - w) * v[..., j] + w * v[..., j + 1]


def cell_arcs(
    sensor_xy: ArrayLike, heading: float, centres: ArrayLike, half_size: float | tuple[float, float]
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """The angular interval [φ_A, φ_B] each rectangular cell subtends at a sensor (its frame).

    ``centres`` (n, 2) are cell centres, ``half_size`` the cell half-width (or (hx, hy)).
    Returns ``(lo, hi, inside)``: the smallest arc holding the bearings of the four vertices
    (width < π when the sensor is outside the cell), with ``lo`` in [-π, π) and ``hi`` > ``lo``;
    for a cell that contains the sensor the arc is the full circle (Kushwaha 2010, Ch. III:
    "[0, 2π] if the sensor lies inside the cell") and ``inside`` is True.
    """
    c = np.asarray(centres, float).reshape(-1, 2)
    if isinstance(half_size, tuple):
        hx, hy = float(half_size[0]), float(half_size[1])
    else:
        hx = hy = float(half_size)
    s = np.asarray(sensor_xy, float)[:2]
    offsets = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
    v = c[:, None, :] + offsets[None] - s  # (n, 4, 2)
    centre_bearing = np.arctan2(c[:, 1] - s[1], c[:, 0] - s[0]) - heading
    bearings = np.arctan2(v[..., 1], v[..., 0]) - heading
    rel = np.mod(bearings - centre_bearing[:, None] + np.pi, TWO_PI) - np.pi
    lo = centre_bearing + rel.min(axis=1)
    hi = centre_bearing + rel.max(axis=1)
    inside = (np.abs(c[:, 0] - s[0]) <= hx) & (np.abs(c[:, 1] - s[1]) <= hy)
    shift = np.mod(lo + np.pi, TWO_PI) - np.pi - lo
    lo, hi = lo + shift, hi + shift
    lo = np.where(inside, -np.pi, lo)
    hi = np.where(inside, np.pi, hi)
    return lo, hi, inside


def _antiderivative_coefficients(
    theta: NDArray[np.float64], start: float, step: float, size: int
) -> NDArray[np.float64]:
    """``A (n, size)`` with ``∫_start^θ λ = A @ λ`` for the piecewise-linear interpolant held
    constant beyond both ends (a non-periodic sampling)."""
    n = theta.size
    cum = np.zeros((size, size))  # cum[j] = coefficients of ∫ from node 0 to node j
    for j in range(1, size):
        cum[j] = cum[j - 1]
        cum[j, j - 1] += step / 2
        cum[j, j] += step / 2
    u = (theta - start) / step
    a = np.zeros((n, size))
    rows = np.arange(n)
    below = u < 0
    above = u > size - 1
    mid = ~(below | above)
    a[below, 0] = u[below] * step
    a[above] = cum[size - 1] + 0.0
    a[above, size - 1] += (u[above] - (size - 1)) * step
    j = np.minimum(np.floor(u[mid]).astype(int), size - 2)
    t = u[mid] - j
    a[mid] = cum[j]
    r = rows[mid]
    a[r, j] += step * (t - t * t / 2)
    a[r, j + 1] += step * t * t / 2
    return a


def arc_mean_matrix(sampling: AngularSampling, lo: ArrayLike, hi: ArrayLike) -> NDArray[np.float64]:
    """``W (n, size)`` with ``W @ λ`` = the mean of the interpolated λ over each arc [lo, hi].

    This is Kushwaha 2010, Eq. 32 (mean of the detection function over the cell's angular
    interval) taken as the exact integral of the Eq. 34 interpolant divided by the arc width.
    Arcs are in the sensor frame; periodic samplings accept any arc up to 2π wide.
    """
    lo = np.asarray(lo, float).ravel()
    hi = np.asarray(hi, float).ravel()
    width = hi - lo
    if np.any(width < 0):
        raise ConfigError(invalid("hi - lo", width.min(), "arcs with hi >= lo"))
    k = sampling.size
    if sampling.periodic:
        # Unroll two turns: every arc then starts in [start, start + 2π) and ends before + 4π.
        a0 = sampling.start + np.mod(lo - sampling.start, TWO_PI)
        b0 = a0 + width
        a = _antiderivative_coefficients(a0, sampling.start, sampling.step, 2 * k + 1)
        b = _antiderivative_coefficients(b0, sampling.start, sampling.step, 2 * k + 1)
        diff = b - a
        folded = diff[:, :k] + diff[:, k : 2 * k]
        folded[:, 0] += diff[:, 2 * k]
    else:
        folded = _antiderivative_coefficients(
            hi, sampling.start, sampling.step, k
        ) - _antiderivative_coefficients(lo, sampling.start, sampling.step, k)
    out = np.empty_like(folded)
    wide = width > 1e-12
    out[wide] = folded[wide] / width[wide, None]
    if np.any(~wide):  # a zero-width arc: the value at that angle
        # row i of eye(k) is the unit function at sample i: interpolate gives (k, m)
        out[~wide] = interpolate(sampling, np.eye(k), lo[~wide]).T
    return out


def mixture_arc_mean(
    weights: ArrayLike, means: ArrayLike, sigmas: ArrayLike, lo: ArrayLike, hi: ArrayLike
) -> NDArray[np.float64]:
    """Mean over each arc [lo, hi] of λ(θ) = Σ a_i N(θ | μ_i, σ_i²) (Kushwaha 2010, Eqs. 32, 35).

    Closed form: Σ a_i (Φ((hi - μ_i)/σ_i) - Φ((lo - μ_i)/σ_i)) / (hi - lo). ``lo``/``hi`` must be in
    the same unwrapped frame as the means (camera angles near 0)."""
    a = np.asarray(weights, float)
    mu = np.asarray(means, float)
    sd = np.asarray(sigmas, float)
    lo = np.asarray(lo, float)[..., None]
    hi = np.asarray(hi, float)[..., None]
    mass = ndtr((hi - mu) / sd) - ndtr((lo - mu) / sd)
    width = np.maximum(hi - lo, 1e-12)[..., 0]
    return (mass * a).sum(axis=-1) / width


def normalize_likelihood(values: ArrayLike, floor: float = 1e-3) -> NDArray[np.float64]:
    """Map a non-negative score to a unit-sum likelihood with a floor (spec 003 §2.2, [C]).

    λ̃ = (λ - min λ) / Σ(λ - min λ), then + ``floor`` × mean(λ̃), renormalised, so that a
    product of sensors can never reach 0. A flat score becomes uniform. The last axis is the cells.
    """
    v = np.asarray(values, float)
    v = v - v.min(axis=-1, keepdims=True)
    total = v.sum(axis=-1, keepdims=True)
    n = v.shape[-1]
    flat = ~(total > 0)
    v = np.where(flat, 1.0 / n, v / np.where(flat, 1.0, total))
    v = v + floor / n
    return v / v.sum(axis=-1, keepdims=True)
