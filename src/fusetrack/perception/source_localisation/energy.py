"""Energy-based localisation (EBL) of acoustic sources: the baseline of Kushwaha 2010, Ch. IV.

Energy model (Kushwaha 2010, Eq. 18; Sheng & Hu 2005, the dissertation's [84]):
``y_k = g_k Σ_m S_m / ‖x_k - x^(m)‖^α + ε_k`` with α = 2 for energy. The ML estimate with equal noise
at every sensor minimises ``‖y - D S‖²`` with ``D_km = g_k / d_km^α``; for given positions the
source energies ``S ≥ 0`` follow by least squares, so only the positions are searched: a grid over
the field, then coordinate-wise grid refinement (spec 003 §2.10 [C]).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ...core import ConfigError, ShapeError, invalid

Array = np.ndarray


def _residual(y: Array, D: Array) -> tuple[Array, Array]:
    """Least-squares ``S ≥ 0`` (clipped) and residual ``‖y - D S‖²`` for ``D (..., K, M)``."""
    dtd = np.swapaxes(D, -1, -2) @ D
    dty = np.swapaxes(D, -1, -2) @ y
    m = D.shape[-1]
    ridge = 1e-9 * np.trace(dtd, axis1=-2, axis2=-1)[..., None, None] + 1e-300
    S = np.linalg.solve(dtd + ridge * np.eye(m), dty[..., None])[..., 0]
    S = np.maximum(S, 0.0)
    r = y - (D @ S[..., None])[..., 0]
    return S, (r * r).sum(-1)


def energy_localise(
    energies: ArrayLike,
    sensors: ArrayLike,
    n_sources: int = 1,
    *,
    field_box: tuple[float, float, float, float] = (0.0, 10.0, 0.0, 5.0),
    gains: ArrayLike | None = None,
    alpha: float = 2.0,
    grid_step: float = 0.1,
    sweeps: int = 3,
) -> tuple[Array, Array]:
    """ML EBL positions ``(M, 2)`` and energies ``(M,)`` from sensor energies ``(K,)`` at ``sensors
    (K, 2)``. Needs ``K ≥ 3M`` for the positions and energies to be identifiable (2-D)."""
    y = np.asarray(energies, float)
    s = np.asarray(sensors, float)
    if s.ndim != 2 or s.shape[1] != 2 or y.shape != (s.shape[0],):
        raise ShapeError(invalid("energies/sensors", (y.shape, s.shape), "(K,) and (K, 2)"))
    if n_sources < 1:
        raise ConfigError(invalid("n_sources", n_sources, "an integer >= 1"))
    if not np.all(np.isfinite(y)):
        raise ConfigError(invalid("energies", y, "finite energies"))
    g = np.ones(s.shape[0]) if gains is None else np.asarray(gains, float)
    x0, x1, y0, y1 = field_box
    gx = np.arange(x0, x1 + 1e-9, grid_step)
    gy = np.arange(y0, y1 + 1e-9, grid_step)
    grid = np.stack(np.meshgrid(gx, gy, indexing="ij"), -1).reshape(-1, 2)
    d = np.maximum(np.hypot(*(grid[:, None, :] - s[None, :, :]).transpose(2, 0, 1)), 0.05)
    cols = g / d**alpha  # (G, K): one source at each grid point
    X = np.zeros((n_sources, 2))
    chosen: list[int] = []
    for sweep in range(sweeps):
        for m in range(n_sources):
            fixed = [c for i, c in enumerate(chosen) if i != m]
            D = np.concatenate(
                [
                    np.broadcast_to(cols[fixed].T, (grid.shape[0], s.shape[0], len(fixed))),
                    cols[:, :, None],
                ],
                axis=-1,
            )
            _, rss = _residual(y, D)
            pick = int(np.argmin(rss))
            if sweep == 0 and len(chosen) <= m:
                chosen.append(pick)
            else:
                chosen[m] = pick
            X[m] = grid[pick]
    S, _ = _residual(y, cols[chosen].T)
    return X, S
