"""Locating several harmonic sound sources from beamform and PSD features (Kushwaha 2010, Ch. IV).

Two steps (Fig. 28, Alg. 1):

1. **Source separation** — maximum-likelihood fundamentals from the compressed PSDs. At the ML
   harmonic energies (Eq. 43) the PSD likelihood no longer depends on the positions (Prop. 2), and
   ``ℓ'(Ω_f) = (1/K) Σ_k Σ_{ω_j ∉ ℍ(Ω_f)} P_k(ω_j)²`` (Eqs. 45–46) is minimised over Ω_f.
2. **Localisation** — MAP positions under the beamform likelihood
   ``ℓ_k(X) = Σ_α (B_k(α) - 𝔹_k(α))² / σ_B²`` with the generative multi-source beamform of Eq. 56:
   ``𝔹_k(α) = Σ_m λ_k^(m)² [N_mic R^(m)(0) + 2 Σ_{i<j} R^(m)(κ_ij^(m)(α))] + N_mic R_η(0)``, where
   ``R^(m)(τ) = Σ_h ψ_h cos(2π h f^(m) τ / f_s)`` is the source autocorrelation and, by Eq. 43, the
   per-sensor harmonic powers ``λ_k² ψ_h = P_k(h f^(m)) / M'²`` come from the separated PSD.

Both are solved by a Gibbs sampler whose univariate conditionals are drawn by slice sampling
(Alg. 1, N = 40 samples); the ML/MAP estimate is the best sample.

Where this departs from the printed equations (spec 003 §5, A-IV-*):

* ℓ' alone is minimised by any subharmonic (it can only fall when ℍ grows; A-IV-3). A penalty
  ``ε_H`` per claimed harmonic bin (``h f ≤ ω_max``) with no transmitted peak is added, and the
  fundamentals are kept in ``[f_lo, f_hi]``.
* Eqs. 50/52 sum over ordered pairs ``p ≠ q`` and then double them; Eq. 56's unordered pairs with
  factor 2 is the algebraically right form (A-IV-5) and is used.
* The pair lag ``κ`` uses the beamformer's own integer delay table and the exact path lengths from
  the hypothesised position to each microphone (the paper's ``d cos(α - β) f_s / C`` is the
  far-field, unrounded version of the same quantity).
* Beamform and PSD come from different pipelines, so each sensor's model is fitted with a gain
  ``a_k ≥ 0`` and an offset ``c_k`` (which also absorbs ``N_mic R_η(0)``) by least squares (A-IV-6).
* Eq. 38 assumes ``E[cos(Φ_i - Φ_j)] = 1`` for sources sharing a harmonic (hence ``M'²`` in Eq. 43);
  for independent phases the powers add (``M'``). ``shared_power="incoherent"`` selects that.
* Beyond the paper: the harmonic tolerance is one 1 Hz bin (a line between two bins lights both);
  the ML fundamentals are refined below a bin from the two bins a line lights; by default the
  per-node powers are fitted as ``λ_k² ψ_h`` over all nodes (:func:`factorised_powers`: Eq. 43 per
  node treats a harmonic a node did not send as silent); and each Gibbs sweep ends with Metropolis
  swaps of two sources' positions, which coordinate-wise moves cannot make.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from ..core.errors import ConfigError, ShapeError, invalid
from ..perception.audio_beamforming import MicrophoneArray, beam_delays
from ..perception.harmonic_features import CompressedPsd, NodeFeatures, harmonicity
from .slice_sampling import slice_sample

Array = np.ndarray


# ----------------------------------------------------------------------------- step 1: frequencies


@dataclass(frozen=True)
class FrequencyModel:
    """Settings of the PSD likelihood: band ``[f_lo, f_hi]`` for fundamentals, ``f_max`` (ω_max,
    Table 10: 1 kHz), the harmonic-set tolerance ``tol`` and the empty-harmonic penalty as a
    fraction of each sensor's median transmitted ``P²`` (0.3 chosen on simulated 1–4 source scenes:
    lower lets subharmonics win, higher lets a source split into two).

    ``tol`` is one bin (1 Hz), not half: seen through a 1 s rectangular window a line between two
    bins lights both (the main lobe is ±1 bin wide), and with half a bin the weaker of the two is
    left unexplained — which a wrong, lower fundamental can then "explain" by chance."""

    f_lo: float = 20.0
    f_hi: float = 300.0
    f_max: float = 1000.0
    tol: float = 1.0
    empty_penalty: float = 0.3

    def __post_init__(self) -> None:
        if not 0 < self.f_lo < self.f_hi:
            raise ConfigError(invalid("f_lo/f_hi", (self.f_lo, self.f_hi), "0 < f_lo < f_hi"))
        if not self.tol > 0:
            raise ConfigError(invalid("tol", self.tol, "a tolerance > 0 Hz"))


def _peaks(psds: Sequence[CompressedPsd]) -> tuple[Array, Array]:
    """Pad the K compressed PSDs into ``(K, J)`` frequency and power arrays (padding: power 0)."""
    if len(psds) == 0:
        raise ShapeError(invalid("psds", psds, "at least one sensor's PSD"))
    j = max(p.freqs.size for p in psds)
    f = np.full((len(psds), max(j, 1)), -1e9)
    p = np.zeros((len(psds), max(j, 1)))
    for k, s in enumerate(psds):
        f[k, : s.freqs.size] = s.freqs
        p[k, : s.freqs.size] = s.powers
    return f, p


def _hits(freqs: Array, f0s: Array, model: FrequencyModel) -> tuple[Array, Array]:
    """For candidates ``f0s (..., M)`` and peaks ``freqs (K, J)``: which peak is harmonic ``h`` of
    which source, ``hit (..., K, J, M)``, and the harmonic numbers ``h (..., K, J, M)``."""
    f = freqs[..., None]  # (K, J, 1)
    f0 = f0s[..., None, None, :]  # (..., 1, 1, M)
    h = np.maximum(np.round(f / f0), 1.0)
    hit = (np.abs(f - h * f0) < model.tol) & (h * f0 <= model.f_max + model.tol)
    return hit, h


class _PsdTerms:
    """The K compressed PSDs as arrays, and each candidate fundamental's own terms of ℓ': which
    peaks it claims ``(..., K, J)`` and how many of its harmonic bins are empty ``(..., K)``.
    ℓ' of several sources combines these (union of claims, sum of empties), so a Gibbs or grid
    step that moves one source recomputes only that source's terms."""

    def __init__(self, psds: Sequence[CompressedPsd], model: FrequencyModel) -> None:
        self.model = model
        self.freqs, self.powers = _peaks(psds)
        self.p2 = self.powers**2
        masked = np.where(self.p2 > 0, self.p2, np.nan)
        has = np.any(self.p2 > 0, axis=-1)
        typical = np.nanmedian(np.where(has[:, None], masked, 0.0), axis=-1)  # (K,)
        positive = np.where(has, typical, 0.0)
        self.eps = model.empty_penalty * np.where(np.isfinite(positive), positive, 0.0)  # (K,)

    def source(self, f0: ArrayLike) -> tuple[Array, Array]:
        f0a = np.asarray(f0, float)
        hit, h = _hits(self.freqs, f0a[..., None], self.model)
        hit, h = hit[..., 0], h[..., 0]  # (..., K, J)
        # distinct harmonics matched (a line between two bins may light both; peaks are sorted)
        repeat = np.zeros_like(hit)
        repeat[..., 1:] = hit[..., :-1] & (h[..., :-1] == h[..., 1:])
        matched = (hit & ~repeat).sum(axis=-1)  # (..., K)
        n_claimed = np.floor((self.model.f_max + self.model.tol) / f0a)[..., None]
        return hit, np.maximum(n_claimed - matched, 0.0)

    def combine(self, claims: Array, empty: Array) -> Array:
        """ℓ' from the union of claims ``(..., K, J)`` and the summed empties ``(..., K)``."""
        residual = np.sum(np.where(claims, 0.0, self.p2), axis=-1)
        return np.asarray(np.mean(residual + self.eps * empty, axis=-1))


