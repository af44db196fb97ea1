"""PF-DWT: particle-filter then wavelet denoising of images with mixed Gaussian + Cauchy noise
(Zhai 2007, Sec. 6.2, Fig 78).

Stage 1 (Eqs. 95-102): a raster-scan (rows top to bottom, columns left to right as "time")
particle filter with a Kalman proposal on the reduced-order 2-D AR image model
``I(i,j) = h1 I(i,j-1) + h2 I(i-1,j) + h3 I(i-1,j-1)`` (Eq. 95). The Kalman filter runs on the
state ``x(i,j) = [I(i,j), I(i,j-1), I(i-1,j+1), I(i-1,j)]`` (Eqs. 96-97; ``u(i,j)`` = the previous
row's estimate of ``I(i-1,j+1)``). The thesis's text swaps Q and R (spec choice 30: Q process,
R measurement). Per pixel the particle filter works on the scalar ``I(i,j)`` (the 4-D prior is
degenerate; spec choice 29): proposal ``N(x̂_1, inflation P_11)``, prior
``N(h1 Î(i,j-1) + h2 Î(i-1,j) + h3 Î(i-1,j-1), q1)``, likelihood the exact pdf of Gaussian
(variance 200) + Cauchy (scale 5) noise, i.e. a Voigt profile (tabulated once from
``scipy.special.voigt_profile`` and interpolated; Cauchy tails beyond the table), systematic
resampling, estimate = mean of the resampled particles, which is then fed back into the Kalman
state (``x̂_1 <- Î``, ``P_11 <-`` particle variance).

Stage 2 (Eqs. 103-107): translation-invariant wavelet thresholding of the PF output: cycle
spinning over all shifts ``p`` in an ``s x s`` block (``X^p[n] = X[n - p]``, threshold, invert,
shift back, average), universal threshold ``T = sigma sqrt(2 ln N_d)`` with
``sigma = median(|HH_1|)/0.6745``, hard (Eq. 104) or soft (Eq. 105) thresholding of the details.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numba
import numpy as np
from numpy.typing import NDArray
from scipy.special import voigt_profile

from ..core import ConfigError, ShapeError, invalid

Array = NDArray[np.float64]
_TABLE_HALF, _TABLE_STEP = 3000.0, 0.25


def voigt_log_table(sigma: float, gamma: float) -> tuple[Array, float, float]:
    """``log`` Voigt pdf on ``[-3000, 3000]`` in steps of 0.25, with the grid start and step."""
    x = np.arange(-_TABLE_HALF, _TABLE_HALF + _TABLE_STEP, _TABLE_STEP)
    return np.log(voigt_profile(x, sigma, gamma)), -_TABLE_HALF, _TABLE_STEP


@numba.njit(cache=True)
def _log_lik(
    r: float, table: np.ndarray, x0: float, dx: float, gamma: float
) -> float:  # pragma: no cover
    u = (r - x0) / dx
    n = table.shape[0]
    if u <= 0.0 or u >= n - 1:
        return np.log(gamma / np.pi / (r * r + gamma * gamma))  # Cauchy tail
    k = int(u)
    f = u - k
    return table[k] * (1.0 - f) + table[k + 1] * f


@numba.njit(cache=True)
def _raster_pf(
    y: np.ndarray,
    init: np.ndarray,
    h: np.ndarray,
    q1: float,
    q3: float,
    r: float,
    n: int,
    inflation: float,
    table: np.ndarray,
    x0: float,
    dx: float,
    gamma: float,
    seed: int,
) -> np.ndarray:  # pragma: no cover - jit
    np.random.seed(seed)  # noqa: NPY002
    rows, cols = y.shape
    est = init.copy()
    C = np.zeros((4, 4))
    C[0, 0], C[0, 2], C[0, 3] = h[0], h[1], h[2]
    C[1, 0] = 1.0
    C[3, 2] = 1.0
    parts = np.empty(n)
    logw = np.empty(n)
    w = np.empty(n)
    res = np.empty(n)
    for i in range(1, rows):
        x = np.array([est[i, 0], est[i, 0], est[i - 1, 1], est[i - 1, 0]])
        P = np.eye(4) * q1
        for j in range(1, cols):
            u = est[i - 1, j + 1] if j + 1 < cols else est[i - 1, j]
            xb = C @ x
            xb[2] = u
            Pb = C @ P @ C.T
            Pb[0, 0] += q1
            Pb[2, 2] += q3
            s = Pb[0, 0] + r
            K = Pb[:, 0] / s
            innov = y[i, j] - xb[0]
            x = xb + K * innov
            P = Pb - np.outer(K, Pb[0, :])
            # particle filter on I(i, j)
            m_q = x[0]
            v_q = max(P[0, 0], 1e-6) * inflation
            m_p = h[0] * est[i, j - 1] + h[1] * est[i - 1, j] + h[2] * est[i - 1, j - 1]
            top = -1e300
            for k in range(n):
                e = np.random.standard_normal()  # noqa: NPY002
                xk = m_q + np.sqrt(v_q) * e
                parts[k] = xk
                lw = _log_lik(y[i, j] - xk, table, x0, dx, gamma)
                lw += -0.5 * (xk - m_p) ** 2 / q1 + 0.5 * e * e + 0.5 * np.log(v_q / q1)
                logw[k] = lw
                if lw > top:
                    top = lw
            tot = 0.0
            for k in range(n):
                w[k] = np.exp(logw[k] - top)
                tot += w[k]
            # systematic resampling
            u0 = np.random.random() / n  # noqa: NPY002
            c = w[0] / tot
            m = 0
            mean = 0.0
            for k in range(n):
                uk = u0 + k / n
                while uk > c and m < n - 1:
                    m += 1
                    c += w[m] / tot
                res[k] = parts[m]
                mean += parts[m]
            mean /= n
            var = 0.0
            for k in range(n):
                var += (res[k] - mean) ** 2
            var /= n
            est[i, j] = mean
            x[0] = mean
            P[0, :] = 0.0
            P[:, 0] = 0.0
            P[0, 0] = max(var, 1e-6)
    return est


def median3(img: Array) -> Array:
    """3 x 3 median filter with edge replication."""
    from scipy.ndimage import median_filter

    return np.asarray(median_filter(img, size=3, mode="nearest"), dtype=np.float64)


@dataclass(frozen=True)
class RasterParticleFilter:
    """Stage 1 of PF-DWT (defaults: spec choices for the thesis's missing values)."""

    h: tuple[float, float, float] = (0.815493, 0.489516, -0.308866)  # Zhai 2007, Sec. 6.2.3
    q1: float = 1000.0  # spec choice 100 rejects real edges as outliers (see the E20 report)
    q3: float = 50.0
    r: float = 1000.0
    n_particles: int = 100
    inflation: float = 4.0
    noise_var: float = 200.0
    cauchy_scale: float = 5.0

    def __call__(self, noisy: Array, seed: int = 0) -> Array:
        y = np.asarray(noisy, dtype=np.float64)
        init = median3(y)  # first row and column (spec choice)
        table, x0, dx = voigt_log_table(float(np.sqrt(self.noise_var)), self.cauchy_scale)
        return np.asarray(
            _raster_pf(
                y,
                init,
                np.asarray(self.h, float),
                self.q1,
                self.q3,
                self.r,
                int(self.n_particles),
                self.inflation,
                table,
                x0,
                dx,
                self.cauchy_scale,
                int(seed),
            )
        )


@numba.njit(cache=True)
def _raster_posterior_mean(
    y: np.ndarray,
    init: np.ndarray,
    h: np.ndarray,
    q1: float,
    table: np.ndarray,
    x0: float,
    dx: float,
    gamma: float,
    nodes: np.ndarray,
) -> np.ndarray:  # pragma: no cover - jit
    rows, cols = y.shape
    est = init.copy()
    sd = np.sqrt(q1)
    logw = np.empty(nodes.shape[0])
    for i in range(1, rows):
        for j in range(1, cols):
            m_p = h[0] * est[i, j - 1] + h[1] * est[i - 1, j] + h[2] * est[i - 1, j - 1]
            top = -1e300
            for k in range(nodes.shape[0]):
                xk = m_p + sd * nodes[k]
                lw = -0.5 * nodes[k] ** 2 + _log_lik(y[i, j] - xk, table, x0, dx, gamma)
                logw[k] = lw
                if lw > top:
                    top = lw
            num = 0.0
            den = 0.0
            for k in range(nodes.shape[0]):
                w = np.exp(logw[k] - top)
                num += w * nodes[k]
                den += w
            est[i, j] = m_p + sd * num / den
    return est


def raster_posterior_mean(
    pf: RasterParticleFilter, noisy: Array, half_width: float = 8.0, nodes: int = 401
) -> Array:
    """The ``n_particles -> infinity`` limit of ``pf`` on ``noisy``: the same raster recursion
    with each pixel's particle mean replaced by its exact posterior mean under the printed
    per-pixel model, prior ``N(h1 Î(i,j-1) + h2 Î(i-1,j) + h3 Î(i-1,j-1), q1)`` times the Voigt
    likelihood (Eqs. 95-102), summed on a uniform grid of ``nodes`` points over
    ``+- half_width`` prior standard deviations (the Kalman proposal only shapes the particle
    filter's Monte Carlo error, so it has no part here; first row and column as in ``pf``)."""
    y = np.asarray(noisy, dtype=np.float64)
    if y.ndim != 2 or min(y.shape) < 2:
        raise ShapeError(invalid("noisy", y.shape, "a 2-D image of at least 2 x 2 pixels"))
    if half_width <= 0 or nodes < 3:
        raise ConfigError(
            invalid("(half_width, nodes)", (half_width, nodes), "half_width > 0, nodes >= 3")
        )
    table, x0, dx = voigt_log_table(float(np.sqrt(pf.noise_var)), pf.cauchy_scale)
    u = np.linspace(-half_width, half_width, int(nodes))
    return np.asarray(
        _raster_posterior_mean(
            y, median3(y), np.asarray(pf.h, float), pf.q1, table, x0, dx, pf.cauchy_scale, u
        )
    )


def universal_threshold(img: Array, wavelet: str = "db4") -> float:
    """``sigma sqrt(2 ln N_d)`` with ``sigma = median(|HH_1|)/0.6745`` (Eq. 103)."""
    import pywt

    _, (_, _, hh) = pywt.dwt2(img, wavelet, mode="periodization")
    sigma = float(np.median(np.abs(hh)) / 0.6745)
    return sigma * float(np.sqrt(2.0 * np.log(img.size)))


def wavelet_threshold(
    img: Array,
    mode: Literal["hard", "soft"] = "hard",
    wavelet: str = "db4",
    level: int = 4,
    threshold: float | None = None,
) -> Array:
    """One decimated transform, details thresholded (Eqs. 104-105), inverted."""
    import pywt

    t = universal_threshold(img, wavelet) if threshold is None else threshold
    coeffs = pywt.wavedec2(img, wavelet, mode="periodization", level=level)
    out = [coeffs[0]] + [tuple(pywt.threshold(c, t, mode=mode) for c in d) for d in coeffs[1:]]
    return np.asarray(
        pywt.waverec2(out, wavelet, mode="periodization")[: img.shape[0], : img.shape[1]]
    )


def ti_threshold(
    img: Array,
    mode: Literal["hard", "soft"] = "hard",
    wavelet: str = "db4",
    level: int = 4,
    shifts: int = 8,
) -> Array:
    """Translation-invariant thresholding by cycle spinning over ``shifts x shifts`` shifts
    (Eqs. 106-107); the threshold is estimated once on the unshifted image."""
    t = universal_threshold(img, wavelet)
    acc = np.zeros_like(img, dtype=np.float64)
    for a in range(shifts):
        for b in range(shifts):
            s = np.roll(img, (a, b), axis=(0, 1))
            acc += np.roll(wavelet_threshold(s, mode, wavelet, level, t), (-a, -b), axis=(0, 1))
    return acc / shifts**2


def isnr(clean: Array, noisy: Array, restored: Array) -> float:
    """``10 log10(||I - Y||^2 / ||I - Î||^2)`` (standard ISNR; the thesis does not define it)."""
    return float(10.0 * np.log10(np.sum((clean - noisy) ** 2) / np.sum((clean - restored) ** 2)))


def add_mixed_noise(
    img: Array, rng: np.random.Generator, var: float = 200.0, cauchy: float = 5.0, clip: bool = True
) -> Array:
    """AWGN of variance ``var`` plus Cauchy noise of scale ``cauchy`` (Sec. 6.2.3), clipped to [0, 255]."""
    y = (
        img
        + np.sqrt(var) * rng.standard_normal(img.shape)
        + cauchy * rng.standard_cauchy(img.shape)
    )
    return np.clip(y, 0.0, 255.0) if clip else y
