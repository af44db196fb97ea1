"""Multi-view colour and texture appearance of a 3-D target (Kushwaha 2010, Ch. V, Eqs. 62-76).

The measurement a camera reports is a :class:`FeatureImage`: its frame's per-pixel colour bin
(8 x 8 hue-saturation bins + 8 value bins, 72) and uniform-LBP texture code (59), computed from
the raw image by :func:`fusetrack.perception.appearance.features_from_rgb`. This module holds
what compares such a frame with a target hypothesis:

* region histograms weighted by the Epanechnikov profile ``k(d) = 1 - d`` of the ellipse distance
  ``d = (y_i - y)^T B (y_i - y)`` (Eqs. 69, 74-75), computed for many candidate regions at once;
* the Bhattacharyya coefficient ``rho = sum_u sqrt(p_u q_u)`` (Eq. 62) and the two-feature mix
  ``rho = alpha rho_HS + (1 - alpha) rho_LBP`` (Eq. 81);
* :class:`AppearanceModel`: one pair of histograms per body-frame viewpoint ``e_j`` (Eq. 66); the
  view a camera sees is ``argmax_j e_target^T R(theta) e_j`` (Eq. 71).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ShapeError, invalid

Array = NDArray[np.float64]
BinMap = NDArray[np.int32]

N_HS = 8 * 8 + 8
N_LBP = 59


@dataclass(frozen=True)
class FeatureImage:
    """One frame's per-pixel colour (``hs``, 0..71) and texture (``lbp``, 0..58) bins, computed
    once per frame (spec Sec. 2.9): the value of a camera's :class:`~fusetrack.core.Measurement`."""

    hs: BinMap
    lbp: BinMap

    @property
    def size(self) -> tuple[int, int]:
        return int(self.hs.shape[1]), int(self.hs.shape[0])


@numba.njit(cache=True)
def _region_histograms_kernel(
    bins: NDArray[np.int32], centres: Array, shapes: Array, n_bins: int, out: Array
) -> None:
    H, W = bins.shape
    for r in range(centres.shape[0]):
        cx, cy = centres[r, 0], centres[r, 1]
        b00, b01, b11 = shapes[r, 0, 0], shapes[r, 0, 1], shapes[r, 1, 1]
        det = b00 * b11 - b01 * b01
        if not (det > 0.0) or not (cx == cx) or not (cy == cy):
            continue
        hx = np.sqrt(b11 / det)  # half-widths of the bounding box of the ellipse
        hy = np.sqrt(b00 / det)
        x0 = max(0, int(np.ceil(cx - hx)))
        x1 = min(W - 1, int(np.floor(cx + hx)))
        y0 = max(0, int(np.ceil(cy - hy)))
        y1 = min(H - 1, int(np.floor(cy + hy)))
        total = 0.0
        for y in range(y0, y1 + 1):
            dy = y - cy
            for x in range(x0, x1 + 1):
                dx = x - cx
                d = b00 * dx * dx + 2.0 * b01 * dx * dy + b11 * dy * dy
                if d < 1.0:
                    w = 1.0 - d
                    out[r, bins[y, x]] += w
                    total += w
        if total > 0.0:
            for u in range(n_bins):
                out[r, u] /= total


def region_histograms(bins: BinMap, centres: ArrayLike, shapes: ArrayLike, n_bins: int) -> Array:
    """Normalised kernel-weighted histograms ``(R, n_bins)`` of the elliptic regions
    ``(y - c_r)^T B_r (y - c_r) < 1`` (Kushwaha 2010, Eqs. 74-75, Epanechnikov profile).

    A region with no pixel in the image (or a NaN ellipse) gives an all-zero row.
    """
    c = np.ascontiguousarray(np.asarray(centres, float).reshape(-1, 2))
    b = np.ascontiguousarray(np.asarray(shapes, float).reshape(-1, 2, 2))
    if b.shape[0] != c.shape[0]:
        raise ShapeError(invalid("shapes.shape", b.shape, f"({c.shape[0]}, 2, 2) like centres"))
    out = np.zeros((c.shape[0], n_bins))
    _region_histograms_kernel(np.ascontiguousarray(bins, dtype=np.int32), c, b, n_bins, out)
    return out


