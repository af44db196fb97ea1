"""The generative multi-source beamform of Kushwaha 2010, Eq. 56, at an acoustic network.

``𝔹_k(α) = Σ_m λ_k^(m)² [N_mic R^(m)(0) + 2 Σ_{i<j} R^(m)(κ_ij^(m)(α))] + N_mic R_η(0)`` with the
source autocorrelation ``R^(m)(τ) = Σ_h ψ_h cos(2π h f^(m) τ / f_s)``; the pair lag ``κ`` uses the
beamformer's own integer delay table and the exact path lengths to each microphone.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ...core import ShapeError, invalid
from ..audio_beamforming import MicrophoneArray, beam_delays

Array = np.ndarray


@dataclass(frozen=True, eq=False)
class AcousticNetwork:
    """K array nodes at ``positions (K, 2)`` with ``headings (K,)``, each the same microphone
    ``array``, forming ``n_beams`` beams at sampling rate ``fs`` with speed of sound ``c``."""

    positions: Array
    headings: Array = field(default_factory=lambda: np.zeros(0))
    array: MicrophoneArray = field(default_factory=MicrophoneArray.rectangle)
    n_beams: int = 36
    fs: float = 100e3
    c: float = 350.0

    def __post_init__(self) -> None:
        pos = np.asarray(self.positions, float)
        if pos.ndim != 2 or pos.shape[1] != 2:
            raise ShapeError(invalid("positions.shape", pos.shape, "(K, 2)"))
        hd = np.asarray(self.headings, float)
        if hd.size == 0:
            hd = np.zeros(pos.shape[0])
        if hd.shape != (pos.shape[0],):
            raise ShapeError(invalid("headings.shape", hd.shape, f"({pos.shape[0]},)"))
        object.__setattr__(self, "positions", pos)
        object.__setattr__(self, "headings", hd)
        pairs = np.array(list(itertools.combinations(range(self.array.n_mics), 2)))
        d = beam_delays(self.array, self.n_beams, self.fs, self.c)  # (Q, P)
        object.__setattr__(self, "_pairs", pairs)
        object.__setattr__(self, "_lut_lag", (d[:, pairs[:, 1]] - d[:, pairs[:, 0]]).T)  # (I, Q)
        mics = np.stack(
            [self.array.world_positions(p, h) for p, h in zip(pos, hd, strict=True)]
        )  # (K, P, 2)
        object.__setattr__(self, "_mics", mics)

    @property
    def n_sensors(self) -> int:
        return int(self.positions.shape[0])

    def microphones(self) -> Array:
        """World positions of every microphone, ``(K, P, 2)``."""
        return np.asarray(self._mics)  # type: ignore[attr-defined]

    def pair_lags(self, x: ArrayLike) -> Array:
        """``κ_ij,k(α)`` in samples for a source at ``x (..., 2)``: LUT lag minus the true arrival
        difference (Prop. 5 proof: ``κ = t_pq(α) - τ_pq``), shape ``(..., K, I, Q)``."""
        xa = np.asarray(x, float)[..., None, None, :]
        tau = np.sqrt(((self.microphones() - xa) ** 2).sum(-1)) * (self.fs / self.c)  # (..., K, P)
        pairs = self._pairs  # type: ignore[attr-defined]
        dtau = tau[..., pairs[:, 1]] - tau[..., pairs[:, 0]]  # (..., K, I)
        return np.asarray(self._lut_lag[None] - dtau[..., None])  # type: ignore[attr-defined]


def source_beamform(network: AcousticNetwork, x: ArrayLike, powers: Array, freqs: Array) -> Array:
    """One source's share of Eq. 56 at every sensor, ``(..., K, Q)``:
    ``Σ_h A_kh [N_mic + 2 Σ_{i<j} cos(2π f_h κ_ij,k(α)/f_s)]`` for harmonic powers ``powers (K, H)``
    at ``freqs (K, H)`` (Prop. 3 per pair, Prop. 4 over pairs)."""
    lag = network.pair_lags(x)  # (..., K, I, Q)
    omega = 2 * np.pi * freqs / network.fs  # (K, H)
    keep = np.flatnonzero(np.any(powers > 0, axis=0))
    if keep.size == 0:
        return np.zeros((*np.shape(x)[:-1], network.n_sensors, network.n_beams))
    a = powers[:, keep]
    w = omega[:, keep]
    # Σ_i cos(w_kh κ_kiq) for every (k, h, q): einsum over pairs of a (…, K, H, I, Q) cosine
    c = np.cos(w[:, :, None, None] * lag[..., :, None, :, :])  # (..., K, H, I, Q)
    pair_sum = c.sum(axis=-2)  # (..., K, H, Q)
    n_mic = network.array.n_mics
    return np.asarray(np.einsum("kh,...khq->...kq", a, n_mic + 2 * pair_sum))


class SourceBeamform:
    """:func:`source_beamform` for one source with the position-free factors precomputed.

    ``cos(w κ) = cos(w t_ij(α)) cos(w Δτ_ij) + sin(w t_ij(α)) sin(w Δτ_ij)`` with ``κ = t_ij(α) - Δτ_ij``:
    the beam-table factors are fixed, so a position costs ``K·H·I`` sines and cosines and two
    matrix products instead of ``K·H·I·Q`` cosines (same numbers, tested)."""

    def __init__(self, network: AcousticNetwork, powers: Array, freqs: Array) -> None:
        self.net = network
        keep = np.flatnonzero(np.any(powers > 0, axis=0))
        a, w = powers[:, keep], 2 * np.pi * freqs[:, keep] / network.fs  # (K, H)
        lut = network._lut_lag  # type: ignore[attr-defined]  # (I, Q)
        phase = w[:, :, None, None] * lut[None, None]  # (K, H, I, Q)
        k, h, i, q = phase.shape
        self.w = w
        self.cos_t = (2 * a[:, :, None, None] * np.cos(phase)).reshape(k, h * i, q)
        self.sin_t = (2 * a[:, :, None, None] * np.sin(phase)).reshape(k, h * i, q)
        self.const = network.array.n_mics * a.sum(axis=1)  # (K,)

    def __call__(self, x: ArrayLike) -> Array:
        xa = np.asarray(x, float)
        lead = xa.shape[:-1]
        if self.w.shape[1] == 0:
            return np.zeros((*lead, self.net.n_sensors, self.net.n_beams))
        mics = self.net.microphones()
        pairs = self.net._pairs  # type: ignore[attr-defined]
        tau = np.sqrt(((mics - xa[..., None, None, :]) ** 2).sum(-1)) * (self.net.fs / self.net.c)
        dtau = tau[..., pairs[:, 1]] - tau[..., pairs[:, 0]]  # (..., K, I)
        ph = self.w[:, :, None] * dtau[..., :, None, :]  # (..., K, H, I)
        k = ph.shape[-3]
        c = np.cos(ph).reshape(*lead, k, 1, -1)
        s = np.sin(ph).reshape(*lead, k, 1, -1)
        out = (c @ self.cos_t)[..., 0, :] + (s @ self.sin_t)[..., 0, :]
        return np.asarray(out + self.const[:, None])


def fit_gain_offset(observed: Array, model: Array) -> tuple[Array, Array, Array]:
    """Least-squares ``B_k ≈ a_k b_k + c_k`` with ``a_k ≥ 0`` over beams, for ``model (..., K, Q)``
    against ``observed (K, Q)``; returns ``(a, c, residual sum of squares)`` each ``(..., K)``."""
    bm = model - model.mean(-1, keepdims=True)
    om = observed - observed.mean(-1, keepdims=True)
    sbb = (bm * bm).sum(-1)
    a = np.where(sbb > 1e-300, (bm * om).sum(-1) / np.where(sbb > 1e-300, sbb, 1.0), 0.0)
    a = np.maximum(a, 0.0)
    c = observed.mean(-1) - a * model.mean(-1)
    r = observed - (a[..., None] * model + c[..., None])
    return a, c, (r * r).sum(-1)
