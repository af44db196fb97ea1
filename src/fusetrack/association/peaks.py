"""Point observations from a fused likelihood grid (spec 003 §2.6, [C]).

Kushwaha 2010 feeds MCMCDA with "raw observations obtained from the multimodal sensor fusion and
peak detection algorithms" without saying how peaks are found. Here: smooth the fused likelihood
with a 3×3 box, keep local maxima of a 5×5-cell neighbourhood that reach ``rel_threshold`` of the
largest value and an absolute threshold, and report the likelihood-weighted centroid of each
maximum's 5×5 window.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.ndimage import maximum_filter, uniform_filter

from ..core import ShapeError, invalid


def likelihood_peaks(
    likelihood: ArrayLike,
    x: ArrayLike,
    y: ArrayLike,
    rel_threshold: float = 0.3,
    abs_threshold: float = 0.0,
    neighbourhood: int = 5,
    max_peaks: int = 10,
) -> NDArray[np.float64]:
    """Peak positions ``(k, 2)`` (world units) of a likelihood on the grid ``x × y`` (shape (nx, ny))."""
    xs = np.asarray(x, float)
    ys = np.asarray(y, float)
    lk = np.asarray(likelihood, float)
    if lk.shape != (xs.size, ys.size):
        lk = lk.reshape(xs.size, ys.size) if lk.size == xs.size * ys.size else lk
    if lk.shape != (xs.size, ys.size):
        raise ShapeError(invalid("likelihood.shape", lk.shape, f"({xs.size}, {ys.size})"))
    smooth = uniform_filter(lk, 3, mode="constant")
    top = smooth.max()
    if not top > 0:
        return np.empty((0, 2))
    is_max = (smooth == maximum_filter(smooth, neighbourhood, mode="constant")) & (
        smooth >= max(rel_threshold * top, abs_threshold)
    )
    idx = np.argwhere(is_max)
    idx = idx[np.argsort(-smooth[is_max], kind="stable")]
    h = neighbourhood // 2
    kept: list[tuple[int, int]] = []
    for i, j in idx:  # a flat top gives several equal maxima: keep one per neighbourhood
        if len(kept) < max_peaks and all(max(abs(i - a), abs(j - b)) > h for a, b in kept):
            kept.append((int(i), int(j)))
    out = []
    for i, j in kept:
        i0, i1 = max(0, i - h), min(xs.size, i + h + 1)
        j0, j1 = max(0, j - h), min(ys.size, j + h + 1)
        w = lk[i0:i1, j0:j1]
        mass = w.sum()
        if mass <= 0:
            continue
        out.append([w.sum(axis=1) @ xs[i0:i1] / mass, w.sum(axis=0) @ ys[j0:j1] / mass])
    return np.array(out).reshape(-1, 2)
