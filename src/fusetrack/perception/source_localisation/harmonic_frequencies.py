"""Step 1 of Kushwaha 2010's harmonic-source localisation (Ch. IV, Alg. 1 lines 1-8): the
maximum-likelihood fundamentals of several harmonic sources from the nodes' compressed PSDs.

At the ML harmonic energies (Eq. 43) the PSD likelihood no longer depends on the positions
(Prop. 2), and ``ℓ'(Ω_f) = (1/K) Σ_k Σ_{ω_j ∉ ℍ(Ω_f)} P_k(ω_j)²`` (Eqs. 45-46) is minimised over
Ω_f by Gibbs sampling with slice-sampled conditionals; :mod:`.harmonic` says where this departs
from the printed equations.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from ...core import ConfigError, ShapeError, invalid, slice_sample
from ..harmonic_features import CompressedPsd

Array = np.ndarray


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