def psd_neg_log_likelihood(
    f0s: ArrayLike, psds: Sequence[CompressedPsd], model: FrequencyModel = FrequencyModel()
) -> Array:
    """``ℓ'(Ω_f) = (1/K) Σ_k [Σ_{ω_j ∉ ℍ} P_k(ω_j)² + ε_k · #empty harmonic bins]`` for candidate
    fundamentals ``f0s (..., M)`` (Kushwaha 2010, Eqs. 45–46, with the A-IV-3 penalty)."""
    terms = _PsdTerms(psds, model)
    hit, empty = terms.source(np.moveaxis(np.atleast_1d(np.asarray(f0s, float)), -1, 0))
    return terms.combine(np.asarray(hit.any(axis=0)), empty.sum(axis=0))


def harmonic_powers(
    f0s: ArrayLike,
    psds: Sequence[CompressedPsd],
    model: FrequencyModel = FrequencyModel(),
    shared_power: Literal["paper", "incoherent"] = "paper",
) -> tuple[Array, Array]:
    """Per-sensor ML harmonic powers ``λ_k² ψ_h = P_k(h f^(m)) / M'²`` (Kushwaha 2010, Eq. 43; ``M'``
    with ``shared_power="incoherent"``) as ``(K, M, J)`` powers at frequencies ``(K, M, J)``
    ``h·f^(m)`` (0 where peak ``j`` is not a harmonic of ``m``)."""
    f0 = np.asarray(f0s, float).reshape(-1)
    freqs, powers = _peaks(psds)
    hit, h = _hits(freqs, f0, model)  # (K, J, M)
    shared = np.maximum(hit.sum(axis=-1, keepdims=True), 1)  # M' per peak
    div = shared**2 if shared_power == "paper" else shared
    amp = np.where(hit, powers[..., None] / div, 0.0)
    return np.moveaxis(amp, -1, 1), np.moveaxis(np.where(hit, h * f0, 0.0), -1, 1)