def region_histograms_reference(
    bins: BinMap, centres: ArrayLike, shapes: ArrayLike, n_bins: int
) -> Array:
    """Readable NumPy version of :func:`region_histograms` (the tests compare the two)."""
    c = np.asarray(centres, float).reshape(-1, 2)
    b = np.asarray(shapes, float).reshape(-1, 2, 2)
    H, W = bins.shape
    yy, xx = np.mgrid[0:H, 0:W]
    out = np.zeros((c.shape[0], n_bins))
    for r in range(c.shape[0]):
        if not np.all(np.isfinite(b[r])) or not np.all(np.isfinite(c[r])):
            continue
        dx, dy = xx - c[r, 0], yy - c[r, 1]
        d = b[r, 0, 0] * dx * dx + 2 * b[r, 0, 1] * dx * dy + b[r, 1, 1] * dy * dy
        w = np.where(d < 1.0, 1.0 - d, 0.0)
        out[r] = np.bincount(bins.ravel(), weights=w.ravel(), minlength=n_bins)[:n_bins]
        if out[r].sum() > 0:
            out[r] /= out[r].sum()
    return out


def bhattacharyya(p: ArrayLike, q: ArrayLike) -> Array:
    """``rho = sum_u sqrt(p_u q_u)`` over the last axis (Kushwaha 2010, Eq. 62)."""
    return np.sum(np.sqrt(np.asarray(p, float) * np.asarray(q, float)), axis=-1)


@dataclass(frozen=True)
class AppearanceModel:
    """Multi-view reference ``Q = [q_e1, ..., q_eJ]`` (Eq. 66): ``viewpoints`` ``(J, 3)`` unit
    vectors in the body frame, ``hs`` ``(J, 72)`` and ``lbp`` ``(J, 59)`` histograms."""

    viewpoints: Array
    hs: Array
    lbp: Array
    alpha: float = 0.5  # alpha_HS of Eq. 81

    def view_index(
        self, camera_centre: ArrayLike, x: ArrayLike, rotation: ArrayLike
    ) -> NDArray[np.intp]:
        """``argmax_j e_target^T R(theta) e_j`` with ``e_target`` from the target to the camera
        (Eq. 71), for positions ``x`` ``(..., 3)``."""
        e = np.asarray(camera_centre, float) - np.asarray(x, float)
        e = e / np.linalg.norm(e, axis=-1, keepdims=True)
        body = e @ np.asarray(rotation, float)  # R^T e in the body frame
        return np.argmax(body @ self.viewpoints.T, axis=-1)

    def similarity(
        self, features: FeatureImage, centres: ArrayLike, shapes: ArrayLike, view: ArrayLike
    ) -> Array:
        """``alpha rho_HS + (1 - alpha) rho_LBP`` of each candidate region against its view
        (Eqs. 62, 74-76, 81); ``view`` is one index or one per region."""
        c = np.asarray(centres, float).reshape(-1, 2)
        b = np.asarray(shapes, float).reshape(-1, 2, 2)
        v = np.broadcast_to(np.asarray(view), (c.shape[0],))
        p_hs = region_histograms(features.hs, c, b, N_HS)
        p_lbp = region_histograms(features.lbp, c, b, N_LBP)
        return self.alpha * bhattacharyya(p_hs, self.hs[v]) + (1 - self.alpha) * bhattacharyya(
            p_lbp, self.lbp[v]
        )

    def all_views(self, features: FeatureImage, centre: ArrayLike, shape: ArrayLike) -> Array:
        """Similarity ``rho_j`` of one region against every view ``j`` (input of Eq. 77)."""
        p_hs = region_histograms(features.hs, centre, shape, N_HS)[0]
        p_lbp = region_histograms(features.lbp, centre, shape, N_LBP)[0]
        return self.alpha * bhattacharyya(p_hs, self.hs) + (1 - self.alpha) * bhattacharyya(
            p_lbp, self.lbp
        )
