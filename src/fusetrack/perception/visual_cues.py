"""The three visual cues of Zhai 2007's multi-cue tracker (Sec. 5.4.1-5.4.2) and its front end.

Each cue finds one location of the target inside a *tracking aid window* centred at the
predicted centre; the location is then an ordinary position measurement (a
:class:`~fusetrack.sensors.PositionFix` with ``cov = sigma^2 I``: Eq. 90 with its sign and the
degenerate cross term corrected, spec Sec. 6 item 15), and the three are fused in the filter as
independent sensors (Eq. 91).

1. *Adaptive edge template*: the Canny edge patch at the previous estimate, cross-correlated
   (Eq. 85, ``(1/MN) sum f(m, n) h(x + m, y + n)``) with the aid window's edge map; argmax.
2. *Intra-frame grey-level template*: a weighted sum of past patches at the past estimates,
   ``eps_t(k) = alpha exp(-(t - k)/tau)``, ``tau = n_h / ln 2``, ``alpha = 1 - exp(-1/tau)``
   (Eq. 86) -- the recursion ``T_t = alpha P_t + (1 - alpha) T_{t-1}``; cross-correlated (Eq. 85);
   argmax. ``half_life=None`` replaces the template each frame (the Appendix B demo).
3. *Colour histogram*: an HSI histogram (16 x 8 x 4 bins, spec choice) of the target box at the
   first frame against the box at every candidate centre of the window; Kullback-Leibler
   divergence ``D(p_target || p_candidate)`` (Eq. 89, ``eps = 1e-6``); argmin. RGB -> HSI by
   Eqs. 87-88 with the numerator ``(R - G) + (R - B)`` (the thesis prints ``(R + G)``).

Eq. 85 is a plain (not normalised) correlation, which prefers bright (or edge-dense) regions
over the target; ``correlation="normalised"`` (zero-mean normalised cross-correlation) is the
usual fix. The default is the printed one; the experiments say which they use.

Ties: when several candidates share the best score (the colour cue on a uniformly coloured
target larger than the box: every placement inside it has the same histogram) the location is
the centre of the tied candidates. The thesis takes "the" argmin; App. B's MATLAB returns every
tied location and then uses the first, which biases the cue towards the window's top-left.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import cv2
import numpy as np
from numpy.typing import NDArray

from ..core import ConfigError, ShapeError, invalid
from .visual_edges import edge_map

Array = NDArray[np.float64]
CUES = ("edge", "grey", "colour")


def rgb_to_hsi(image: NDArray[np.generic]) -> tuple[Array, Array, Array]:
    """Hue (degrees, [0, 360)), saturation and intensity ([0, 1]) of an RGB image (Eqs. 87-88).

    ``H = theta if B <= G else 360 - theta``,
    ``theta = arccos(((R-G) + (R-B)) / 2 / sqrt((R-G)^2 + (R-B)(G-B)))``,
    ``S = 1 - 3 min(R, G, B) / (R + G + B)``, ``I = (R + G + B) / 3``.
    """
    img = np.asarray(image, dtype=np.float64)
    if img.ndim != 3 or img.shape[-1] != 3:
        raise ShapeError(invalid("image.shape", img.shape, "(H, W, 3) RGB"))
    if np.issubdtype(np.asarray(image).dtype, np.integer):
        img = img / 255.0
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    num = 0.5 * ((r - g) + (r - b))
    den = np.sqrt((r - g) ** 2 + (r - b) * (g - b))
    theta = np.degrees(np.arccos(np.clip(num / np.maximum(den, 1e-12), -1.0, 1.0)))
    hue = np.where(b <= g, theta, 360.0 - theta)
    hue = np.where(den < 1e-12, 0.0, hue) % 360.0  # grey: hue undefined, set 0
    total = r + g + b
    sat = np.where(total > 0, 1.0 - 3.0 * np.min(img, axis=-1) / np.maximum(total, 1e-12), 0.0)
    return hue, sat, total / 3.0


def hsi_bins(
    image: NDArray[np.generic], bins: tuple[int, int, int] = (16, 8, 4)
) -> NDArray[np.intp]:
    """The joint HSI bin index ``(H, W)`` of every pixel."""
    h, s, i = rgb_to_hsi(image)
    nh, ns, ni = bins
    bh = np.minimum((h / 360.0 * nh).astype(np.intp), nh - 1)
    bs = np.minimum((s * ns).astype(np.intp), ns - 1)
    bi = np.minimum((i * ni).astype(np.intp), ni - 1)
    return np.asarray((bh * ns + bs) * ni + bi, dtype=np.intp)


def hsi_histogram(patch: NDArray[np.generic], bins: tuple[int, int, int] = (16, 8, 4)) -> Array:
    """Normalised joint HSI histogram of a patch (``prod(bins)`` entries)."""
    idx = hsi_bins(patch, bins).ravel()
    h = np.bincount(idx, minlength=int(np.prod(bins))).astype(np.float64)
    return h / max(h.sum(), 1.0)


def kl_divergence(p: Array, q: Array, eps: float = 1e-6) -> Array:
    """``D(p || q) = sum p log(p / q)`` over the last axis (Eq. 89), ``eps`` added to both."""
    p = np.asarray(p, float) + eps
    q = np.asarray(q, float) + eps
    return np.asarray(np.sum(p * np.log(p / q), axis=-1), dtype=np.float64)


def crop(
    image: NDArray[np.generic], centre: tuple[int, int], half: tuple[int, int]
) -> NDArray[np.generic]:
    """The ``(2 hh + 1, 2 hw + 1)`` patch at ``centre = (row, col)``, zero outside the image."""
    (r, c), (hh, hw) = centre, half
    H, W = image.shape[:2]
    out = np.zeros((2 * hh + 1, 2 * hw + 1, *image.shape[2:]), image.dtype)
    r0, r1, c0, c1 = r - hh, r + hh + 1, c - hw, c + hw + 1
    rr0, rr1, cc0, cc1 = max(r0, 0), min(r1, H), max(c0, 0), min(c1, W)
    if rr1 > rr0 and cc1 > cc0:
        out[rr0 - r0 : rr1 - r0, cc0 - c0 : cc1 - c0] = image[rr0:rr1, cc0:cc1]
    return out


def correlation_map(
    region: Array, template: Array, correlation: Literal["plain", "normalised"] = "plain"
) -> Array:
    """Eq. 85 at every placement of ``template`` inside ``region`` (``valid`` size)."""
    method = cv2.TM_CCORR if correlation == "plain" else cv2.TM_CCOEFF_NORMED
    out = cv2.matchTemplate(region.astype(np.float32), template.astype(np.float32), method)
    return np.asarray(out / template.size if correlation == "plain" else out, dtype=np.float64)


def kld_map(
    region_bins: NDArray[np.intp], target: Array, box: tuple[int, int], eps: float = 1e-6
) -> Array:
    """``D(target || candidate)`` for every ``box``-sized placement in ``region_bins`` (valid size).

    Candidate histograms come from integral images of the target's occupied bins only (the
    other bins add ``eps log(eps / (q + eps))``, which is ignored: they are nearly equal).
    """
    bh, bw = box
    occ = np.flatnonzero(target > 0)
    lut = np.full(len(target), len(occ), dtype=np.intp)  # unoccupied bins -> a dummy channel
    lut[occ] = np.arange(len(occ))
    h, w = region_bins.shape
    onehot = np.zeros((h, w, len(occ) + 1), np.float32)
    rows, cols = np.indices((h, w))
    onehot[rows, cols, lut[region_bins]] = 1.0
    integ = np.zeros((h + 1, w + 1, len(occ) + 1), np.float32)
    np.cumsum(onehot, axis=0, out=integ[1:, 1:])
    np.cumsum(integ[1:, 1:], axis=1, out=integ[1:, 1:])
    integ = integ[..., :-1]
    counts = integ[bh:, bw:] - integ[:-bh, bw:] - integ[bh:, :-bw] + integ[:-bh, :-bw]
    q = counts.astype(np.float64) / (bh * bw)
    p = target[occ] + eps
    return np.asarray(np.sum(p * np.log(p / (q + eps)), axis=-1), dtype=np.float64)


@dataclass
class MultiCueFrontEnd:
    """Aid-window cue locator for one tracker (mutable: the templates adapt to its estimates).

    ``box = (h, w)`` odd target box (px); ``half_window`` makes a ``(2 hw + 1)^2`` window of
    candidate centres (App. B: 20 -> 41 x 41); ``cues`` in the order of the filter's sensors.
    ``measure`` returns, per cue, the location ``[x, y]`` = (column, row), or None when the cue
    finds nothing (an edge window without edges).
    """

    box: tuple[int, int] = (37, 29)
    half_window: int = 20
    cues: Sequence[str] = CUES
    half_life: float | None = 5.0
    correlation: Literal["plain", "normalised"] = "plain"
    bins: tuple[int, int, int] = (16, 8, 4)
    edge_smooth: float = 1.0
    grey: Array | None = field(default=None, init=False)
    edge: Array | None = field(default=None, init=False)
    target_hist: Array | None = field(default=None, init=False)

    def __post_init__(self) -> None:
        bad = [c for c in self.cues if c not in CUES]
        if bad or not self.cues:
            raise ConfigError(invalid("cues", list(self.cues), f"a non-empty subset of {CUES}"))
        if self.box[0] % 2 == 0 or self.box[1] % 2 == 0:
            raise ConfigError(invalid("box", self.box, "odd (h, w) so the box has a centre pixel"))
        if self.half_life is not None and self.half_life <= 0:
            raise ConfigError(invalid("half_life", self.half_life, "> 0 frames or None"))

    @property
    def alpha(self) -> float:
        """Eq. 86's weight of the newest patch: ``1 - exp(-1/tau)``, ``tau = n_h / ln 2``."""
        if self.half_life is None:
            return 1.0
        return float(1.0 - np.exp(-np.log(2.0) / self.half_life))

    @staticmethod
    def _grey(frame: NDArray[np.uint8]) -> Array:
        img = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY)
        return np.asarray(img, dtype=np.float64)

    def _edges(self, frame: NDArray[np.uint8]) -> Array:
        return edge_map(frame, self.edge_smooth)

    def adapt(self, frame: NDArray[np.uint8], estimate: Array) -> None:
        """Update the templates at the new estimate (Eq. 86; the edge template is replaced)."""
        rc = (round(float(estimate[1])), round(float(estimate[0])))
        half = (self.box[0] // 2, self.box[1] // 2)
        if "grey" in self.cues:
            patch = np.asarray(crop(self._grey(frame), rc, half), dtype=np.float64)
            a = self.alpha
            self.grey = patch if self.grey is None else a * patch + (1 - a) * self.grey
        if "edge" in self.cues:
            self.edge = np.asarray(crop(self._edges(frame), rc, half), dtype=np.float64)
        if "colour" in self.cues and self.target_hist is None:
            if frame.ndim != 3:
                raise ShapeError(
                    invalid("frame.shape", frame.shape, "(H, W, 3) for the colour cue")
                )
            self.target_hist = hsi_histogram(crop(frame, rc, half), self.bins)

    def measure(self, frame: NDArray[np.uint8], predicted: Array) -> list[Array | None]:
        """Each cue's location in the aid window at ``predicted = [x, y]``."""
        rc = (round(float(predicted[1])), round(float(predicted[0])))
        hw = self.half_window
        half = (hw + self.box[0] // 2, hw + self.box[1] // 2)
        out: list[Array | None] = []
        for cue in self.cues:
            if cue == "colour":
                assert self.target_hist is not None
                score = -kld_map(
                    hsi_bins(crop(frame, rc, half), self.bins), self.target_hist, self.box
                )
            elif cue == "grey":
                assert self.grey is not None
                score = correlation_map(
                    np.asarray(crop(self._grey(frame), rc, half), dtype=np.float64),
                    self.grey,
                    self.correlation,
                )
            else:
                assert self.edge is not None
                region = np.asarray(crop(self._edges(frame), rc, half), dtype=np.float64)
                if not np.any(region) or not np.any(self.edge):
                    out.append(None)
                    continue
                score = correlation_map(region, self.edge, self.correlation)
                if not np.any(score > 0):
                    out.append(None)
                    continue
            top = float(np.max(score))
            ii, jj = np.nonzero(score >= top - 1e-9 * (1.0 + abs(top)))
            i, j = float(ii.mean()), float(jj.mean())  # the centre of tied maxima (see below)
            out.append(np.array([rc[1] - hw + j, rc[0] - hw + i], dtype=np.float64))
        return out