def factorised_powers(
    f0s: ArrayLike, powers: Array, freqs: Array, iterations: int = 20
) -> tuple[Array, Array]:
    """Harmonic powers ``λ_k² ψ_h`` on a harmonic-number grid ``(K, M, H)`` at ``h·f^(m)``, fitted to
    the per-sensor Eq. 43 powers ``(K, M, J)`` (from :func:`harmonic_powers`) as the product the
    graphical model implies (Fig. 28: ``ψ^(m)`` belongs to the source, ``λ_k^(m)`` to the path).

    Beyond the paper: Eq. 43 reads ``λ_k² ψ_h`` at each node on its own, so a harmonic that one node
    did not send counts as silent there. Fitting ``λ_k²`` and ``ψ_h`` to the harmonics every node did
    send (alternating least squares over the observed entries) fills those in."""
    f0 = np.asarray(f0s, float).reshape(-1)
    k_n, m_n, _ = powers.shape
    h_of = np.where(powers > 0, np.round(freqs / f0[None, :, None]), 0).astype(int)
    h_max = max(int(h_of.max(initial=0)), 1)
    obs = np.zeros((k_n, m_n, h_max))  # two bins of one line (or repeats) add up
    seen = np.zeros((k_n, m_n, h_max), bool)
    k_i, m_i, j_i = np.nonzero(powers > 0)
    np.add.at(obs, (k_i, m_i, h_of[k_i, m_i, j_i] - 1), powers[k_i, m_i, j_i])
    seen[k_i, m_i, h_of[k_i, m_i, j_i] - 1] = True
    lam = np.ones((k_n, m_n))
    psi = np.where(seen.any(0), obs.max(0), 0.0)  # (M, H)
    for _ in range(iterations):
        num = (obs * psi[None] * seen).sum(-1)
        den = (psi[None] ** 2 * seen).sum(-1)
        lam = np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)  # (K, M)
        num = (obs * lam[..., None] * seen).sum(0)
        den = (lam[..., None] ** 2 * seen).sum(0)
        psi = np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)  # (M, H)
    full = np.where(seen, obs, lam[..., None] * psi[None])  # keep what was observed
    grid = np.broadcast_to(f0[None, :, None] * np.arange(1, h_max + 1), full.shape)
    return np.maximum(full, 0.0), np.array(grid)


