"""Grid proposals: Galerkin projection (Zhai 2007, Ch. 4, Algorithm 5) and state-space
discretisation (Ch. 5, Algorithm 6) on the position subspace.

Both build a piecewise-constant density over the target's position, draw particle positions
from it, and complete each particle's other state entries (velocity, acceleration) from the
motion model given the position (the spec's "ancestor / noise-inversion trick", Sec. 2.5): an
ancestor ``j`` is drawn with probability ∝ ``N(p; [f(x_{t-1}^j)]_pos, Q_pp)`` and the rest from
the Gaussian conditional ``x_rest | p, j``. The particle weight is then the exact marginal one,
``w ∝ p(z | x) p̂(p) / q(p)`` with ``p̂(p) = (1/N) sum_j N(p; [f(x^j)]_pos, Q_pp)``: the grid only
has to be a good proposal, its discretisation error is corrected by the weight.

Galerkin prediction (Eqs. 64-77, with Eq. 74 corrected as the spec derives it): on a periodic
grid the projection of the Chapman-Kolmogorov integral onto the Fourier basis is a circular
convolution, ``c~_l = c_l Δ FFT[k]_l``, i.e. ``p~ = Δ (k ⊛ p)`` evaluated with FFTs
(:func:`galerkin_predict`); the Bayes update (Eqs. 70-73) is the pointwise product with the
likelihood. The grid is a moving window, mean ± ``span`` std of the predicted particles per axis.

Discretisation (Algorithm 6): cells of side Δ over the resampled particles, weights = particle
fractions, full-state centres = mean of each cell's particles; centres propagate noise-free,
predictive weights by Eq. 78 and the update by Eq. 79; cells below ``threshold`` are dropped.

These proposals work on one particle set at a time (``prev`` of shape ``(N, d)``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from ..core import ConfigError, ShapeError, invalid
from .mixture_density import gauss_logpdf, gaussian_mixture_ancestors
from .proposals import Array, LogLikelihood, Zs


def galerkin_predict(density: Array, kernel: Array, cell: float) -> Array:
    """Galerkin (Fourier) prediction ``Δ (k ⊛ p)`` on a periodic grid (Zhai 2007, Eqs. 74-75 corrected).

    ``density`` ``(n_1, ..., n_k)`` is the previous density at the grid points; ``kernel`` the
    shift-invariant transition density ``k(x_t - x_{t-1})`` sampled at offsets ``(i - n//2) Δ``
    (zero offset at index ``n//2``); ``cell`` the cell volume ``Δ_1 ... Δ_k``. Computed as
    ``c~_l = c_l Δ FFT[k]_l`` in the Fourier basis, which is the same circular convolution.
    """
    p = np.asarray(density, float)
    k = np.fft.ifftshift(np.asarray(kernel, float))
    return np.asarray(np.real(np.fft.ifftn(np.fft.fftn(p) * np.fft.fftn(k))) * cell)


def _split(motion: Any, d: int) -> tuple[list[int], list[int]]:
    pos = list(getattr(motion, "position_index", ()) or ())
    if not pos:
        raise ConfigError(invalid("motion.position_index", pos, "a non-empty tuple"))
    rest = [i for i in range(d) if i not in pos]
    return pos, rest


def complete_from_ancestors(
    p: Array,
    prev: Array,
    motion: Any,
    dt: float,
    rng: np.random.Generator,
    log_ancestor_weight: Array | None = None,
) -> tuple[Array, Array]:
    """Full states for positions ``p (N, k)`` and ``log p̂(p)`` (the predictive position density).

    Ancestor ``j ∝ a_j N(p; f(x^j)_pos, Q_pp)``, then ``x_rest ~ N(f(x^j)_rest + K (p - f(x^j)_pos), S)``;
    ``p̂(p) = (1/N) sum_j a_j N(p; f(x^j)_pos, Q_pp)`` with ``log a_j = log_ancestor_weight``
    (default 0; a regime's transition probability from the ancestor's regime in the MM filter).
    """
    n, d = prev.shape
    pos, rest = _split(motion, d)
    m = np.asarray(motion.mean(prev, dt))
    Q = np.asarray(motion.noise_cov(dt), float)
    Qpp = Q[np.ix_(pos, pos)]
    log_a = np.zeros(n) if log_ancestor_weight is None else log_ancestor_weight
    lse, anc = gaussian_mixture_ancestors(p, m[:, pos], Qpp, log_a, rng.random(len(p)))
    log_pred = lse - np.log(n)
    x = np.empty((len(p), d))
    x[:, pos] = p
    if rest:
        K = Q[np.ix_(rest, pos)] @ np.linalg.inv(Qpp)
        S = Q[np.ix_(rest, rest)] - K @ Q[np.ix_(pos, rest)]
        S = 0.5 * (S + S.T) + 1e-12 * np.eye(len(rest)) * max(float(np.trace(S)), 1e-300)
        mr = m[anc][:, rest] + (p - m[anc][:, pos]) @ K.T
        x[:, rest] = mr + rng.standard_normal((len(p), len(rest))) @ np.linalg.cholesky(S).T
    return x, np.asarray(log_pred)


def sample_cells(
    centres: Array, w: Array, delta: Array, n: int, rng: np.random.Generator
) -> tuple[Array, Array]:
    """``n`` positions: cell ``j ∝ w_j`` then uniform in its box of side ``delta`` around
    ``centres[j]``; returns them and ``log q(p)``, ``q(p) = sum_j w_j U_j(p)`` (boxes may overlap)."""
    cdf = np.cumsum(w)
    cdf[-1] = 1.0
    idx = np.minimum(np.searchsorted(cdf, rng.random(n), side="right"), len(w) - 1)
    p = centres[idx] + (rng.random((n, centres.shape[1])) - 0.5) * delta
    inside = np.all(np.abs(p[:, None, :] - centres[None, :, :]) <= delta / 2 + 1e-12, axis=-1)
    q = inside.astype(float) @ w / float(np.prod(delta))
    return p, np.log(q)


def _grid_states(centres: Array, fill: Array, pos: list[int]) -> Array:
    X = np.tile(fill, (len(centres), 1))
    X[:, pos] = centres
    return X


class _PositionGridProposal:
    """What both grid proposals share: one particle set, a weight log-ratio, no state."""

    returns_log_ratio = True

    def initialize(self, prior: Any, particles: Array, rng: np.random.Generator) -> None:
        if particles.ndim != 2:
            raise ShapeError(
                invalid("particles.shape", particles.shape, "(N, d): one set (no batch)")
            )
        return None

    def feedback(self, state: Any, particles: Array, estimate: Array, filt: Any) -> None:
        return None


@dataclass
class GalerkinProposal(_PositionGridProposal):
    """Galerkin-projection proposal on an ``n_grid``-per-axis position grid (Algorithm 5).

    ``prediction="galerkin"``: FFT circular convolution of the histogram of predicted particle
    means with the position-noise kernel (the Fourier-basis projection, ``n_grid`` basis
    functions per axis); ``"mixture"``: the exact Gaussian-mixture predictive density at the grid
    points (slower; a reference). ``weight="exact"`` corrects the grid with the exact marginal
    weight; ``"projected"`` uses the projected predictive density in the weight (the thesis's
    projection filter: weights are then nearly uniform and the grid's error is not corrected).
    """

    n_grid: int = 100
    span: float = 6.0
    prediction: Literal["galerkin", "mixture"] = "galerkin"
    weight: Literal["exact", "projected"] = "exact"
    border_mass: float = 1e-3

    def __post_init__(self) -> None:
        if isinstance(self.n_grid, bool) or int(self.n_grid) != self.n_grid or self.n_grid < 4:
            raise ConfigError(invalid("n_grid", self.n_grid, "an integer >= 4"))
        if self.prediction not in ("galerkin", "mixture"):
            raise ConfigError(invalid("prediction", self.prediction, "'galerkin' or 'mixture'"))

    def grid_density(
        self, prev: Array, zs: Zs, dt: float, filt: Any
    ) -> tuple[list[Array], Array, Array]:
        """Axes (cell centres per axis), the posterior cell probabilities (grid shape) and the
        predictive density at the centres."""
        motion = filt.motion
        n, d = prev.shape
        pos, _ = _split(motion, d)
        m = np.asarray(motion.mean(prev, dt))
        Qpp = np.asarray(motion.noise_cov(dt), float)[np.ix_(pos, pos)]
        mp = m[:, pos]
        centre = mp.mean(axis=0)
        half = self.span * np.sqrt(mp.var(axis=0) + np.diag(Qpp))
        g = self.n_grid
        axes = [c - h + (np.arange(g) + 0.5) * (2 * h / g) for c, h in zip(centre, half)]
        deltas = 2 * half / g
        cell = float(np.prod(deltas))
        mesh = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)  # (g,)*k + (k,)
        if self.prediction == "galerkin":
            edges = [np.concatenate([a - dl / 2, [a[-1] + dl / 2]]) for a, dl in zip(axes, deltas)]
            hist, _ = np.histogramdd(mp, bins=edges)
            dens = hist / (n * cell)
            offs = np.stack(
                np.meshgrid(*[(np.arange(g) - g // 2) * dl for dl in deltas], indexing="ij"),
                axis=-1,
            )
            kern = np.exp(gauss_logpdf(offs, Qpp))
            pred = np.clip(galerkin_predict(dens, kern, cell), 0.0, None)
        else:
            flat = mesh.reshape(-1, len(pos))
            lse, _ = gaussian_mixture_ancestors(flat, mp, Qpp, np.zeros(n), np.zeros(len(flat)))
            pred = np.exp(lse - np.log(n)).reshape(mesh.shape[:-1])
        states = _grid_states(mesh.reshape(-1, len(pos)), m.mean(axis=0), pos)
        ll = LogLikelihood(filt.sensors, zs)
        log_l = ll(states) if ll else np.zeros(len(states))
        log_post = np.log(np.maximum(pred.reshape(-1), 1e-300)) + log_l
        log_post = np.where(pred.reshape(-1) > 0, log_post, -np.inf)
        if not np.any(np.isfinite(log_post)):
            filt.stats.note_degenerate(
                "GalerkinProposal", "on every grid cell; the prediction was used"
            )
            log_post = np.log(np.maximum(pred.reshape(-1), 1e-300))
        prob = np.exp(log_post - np.max(log_post))
        prob /= prob.sum()
        prob = prob.reshape(pred.shape)
        border = np.ones(prob.shape, bool)
        border[tuple(slice(1, -1) for _ in prob.shape)] = False
        if prob[border].sum() > self.border_mass:
            filt.stats.grid_too_small += 1
        return axes, prob, pred

    def draw(
        self, state: Any, prev: Array, zs: Zs, dt: float, rng: np.random.Generator, filt: Any
    ) -> tuple[Array, Array, None]:
        axes, prob, pred = self.grid_density(prev, zs, dt, filt)
        n = prev.shape[0]
        deltas = np.array([a[1] - a[0] for a in axes])
        flat = prob.reshape(-1)
        cdf = np.cumsum(flat)
        cdf[-1] = 1.0
        idx = np.minimum(np.searchsorted(cdf, rng.random(n), side="right"), flat.size - 1)
        sub = np.stack(np.unravel_index(idx, prob.shape), axis=-1)
        centres = np.stack([a[s] for a, s in zip(axes, sub.T)], axis=-1)
        p = centres + (rng.random(centres.shape) - 0.5) * deltas
        log_q = np.log(flat[idx]) - np.sum(np.log(deltas))
        x, log_pred = complete_from_ancestors(p, prev, filt.motion, dt, rng)
        if self.weight == "projected":  # the projection filter's own predictive density
            log_pred = np.log(np.maximum(pred.reshape(-1)[idx], 1e-300))
        return x, log_pred - log_q, None


@dataclass
class DiscretisationProposal(_PositionGridProposal):
    """State-space discretisation proposal (Algorithm 6): weighted position cells.

    Cell side ``Δ = cell_scale * std`` of the predicted positions per axis (spec choice 0.5),
    cells lighter than ``threshold`` dropped, at most ``max_cells`` kept.
    """

    cell_scale: float = 0.5
    threshold: float = 1e-4
    max_cells: int = 400

    def cells(self, prev: Array, zs: Zs, dt: float, filt: Any) -> tuple[Array, Array, Array]:
        """Propagated cell centres ``(C, d)``, their posterior weights ``(C,)`` and side ``Δ (k,)``."""
        motion = filt.motion
        n, d = prev.shape
        pos, _ = _split(motion, d)
        m = np.asarray(motion.mean(prev, dt))
        Qpp = np.asarray(motion.noise_cov(dt), float)[np.ix_(pos, pos)]
        spread = np.sqrt(m[:, pos].var(axis=0) + np.diag(Qpp))
        delta = np.maximum(self.cell_scale * spread, 1e-9)
        key = np.floor((prev[:, pos] - prev[:, pos].min(axis=0)) / delta).astype(np.int64)
        _, cell_of, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        cell_of = cell_of.reshape(-1)
        c = len(counts)
        w_prev = counts / n
        centre_prev = np.zeros((c, d))
        np.add.at(centre_prev, cell_of, prev)
        centre_prev /= counts[:, None]
        centre = np.asarray(motion.mean(centre_prev, dt))  # noise-free propagation (step 2)
        cp = np.ascontiguousarray(centre[:, pos])  # p(x_t,j | x_t-1,i) = N(c_j; c_i, Q_pp)
        log_pred, _ = gaussian_mixture_ancestors(cp, cp, Qpp, np.log(w_prev), np.zeros(c))  # Eq. 78
        ll = LogLikelihood(filt.sensors, zs)
        log_w = log_pred + (ll(centre) if ll else 0.0)  # Eq. 79
        if not np.any(np.isfinite(log_w)):
            filt.stats.note_degenerate(
                "DiscretisationProposal", "in every cell; the prediction was used"
            )
            log_w = log_pred
        w = np.exp(log_w - np.max(log_w))
        w /= w.sum()
        keep = w >= self.threshold
        if keep.sum() > self.max_cells:
            keep = w >= np.sort(w)[-self.max_cells]
        w = np.where(keep, w, 0.0)
        w /= w.sum()
        return centre[keep], w[keep], delta

    def draw(
        self, state: Any, prev: Array, zs: Zs, dt: float, rng: np.random.Generator, filt: Any
    ) -> tuple[Array, Array, None]:
        centre, w, delta = self.cells(prev, zs, dt, filt)
        pos, _ = _split(filt.motion, prev.shape[1])
        p, log_q = sample_cells(centre[:, pos], w, delta, prev.shape[0], rng)
        x, log_pred = complete_from_ancestors(p, prev, filt.motion, dt, rng)
        return x, log_pred - log_q, None
