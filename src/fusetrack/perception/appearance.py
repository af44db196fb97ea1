"""From a camera's RGB frame to the appearance features its measurement carries (Kushwaha 2010,
Ch. V, Eqs. 60-69).

* Colour (after Perez et al.): HSV, an 8 x 8 hue-saturation histogram of the pixels with
  saturation > 0.1 and value > 0.2, and 8 value-only bins for the "colour-free" rest: 72 bins.
* Texture (after Ojala et al.): uniform local binary patterns, 8 neighbours at radius 1, the 59
  non-rotation-invariant uniform codes (scikit-image ``local_binary_pattern``, ``nri_uniform``).
* The target's multi-view reference model from rendered or recorded views (Eqs. 66-69).

Comparing a frame with a target hypothesis (region histograms, Bhattacharyya similarity, the
appearance likelihood) is the sensor model's work: :mod:`fusetrack.sensors.appearance`.
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray
from skimage.feature import local_binary_pattern

from ..core import ShapeError, invalid
from ..sensors import N_HS, N_LBP, AppearanceModel, BinMap, FeatureImage, region_histograms

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


def features_from_rgb(image: NDArray[np.uint8]) -> FeatureImage:
    """A frame's colour and texture bins, the value of its camera's measurement."""
    return FeatureImage(hs_bins(image), lbp_bins(image))


def appearance_model_from_views(
    images: Sequence[NDArray[np.uint8]],
    centres: ArrayLike,
    shapes: ArrayLike,
    viewpoints: ArrayLike,
    alpha: float = 0.5,
) -> AppearanceModel:
    """Histograms of the target's ellipse in each reference image (Eqs. 66-69), one view each."""
    c = np.asarray(centres, float)
    b = np.asarray(shapes, float)
    hs, lbp = [], []
    for j, img in enumerate(images):
        f = features_from_rgb(img)
        hs.append(region_histograms(f.hs, c[j], b[j], N_HS)[0])
        lbp.append(region_histograms(f.lbp, c[j], b[j], N_LBP)[0])
    return AppearanceModel(np.asarray(viewpoints, float), np.array(hs), np.array(lbp), alpha)