@dataclass(frozen=True)
class FrequencyEstimate:
    """ML fundamentals ``f0 (M,)``, their ``ℓ'`` and all Gibbs samples ``(N, M)``."""

    f0: Array
    neg_log_likelihood: float
    samples: Array
    evaluations: int


def initial_frequencies(
    psds: Sequence[CompressedPsd],
    n_sources: int,
    model: FrequencyModel = FrequencyModel(),
    step: float = 0.05,
    sweeps: int = 1,
) -> Array:
    """Greedy grid search (spec 003 §2.7 [C], Alg. 1 line 1): add one fundamental at a time at the
    grid point of least ``ℓ'`` given those already placed, then re-place each in turn."""
    terms = _PsdTerms(psds, model)
    grid = np.arange(model.f_lo, model.f_hi + step / 2, step)
    g_hit, g_empty = terms.source(grid)  # (G, K, J), (G, K)
    chosen: list[int] = []
    for sweep in range(sweeps + 1):
        for m in range(n_sources):
            others = [g for i, g in enumerate(chosen) if i != m]
            claims = g_hit | np.any(g_hit[others], axis=0) if others else g_hit
            empty = g_empty + g_empty[others].sum(axis=0) if others else g_empty
            pick = int(np.argmin(terms.combine(claims, empty)))
            if sweep == 0:
                chosen.append(pick)
            else:
                chosen[m] = pick
    return np.asarray(grid[chosen], float)


def refine_frequencies(
    f0s: ArrayLike, psds: Sequence[CompressedPsd], model: FrequencyModel = FrequencyModel()
) -> Array:
    """Sub-bin fundamentals (beyond the paper): a line at ``(b + δ)`` bins seen through a rectangular
    window gives ``|Y_{b+1}|/|Y_b| = δ/(1 - δ)``, so every harmonic that lights two adjacent
    transmitted bins, and is claimed by one source only, gives a line frequency; ``f0`` is their
    least-squares fit ``Σ h f_h / Σ h²``. Kept only where it does not raise ``ℓ'``."""
    f0 = np.asarray(f0s, float).reshape(-1).copy()
    terms = _PsdTerms(psds, model)
    hit, h = _hits(terms.freqs, f0, model)  # (K, J, M)
    alone = hit & (hit.sum(-1, keepdims=True) == 1)
    res = np.array([p.resolution for p in psds])[:, None]
    f, pw = terms.freqs, terms.powers
    adjacent = np.isclose(f[:, 1:] - f[:, :-1], res)  # (K, J-1)
    base = f0.copy()
    for m in range(f0.size):
        pair = alone[:, :-1, m] & alone[:, 1:, m] & adjacent & (h[:, :-1, m] == h[:, 1:, m])
        if not pair.any():
            continue
        a, b = np.sqrt(pw[:, :-1][pair]), np.sqrt(pw[:, 1:][pair])
        line = f[:, :-1][pair] + (b / (a + b)) * np.broadcast_to(res, pair.shape)[pair]
        hh = h[:, :-1, m][pair]
        trial = f0.copy()
        trial[m] = float(np.sum(hh * line) / np.sum(hh * hh))
        if model.f_lo <= trial[m] <= model.f_hi and float(
            psd_neg_log_likelihood(trial, psds, model)
        ) <= float(psd_neg_log_likelihood(base, psds, model)):
            f0 = trial
    return f0


