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
* ``powers="range-aware"`` (A-IV-7's alternative): the harmonic energies are a source-level
  spectrum decaying as ``1/r²`` from the hypothesised position, ``λ_k^(m)² ψ_h = L_m ψ̂_h^(m) / r_km²``,
  with ``ψ̂^(m)`` the shape of the factorised spectrum and ``L_m`` the least-squares level of the
  PSD powers given the ranges; the model then reads range as well as bearing from the levels.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from ...core import ConfigError, ShapeError, invalid, slice_sample
from ..harmonic_features import CompressedPsd, NodeFeatures, harmonicity
from .harmonic_beamform import AcousticNetwork, SourceBeamform
from .harmonic_frequencies import (
    FrequencyModel,
    estimate_frequencies,
    factorised_powers,
    harmonic_powers,
)

Array = np.ndarray
DEFAULT_FREQUENCY_MODEL = FrequencyModel()


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
    powers are read as Eq. 43 prints them (``"per-node"``), fitted as ``λ_k² ψ_h``
    (``"factorised"``, :func:`factorised_powers`) or tied to each source's range
    (``"range-aware"``: ``L_m ψ̂_h / r_km²``, A-IV-7; ranges floored at ``min_range`` m)."""

    field_box: tuple[float, float, float, float] = (0.0, 10.0, 0.0, 5.0)
    rel_sigma: float = 0.05
    grid_step: float = 0.5
    n_samples: int = 40
    width: float = 1.0
    shared_power: Literal["paper", "incoherent"] = "paper"
    powers: Literal["per-node", "factorised", "range-aware"] = "factorised"
    min_range: float = 0.1
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
        self.levels = powers.sum(-1)  # (K, M): each source's harmonic power at each node
        if model.powers == "range-aware":  # one spectrum shape per source, the same at every node
            shape = powers.sum(0) / np.maximum(powers.sum(axis=(0, 2)), 1e-300)[:, None]  # (M, H)
            powers = np.broadcast_to(shape, powers.shape)
        self.models = [
            SourceBeamform(network, powers[:, m], freqs[:, m]) for m in range(powers.shape[1])
        ]

    def share(self, m: int, x: ArrayLike) -> Array:
        self.evaluations += int(np.prod(np.shape(x)[:-1], dtype=int))
        out = self.models[m](x)
        if self.cfg.powers != "range-aware":
            return out
        xa = np.asarray(x, float)[..., None, :]
        r = np.maximum(np.sqrt(((xa - self.net.positions) ** 2).sum(-1)), self.cfg.min_range)
        g = r**-2  # (..., K): 1/r² decay from the hypothesised position
        level = (g * self.levels[:, m]).sum(-1) / (g * g).sum(-1)  # least-squares L_m
        return np.asarray(out * (level[..., None] * g)[..., None])

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
    frequency_model: FrequencyModel = DEFAULT_FREQUENCY_MODEL,
    model: BeamformModel = BeamformModel(),
    f0_init: ArrayLike | None = None,
    previous: ArrayLike | None = None,
    start: ArrayLike | None = None,
) -> LocalisationResult:
    """Algorithm 1 for one time step: ML fundamentals from the PSDs, then the MAP positions from the
    beamforms by Gibbs sampling with slice-sampled coordinates (``model.n_samples`` sweeps), started
    from a greedy grid search, or from ``start (M, 2)`` (e.g. another model's estimate) where that
    has the lower ``-log p``. ``previous (M, 2)`` is ``X_{t-1}`` (adds its Gaussian prior)."""
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
    if model.powers in ("factorised", "range-aware"):
        powers, freqs = factorised_powers(freq.f0, powers, freqs)
    share = powers.sum(axis=(0, 2))
    supported = share > model.min_share * max(float(share.sum()), 1e-300)
    prev = None if previous is None else np.asarray(previous, float).reshape(n_sources, 2)
    post = _Posterior(network, B, powers, freqs, model, prev)
    X, shares = _initial_positions(post, share, prev)
    if start is not None:
        X1 = np.asarray(start, float).reshape(n_sources, 2)
        shares1 = np.stack([post.share(m, X1[m]) for m in range(n_sources)])
        if post.energy(shares1.sum(0), X1) < post.energy(shares.sum(0), X):
            X, shares = X1, shares1
    best_X, best, samples = _gibbs_positions(post, X, shares, rng)
    return LocalisationResult(
        freq.f0,
        best_X,
        supported,
        _mean_harmonicity(psds, freq.f0, frequency_model.f_max),
        freq.neg_log_likelihood,
        best,
        samples,
        freq.evaluations + post.evaluations,
    )


def _mean_harmonicity(psds: Sequence[CompressedPsd], f0: Array, f_max: float) -> float:
    """Eq. 59 averaged over the nodes (0 when no node transmitted any power)."""
    if float(sum(float(p.powers.sum()) for p in psds)) <= 0:
        return 0.0
    return float(np.mean([harmonicity(p.freqs, p.powers, f0, f_max=f_max) for p in psds]))


def _initial_positions(post: _Posterior, share: Array, prev: Array | None) -> tuple[Array, Array]:
    """Greedy grid search, strongest source first, then one ICM sweep: positions ``(M, 2)`` and
    each source's beamform share ``(M, K, Q)`` (spec 003 §2.7 [C], Alg. 1 line 1)."""
    n_sources = share.size
    x0, x1, y0, y1 = post.cfg.field_box
    gx = np.arange(x0, x1 + 1e-9, post.cfg.grid_step)
    gy = np.arange(y0, y1 + 1e-9, post.cfg.grid_step)
    grid = np.stack(np.meshgrid(gx, gy, indexing="ij"), -1).reshape(-1, 2)
    X = np.tile([(x0 + x1) / 2, (y0 + y1) / 2], (n_sources, 1)) if prev is None else prev.copy()
    shares = np.zeros((n_sources, post.net.n_sensors, post.net.n_beams))
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
    return X, shares


def _gibbs_positions(
    post: _Posterior, X: Array, shares: Array, rng: np.random.Generator
) -> tuple[Array, float, Array]:
    """Alg. 1's position sweeps from ``X``: every coordinate slice-sampled in turn, then Metropolis
    swaps of source pairs. Returns the MAP sample, its ``-log p`` and all samples ``(N, M, 2)``."""
    n_sources = X.shape[0]
    cur = float(post.energy(shares.sum(0), X))
    best, best_X = cur, X.copy()
    samples = np.empty((post.cfg.n_samples, n_sources, 2))
    for k in range(post.cfg.n_samples):
        for m in range(n_sources):
            for axis in (0, 1):
                cur = _slice_coordinate(post, X, shares, m, axis, cur, rng)
        X, shares, cur = _swap_sources(post, X, shares, cur, rng)
        samples[k] = X
        if cur < best:
            best, best_X = cur, X.copy()
    return best_X, best, samples


def _slice_coordinate(
    post: _Posterior,
    X: Array,
    shares: Array,
    m: int,
    axis: int,
    cur: float,
    rng: np.random.Generator,
) -> float:
    """One Gibbs conditional: coordinate ``axis`` of source ``m`` slice-sampled within the field
    (Alg. 1); updates ``X`` and ``shares`` in place and returns the new ``-log p``."""
    x0, x1, y0, y1 = post.cfg.field_box
    lower, upper = ((x0, x1), (y0, y1))[axis]
    rest = shares.sum(0) - shares[m]

    def logp(v: float) -> float:
        trial = X.copy()
        trial[m, axis] = v
        return -float(post.energy(rest + post.share(m, trial[m]), trial))

    d = slice_sample(
        logp, float(X[m, axis]), rng, width=post.cfg.width, lower=lower, upper=upper, logp0=-cur
    )
    if d.x != X[m, axis]:
        X[m, axis] = d.x
        shares[m] = post.share(m, X[m])
    return float(-d.logp)


def _swap_sources(
    post: _Posterior, X: Array, shares: Array, cur: float, rng: np.random.Generator
) -> tuple[Array, Array, float]:
    """A Metropolis swap of every pair of sources' positions (symmetric proposal): the coordinate-wise
    Gibbs moves cannot exchange two sources whose bearings are close (beyond Alg. 1)."""
    for m, n in itertools.combinations(range(X.shape[0]), 2):
        trial = X.copy()
        trial[[m, n]] = X[[n, m]]
        t_shares = shares.copy()
        t_shares[m], t_shares[n] = post.share(m, trial[m]), post.share(n, trial[n])
        u_swap = float(post.energy(t_shares.sum(0), trial))
        if u_swap <= cur or rng.random() < math.exp(cur - u_swap):
            X, shares = trial, t_shares
            cur = u_swap
    return X, shares, cur


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
