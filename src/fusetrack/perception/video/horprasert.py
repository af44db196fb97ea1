"""Statistical background subtraction with brightness and chromaticity distortion
(Horprasert, Harwood & Davis 1999; Nott 2009, Sec. 4.1).

Every pixel ``i`` of the empty scene is modelled by the 4-tuple ``<mu_i, sigma_i, a_i, b_i>``:
the mean and standard deviation of its colour over ``N`` training frames, and the spread of its
brightness and chromaticity distortions. For a colour ``I`` (per channel ``c``)::

    alpha_i = sum_c I_c mu_c / sigma_c^2  /  sum_c (mu_c / sigma_c)^2        brightness distortion
    CD_i    = sqrt(sum_c ((I_c - alpha_i mu_c) / sigma_c)^2)                 chromaticity distortion
    a_i     = RMS over training of (alpha_i - 1),   b_i = RMS of CD_i

A new pixel is normalised, ``alpha^ = (alpha - 1) / a``, ``CD^ = CD / b``, and classified::

    F (foreground)  CD^ > tau_CD  or  alpha < alpha_lo   (too dark to be a shadow)
    B (background)  tau_a2 < alpha^ < tau_a1
    S (shadow)      alpha^ < 0           (same chromaticity, darker)
    H (highlight)   otherwise            (same chromaticity, brighter)

The thresholds come from a detection rate ``r``: ``tau_CD`` and ``(tau_a2, tau_a1)`` are chosen
so that a fraction ``r`` of the training samples is background ("the classification threshold is
set based on confidence level so that the static background does not get classified as
foreground", Nott 2009, Sec. 4.1). The foreground mask is ``F`` only.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from ...core import ConfigError, ShapeError, invalid

BACKGROUND, FOREGROUND, SHADOW, HIGHLIGHT = 0, 1, 2, 3
_MAX_THRESHOLD_SAMPLES = 4_000_000


@njit(cache=True)
def _alpha_cd_kernel(
    frames: NDArray[np.float32],
    k: NDArray[np.float32],
    inv_sigma: NDArray[np.float32],
    m: NDArray[np.float32],
) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """``alpha`` and ``CD`` of frames ``(N, H, W, 3)`` (fused form of :func:`_distortions`)."""
    n, h, w = frames.shape[0], frames.shape[1], frames.shape[2]
    alpha = np.empty((n, h, w), np.float32)
    cd = np.empty((n, h, w), np.float32)
    for t in range(n):
        for i in range(h):
            for j in range(w):
                i0, i1, i2 = frames[t, i, j, 0], frames[t, i, j, 1], frames[t, i, j, 2]
                a = i0 * k[i, j, 0] + i1 * k[i, j, 1] + i2 * k[i, j, 2]
                d0 = i0 * inv_sigma[i, j, 0] - a * m[i, j, 0]
                d1 = i1 * inv_sigma[i, j, 1] - a * m[i, j, 1]
                d2 = i2 * inv_sigma[i, j, 2] - a * m[i, j, 2]
                alpha[t, i, j] = a
                cd[t, i, j] = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    return alpha, cd


@njit(cache=True)
def _foreground_kernel(
    frame: NDArray[np.uint8],
    k: NDArray[np.float32],
    inv_sigma: NDArray[np.float32],
    m: NDArray[np.float32],
    thr2: NDArray[np.float32],
    alpha_lo: float,
) -> NDArray[np.bool_]:
    """Fused per-pixel ``CD^ > tau_CD or alpha < alpha_lo`` (the reference is ``foreground_reference``):
    ``alpha = sum_c I_c k_c`` with ``k_c = (mu_c / sigma_c^2) / sum (mu / sigma)^2``,
    ``CD^2 = sum_c (I_c / sigma_c - alpha mu_c / sigma_c)^2`` against ``thr2 = (tau_CD b)^2``."""
    h, w = frame.shape[0], frame.shape[1]
    out = np.empty((h, w), np.bool_)
    for i in range(h):
        for j in range(w):
            i0 = np.float32(frame[i, j, 0])
            i1 = np.float32(frame[i, j, 1])
            i2 = np.float32(frame[i, j, 2])
            a = i0 * k[i, j, 0] + i1 * k[i, j, 1] + i2 * k[i, j, 2]
            d0 = i0 * inv_sigma[i, j, 0] - a * m[i, j, 0]
            d1 = i1 * inv_sigma[i, j, 1] - a * m[i, j, 1]
            d2 = i2 * inv_sigma[i, j, 2] - a * m[i, j, 2]
            out[i, j] = (d0 * d0 + d1 * d1 + d2 * d2 > thr2[i, j]) or (a < alpha_lo)
    return out


def _distortions(
    frames: NDArray[np.float32], model: HorprasertModel
) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """Brightness ``alpha`` and chromaticity ``CD`` of frames ``(..., H, W, 3)`` against the model."""
    alpha = np.einsum("...c,...c->...", frames, model.mu_over_var) * model.inv_denom
    diff = (frames - alpha[..., None] * model.mu) * model.inv_sigma
    cd = np.sqrt(np.einsum("...c,...c->...", diff, diff))
    return alpha, cd


@dataclass(frozen=True)
class HorprasertModel:
    """A trained background model; :meth:`classify` labels a frame, :meth:`foreground` masks it."""

    mu: NDArray[np.float32]
    inv_sigma: NDArray[np.float32]
    mu_over_var: NDArray[np.float32]
    inv_denom: NDArray[np.float32]
    inv_a: NDArray[np.float32]
    inv_b: NDArray[np.float32]
    tau_cd: float
    tau_a1: float
    tau_a2: float
    alpha_lo: float
    _kernel_args: tuple[NDArray[np.float32], ...] | None = field(
        default=None, repr=False, compare=False
    )

    @classmethod
    def train(
        cls,
        frames: ArrayLike,
        *,
        detection_rate: float = 0.9999,
        sigma_min: float = 1.0,
        alpha_lo: float = 0.5,
        floor: float = 1e-3,
        rng: np.random.Generator | None = None,
    ) -> HorprasertModel:
        """Fit ``<mu, sigma, a, b>`` and the thresholds on ``N >= 2`` frames ``(N, H, W, 3)`` of the empty scene."""
        f = np.asarray(frames, dtype=np.float32)
        if f.ndim != 4 or f.shape[-1] != 3 or f.shape[0] < 2:
            raise ShapeError(
                invalid("frames.shape", f.shape, "(N, H, W, 3) colour frames with N >= 2")
            )
        if not 0.5 < detection_rate < 1.0:
            raise ConfigError(invalid("detection_rate", detection_rate, "a fraction in (0.5, 1)"))
        mu = f.mean(0)
        sigma = np.maximum(f.std(0), np.float32(sigma_min))
        inv_sigma = (1.0 / sigma).astype(np.float32)
        mu_over_var = (mu * inv_sigma**2).astype(np.float32)
        denom = np.einsum("...c,...c->...", mu * inv_sigma, mu * inv_sigma)
        inv_denom = (1.0 / np.maximum(denom, 1e-6)).astype(np.float32)
        k = (mu_over_var * inv_denom[..., None]).astype(np.float32)
        alpha, cd = _alpha_cd_kernel(f, k, inv_sigma, (mu * inv_sigma).astype(np.float32))
        a = np.maximum(np.sqrt(np.mean((alpha - 1.0) ** 2, axis=0)), floor).astype(np.float32)
        b = np.maximum(np.sqrt(np.mean(cd**2, axis=0)), floor).astype(np.float32)
        a_hat = ((alpha - 1.0) / a).ravel()
        cd_hat = (cd / b).ravel()
        if a_hat.size > _MAX_THRESHOLD_SAMPLES:  # thresholds from a random subset: same quantiles
            g = rng if rng is not None else np.random.default_rng(0)
            keep = g.integers(0, a_hat.size, _MAX_THRESHOLD_SAMPLES)
            a_hat, cd_hat = a_hat[keep], cd_hat[keep]
        tail = 1.0 - detection_rate
        tau_cd = float(np.quantile(cd_hat, detection_rate))
        tau_a2, tau_a1 = (float(v) for v in np.quantile(a_hat, [tail / 2, 1 - tail / 2]))
        return cls(
            mu,
            inv_sigma,
            mu_over_var,
            inv_denom,
            (1.0 / a).astype(np.float32),
            (1.0 / b).astype(np.float32),
            tau_cd,
            tau_a1,
            tau_a2,
            float(alpha_lo),
        )

    @property
    def shape(self) -> tuple[int, int]:
        return (int(self.mu.shape[0]), int(self.mu.shape[1]))

    def _check(self, frame: ArrayLike) -> NDArray[np.float32]:
        f = np.asarray(frame, dtype=np.float32)
        if f.shape[-3:] != (*self.shape, 3):
            raise ShapeError(
                invalid("frame.shape", f.shape, f"(..., {self.shape[0]}, {self.shape[1]}, 3)")
            )
        return f

    def classify(self, frame: ArrayLike) -> NDArray[np.uint8]:
        """Per-pixel class ``(..., H, W)``: BACKGROUND 0, FOREGROUND 1, SHADOW 2, HIGHLIGHT 3."""
        f = self._check(frame)
        alpha, cd = _distortions(f, self)
        a_hat = (alpha - 1.0) * self.inv_a
        cd_hat = cd * self.inv_b
        out = np.full(alpha.shape, HIGHLIGHT, dtype=np.uint8)
        out[a_hat < 0] = SHADOW
        out[(a_hat > self.tau_a2) & (a_hat < self.tau_a1)] = BACKGROUND
        out[(cd_hat > self.tau_cd) | (alpha < self.alpha_lo)] = FOREGROUND
        return out

    def foreground_reference(self, frame: ArrayLike) -> NDArray[np.bool_]:
        """The foreground mask ``(..., H, W)`` (class F only), plain NumPy."""
        f = self._check(frame)
        alpha, cd = _distortions(f, self)
        return np.asarray((cd * self.inv_b > self.tau_cd) | (alpha < self.alpha_lo))

    def foreground(self, frame: ArrayLike) -> NDArray[np.bool_]:
        """The foreground mask ``(H, W)`` of one frame (class F only; shadows and highlights are
        background): a fused Numba kernel, equal to :meth:`foreground_reference`."""
        f = np.asarray(frame)
        if f.dtype != np.uint8 or f.shape != (*self.shape, 3):
            return self.foreground_reference(f)
        if self._kernel_args is None:
            k = (self.mu_over_var * self.inv_denom[..., None]).astype(np.float32)
            m = (self.mu * self.inv_sigma).astype(np.float32)
            thr2 = ((self.tau_cd / self.inv_b) ** 2).astype(np.float32)
            object.__setattr__(
                self, "_kernel_args", (k, np.ascontiguousarray(self.inv_sigma), m, thr2)
            )
        assert self._kernel_args is not None
        k, inv_s, m, thr2 = self._kernel_args
        return _foreground_kernel(np.ascontiguousarray(f), k, inv_s, m, thr2, float(self.alpha_lo))


__all__ = ["BACKGROUND", "FOREGROUND", "HIGHLIGHT", "SHADOW", "HorprasertModel"]