def estimate_frequencies(
    psds: Sequence[CompressedPsd],
    n_sources: int,
    rng: np.random.Generator,
    *,
    model: FrequencyModel = FrequencyModel(),
    n_samples: int = 40,
    width: float = 0.5,
    init: ArrayLike | None = None,
    refine: bool = True,
) -> FrequencyEstimate:
    """Alg. 1 lines 3–8: Gibbs sampling of ``p(Ω_f | P) ∝ exp(-ℓ'(Ω_f)/σ_P²)`` with slice-sampled
    univariate conditionals; the ML estimate is the sample of least ``ℓ'``. ``σ_P² = 0.01 · mean_k
    Σ_j P_k²`` (spec 003 [C]). Initialised by :func:`initial_frequencies` unless ``init`` is given;
    ``refine`` then applies :func:`refine_frequencies`."""
    if n_sources < 1:
        raise ConfigError(invalid("n_sources", n_sources, "an integer >= 1"))
    f0 = (
        initial_frequencies(psds, n_sources, model)
        if init is None
        else np.asarray(init, float).reshape(n_sources).copy()
    )
    f0 = np.clip(f0, model.f_lo, model.f_hi)
    terms = _PsdTerms(psds, model)
    sigma2 = max(0.01 * float(np.mean(np.sum(terms.p2, axis=-1))), 1e-300)
    hits, empties = terms.source(f0)  # (K, J), (K,) for each source: (M, K, J), (M, K)
    hits, empties = hits.copy(), empties.copy()
    cur = float(terms.combine(np.asarray(hits.any(0)), empties.sum(0)))
    best, best_f = cur, f0.copy()
    samples = np.empty((n_samples, n_sources))
    evals = 1
    for k in range(n_samples):
        for m in range(n_sources):
            rest_claims = np.asarray(np.delete(hits, m, axis=0).any(0))
            rest_empty = np.delete(empties, m, axis=0).sum(0)

            def logp(v: float, rc: Array = rest_claims, re: Array = rest_empty) -> float:
                hv, ev = terms.source(v)
                return -float(terms.combine(rc | hv, re + ev)) / sigma2

            d = slice_sample(
                logp,
                float(f0[m]),
                rng,
                width=width,
                lower=model.f_lo,
                upper=model.f_hi,
                logp0=-cur / sigma2,
            )
            evals += d.evaluations
            f0[m] = d.x
            hits[m], empties[m] = terms.source(d.x)
            cur = -d.logp * sigma2
        samples[k] = f0
        if cur < best:
            best, best_f = cur, f0.copy()
    if refine:
        best_f = refine_frequencies(best_f, psds, model)
    return FrequencyEstimate(best_f, best, samples, evals)


# ----------------------------------------------------------------------------- step 2: positions


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


@dataclass(frozen=True)
class LocalisationResult:
    """Estimated fundamentals ``f0 (M,)`` and positions ``(M, 2)``; ``supported[m]`` is False for a
    source whose harmonics carry less than ``min_share`` of the harmonic PSD power (more sources
    requested than present, or no harmonic peaks at all: its position is then only the prior's);
    ``harmonicity`` is Eq. 59 on the transmitted peaks (a confidence indicator, Ch. IV)."""

    f0: Array
    positions: Array
    supported: Array
    harmonicity: float
    psd_neg_log_likelihood: float
    neg_log_posterior: float
    position_samples: Array
    evaluations: int


@dataclass(frozen=True)
class BeamformModel:
    """Settings of the localisation step: the ``field_box`` (uniform prior), relative beamform
    noise ``rel_sigma`` (``σ_B,k = rel_sigma · std_α B_k``), the initial grid step (m), Gibbs
    samples, slice width (m), the shared-harmonic power rule, and whether the per-node harmonic
    powers are read as Eq. 43 prints them (``"per-node"``) or fitted as ``λ_k² ψ_h``
    (``"factorised"``, :func:`factorised_powers`)."""

    field_box: tuple[float, float, float, float] = (0.0, 10.0, 0.0, 5.0)
    rel_sigma: float = 0.05
    grid_step: float = 0.5
    n_samples: int = 40
    width: float = 1.0
    shared_power: Literal["paper", "incoherent"] = "paper"
    powers: Literal["per-node", "factorised"] = "factorised"
    min_share: float = 0.01
    prior_sigma: float = 1.0  # m: N(X | X_{t-1}, prior_sigma² I) when a previous estimate is given


