"""Multi-view colour and texture appearance of a 3-D target (Kushwaha 2010, Ch. V, Eqs. 60-76).

* Colour (after Perez et al.): HSV, an 8 x 8 hue-saturation histogram of the pixels with
  saturation > 0.1 and value > 0.2, and 8 value-only bins for the "colour-free" rest: 72 bins.
* Texture (after Ojala et al.): uniform local binary patterns, 8 neighbours at radius 1, the 59
  non-rotation-invariant uniform codes (scikit-image ``local_binary_pattern``, ``nri_uniform``).
* Region histograms weighted by the Epanechnikov profile ``k(d) = 1 - d`` of the ellipse distance
  ``d = (y_i - y)^T B (y_i - y)`` (Eqs. 69, 74-75), computed for many candidate regions at once.
* The Bhattacharyya coefficient ``rho = sum_u sqrt(p_u q_u)`` (Eq. 62) and the two-feature mix
  ``rho = alpha rho_HS + (1 - alpha) rho_LBP`` (Eq. 81).
* :class:`AppearanceModel`: one pair of histograms per body-frame viewpoint ``e_j`` (Eq. 66); the
  view a camera sees is ``argmax_j e_target^T R(theta) e_j`` (Eq. 71).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray
from skimage.feature import local_binary_pattern

from ..core.errors import ShapeError, invalid

Array = NDArray[np.float64]
BinMap = NDArray[np.int32]

N_HS = 8 * 8 + 8
N_LBP = 59
S_MIN, V_MIN = 0.1, 0.2  # Perez et al.'s thresholds on [0, 1]


def hs_bins(image: NDArray[np.uint8]) -> BinMap:
    """Per-pixel colour bin (0..71) of an RGB image: 8 x 8 HS bins, else 8 value bins."""
    if image.ndim != 3 or image.shape[2] != 3:
        raise ShapeError(invalid("image.shape", image.shape, "(H, W, 3) RGB"))
    hsv = cv2.cvtColor(image, cv2.COLOR_RGB2HSV).astype(np.int32)
    h = np.minimum(hsv[..., 0] * 8 // 180, 7)
    s = np.minimum(hsv[..., 1] * 8 // 256, 7)
    v = np.minimum(hsv[..., 2] * 8 // 256, 7)
    coloured = (hsv[..., 1] > S_MIN * 255) & (hsv[..., 2] > V_MIN * 255)
    return np.where(coloured, h * 8 + s, 64 + v).astype(np.int32)


def lbp_bins(image: NDArray[np.uint8]) -> BinMap:
    """Per-pixel uniform LBP code (0..58) of an RGB image's grey levels (P = 8, R = 1)."""
    grey = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
    return local_binary_pattern(grey, 8, 1, method="nri_uniform").astype(np.int32)


@dataclass(frozen=True)
class FeatureImage:
    """One frame's per-pixel colour and texture bins, computed once per frame (spec Sec. 2.9)."""

    hs: BinMap
    lbp: BinMap

    @classmethod
    def from_rgb(cls, image: NDArray[np.uint8]) -> FeatureImage:
        return cls(hs_bins(image), lbp_bins(image))

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

    @classmethod
    def from_views(
        cls,
        images: Sequence[NDArray[np.uint8]],
        centres: ArrayLike,
        shapes: ArrayLike,
        viewpoints: ArrayLike,
        alpha: float = 0.5,
    ) -> AppearanceModel:
        """Histograms of the target's ellipse in each reference image (Eqs. 67-69)."""
        c = np.asarray(centres, float)
        b = np.asarray(shapes, float)
        hs, lbp = [], []
        for j, img in enumerate(images):
            f = FeatureImage.from_rgb(img)
            hs.append(region_histograms(f.hs, c[j], b[j], N_HS)[0])
            lbp.append(region_histograms(f.lbp, c[j], b[j], N_LBP)[0])
        return cls(np.asarray(viewpoints, float), np.array(hs), np.array(lbp), alpha)

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