class _Posterior:
    """``-log p(X | B)`` with each source's beamform share cached (a Gibbs step moves one source)."""

    def __init__(
        self,
        network: AcousticNetwork,
        beamforms: Array,
        powers: Array,
        freqs: Array,
        model: BeamformModel,
        previous: Array | None,
    ) -> None:
        self.net, self.B, self.A, self.F, self.cfg, self.prev = (
            network,
            beamforms,
            powers,
            freqs,
            model,
            previous,
        )
        spread = beamforms.std(axis=-1)
        floor = 1e-12 * max(float(np.abs(beamforms).max()), 1e-300)
        self.sigma2 = (model.rel_sigma * np.maximum(spread, floor)) ** 2  # (K,)
        self.om = beamforms - beamforms.mean(-1, keepdims=True)  # centred observations
        self.ss_o = (self.om * self.om).sum(-1)
        self.evaluations = 0
        self.models = [
            SourceBeamform(network, powers[:, m], freqs[:, m]) for m in range(powers.shape[1])
        ]

    def share(self, m: int, x: ArrayLike) -> Array:
        self.evaluations += int(np.prod(np.shape(x)[:-1], dtype=int))
        return self.models[m](x)

    def energy(self, total: Array, x_all: Array) -> Array:
        """``Σ_k ℓ_k`` plus the prior, for summed shares ``total (..., K, Q)`` and positions
        ``x_all (..., M, 2)``."""
        # fit_gain_offset's residual, from centred sums: rss = S_oo - 2a S_bo + a² S_bb
        bm = total - total.mean(-1, keepdims=True)
        sbb = np.einsum("...q,...q->...", bm, bm)
        sbo = np.einsum("...q,...q->...", bm, self.om)
        a = np.maximum(sbo / np.maximum(sbb, 1e-300), 0.0)
        rss = np.maximum(self.ss_o - 2 * a * sbo + a * a * sbb, 0.0)
        u = (rss / self.sigma2).sum(-1)
        x0, x1, y0, y1 = self.cfg.field_box
        inside = np.all(
            (x_all[..., 0] >= x0)
            & (x_all[..., 0] <= x1)
            & (x_all[..., 1] >= y0)
            & (x_all[..., 1] <= y1),
            axis=-1,
        )
        if self.prev is not None:
            u = u + 0.5 * ((x_all - self.prev) ** 2).sum((-1, -2)) / self.cfg.prior_sigma**2
        return np.asarray(np.where(inside, u, np.inf))


def localise(
    network: AcousticNetwork,
    features: Sequence[NodeFeatures],
    n_sources: int,
    rng: np.random.Generator,
    *,
    frequency_model: FrequencyModel = FrequencyModel(),
    model: BeamformModel = BeamformModel(),
    f0_init: ArrayLike | None = None,
    previous: ArrayLike | None = None,
) -> LocalisationResult:
    """Algorithm 1 for one time step: ML fundamentals from the PSDs, then the MAP positions from the
    beamforms by Gibbs sampling with slice-sampled coordinates (``model.n_samples`` sweeps), started
    from a greedy grid search. ``previous (M, 2)`` is ``X_{t-1}`` (adds its Gaussian prior)."""
    if len(features) != network.n_sensors:
        raise ShapeError(invalid("len(features)", len(features), f"{network.n_sensors} sensors"))
    if n_sources < 1:
        raise ConfigError(invalid("n_sources", n_sources, "an integer >= 1"))
    psds = [f.psd for f in features]
    B = np.stack([np.asarray(f.beamform, float) for f in features])
    if B.shape[1] != network.n_beams or not np.all(np.isfinite(B)):
        raise ShapeError(invalid("beamform", B.shape, f"(K, {network.n_beams}) finite energies"))
    freq = estimate_frequencies(
        psds, n_sources, rng, model=frequency_model, n_samples=model.n_samples, init=f0_init
    )
    powers, freqs = harmonic_powers(freq.f0, psds, frequency_model, model.shared_power)
    if model.powers == "factorised":
        powers, freqs = factorised_powers(freq.f0, powers, freqs)
    share = powers.sum(axis=(0, 2))
    total_power = float(sum(float(p.powers.sum()) for p in psds))
    supported = share > model.min_share * max(float(share.sum()), 1e-300)
    h = (
        float(
            np.mean(
                [harmonicity(p.freqs, p.powers, freq.f0, f_max=frequency_model.f_max) for p in psds]
            )
        )
        if total_power > 0
        else 0.0
    )
    prev = None if previous is None else np.asarray(previous, float).reshape(n_sources, 2)
    post = _Posterior(network, B, powers, freqs, model, prev)

    # initial positions: greedy grid search, strongest source first, then one ICM sweep
    x0, x1, y0, y1 = model.field_box
    gx = np.arange(x0, x1 + 1e-9, model.grid_step)
    gy = np.arange(y0, y1 + 1e-9, model.grid_step)
    grid = np.stack(np.meshgrid(gx, gy, indexing="ij"), -1).reshape(-1, 2)
    X = np.tile([(x0 + x1) / 2, (y0 + y1) / 2], (n_sources, 1)) if prev is None else prev.copy()
    shares = np.zeros((n_sources, network.n_sensors, network.n_beams))
    order = np.argsort(-share)
    placed: list[int] = []
    for sweep in range(2):
        for m in order:
            if sweep == 0:
                placed.append(int(m))
            others = shares[[i for i in placed if i != m]].sum(0)
            cand = post.share(int(m), grid)  # (G, K, Q)
            xs = np.broadcast_to(X, (grid.shape[0], n_sources, 2)).copy()
            xs[:, m] = grid
            u = post.energy(others + cand, xs)
            g = int(np.argmin(u))
            X[m], shares[m] = grid[g], cand[g]
    cur = float(post.energy(shares.sum(0), X))
    best, best_X = cur, X.copy()
    samples = np.empty((model.n_samples, n_sources, 2))
    bounds = ((x0, x1), (y0, y1))
    for k in range(model.n_samples):
        for m in range(n_sources):
            for axis in (0, 1):
                rest = shares.sum(0) - shares[m]

                def logp(
                    v: float, m: int = m, axis: int = axis, rest: Array = rest, X: Array = X
                ) -> float:
                    trial = X.copy()
                    trial[m, axis] = v
                    return -float(post.energy(rest + post.share(m, trial[m]), trial))

                d = slice_sample(
                    logp,
                    float(X[m, axis]),
                    rng,
                    width=model.width,
                    lower=bounds[axis][0],
                    upper=bounds[axis][1],
                    logp0=-cur,
                )
                if d.x != X[m, axis]:
                    X[m, axis] = d.x
                    shares[m] = post.share(m, X[m])
                cur = float(-d.logp)
        # a Metropolis swap of two sources' positions (symmetric proposal): the coordinate-wise
        # Gibbs moves cannot exchange two sources whose bearings are close (beyond Alg. 1)
        for m, n in itertools.combinations(range(n_sources), 2):
            trial = X.copy()
            trial[[m, n]] = X[[n, m]]
            t_shares = shares.copy()
            t_shares[m], t_shares[n] = post.share(m, trial[m]), post.share(n, trial[n])
            u_swap = float(post.energy(t_shares.sum(0), trial))
            if u_swap <= cur or rng.random() < math.exp(cur - u_swap):
                X, shares = trial, t_shares
                cur = u_swap
        samples[k] = X
        if cur < best:
            best, best_X = cur, X.copy()
    return LocalisationResult(
        freq.f0,
        best_X,
        supported,
        h,
        freq.neg_log_likelihood,
        best,
        samples,
        freq.evaluations + post.evaluations,
    )


def match_error(estimated: ArrayLike, truth: ArrayLike) -> tuple[float, Array]:
    """Kushwaha 2010's error ``E = (1/M) Σ_m ‖x^(m) - x̃^(m)‖`` after matching estimates to truth by
    the minimum-cost assignment (the paper calls it RMS; it is the mean Euclidean error, A-IV-10).
    Returns ``(E, perm)`` with ``estimated[perm[i]]`` matched to ``truth[i]``."""
    from scipy.optimize import linear_sum_assignment

    e = np.asarray(estimated, float).reshape(-1, 2)
    t = np.asarray(truth, float).reshape(-1, 2)
    cost = np.hypot(*(t[:, None, :] - e[None, :, :]).transpose(2, 0, 1))
    rows, cols = linear_sum_assignment(cost)
    perm = np.empty(t.shape[0], np.int64)
    perm[rows] = cols
    return float(cost[rows, cols].mean()) if rows.size else math.nan, perm
