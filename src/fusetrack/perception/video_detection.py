"""A camera's motion detection function over bearing (Kushwaha 2010, Ch. III, Eqs. 23–27, 35).

Per frame: adaptive Gaussian-mixture background subtraction, a 3×3 median filter, foreground
pixel counts per image column summed into M = 160 angle bins (Eqs. 23–24), removal of the
persistent background by a moving average (Eqs. 25–26), a 7-tap box blur against glints
(Eq. 27), and a Gaussian-mixture fit of the result, λ(θ) = Σ a_i N(θ | μ_i, σ_i²) (Eq. 35), which is
what the fusion node uses as the camera's likelihood over bearing.

The paper uses the KaewTraKulPong–Bowden mixture (OpenCV ``bgsegm.MOG``, in the contrib build
only). ``opencv-python-headless`` has Zivkovic's MOG2, the same per-pixel adaptive mixture with an
automatically chosen number of components; we use it with shadow detection off.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ShapeError, invalid


def column_bins(column_angles: ArrayLike, fov: float, n_bins: int = 160) -> NDArray[np.int64]:
    """Bin index of each image column: θ_i = θ_min + (i - 1)(θ_max - θ_min)/M (Kushwaha 2010, Eq. 23)."""
    a = np.asarray(column_angles, float)
    idx = np.floor((a + fov / 2) / fov * n_bins).astype(np.int64)
    return np.clip(idx, 0, n_bins - 1)


def detection_from_mask(mask: ArrayLike, bins: ArrayLike, n_bins: int = 160) -> NDArray[np.float64]:
    """λ(θ_i) = Σ_{j ∈ θ_i} Σ_k F(j, k): foreground pixels of the columns in bin i (Kushwaha 2010, Eq. 24)."""
    f = np.asarray(mask)
    b = np.asarray(bins)
    if f.ndim != 2 or f.shape[1] != b.size:
        raise ShapeError(
            invalid("mask.shape", f.shape, f"(rows, {b.size}) matching the column bins")
        )
    counts = np.bincount(b, weights=(f > 0).sum(axis=0).astype(float), minlength=n_bins)
    return np.asarray(counts, dtype=np.float64)


@dataclass
class DetectionPostFilter:
    """Eqs. 25–27: b_t = α b_{t-1} + (1 - α) λ_t; λ_t ← max(λ_t - b_{t-1}, 0); λ_t ← λ_t * (1/7)·1₇.

    The background update uses the raw λ_t (spec 003 A-III-8; α = 0.95 per frame)."""

    alpha: float = 0.95
    taps: int = 7
    background: NDArray[np.float64] | None = None

    def __call__(self, lam: ArrayLike) -> NDArray[np.float64]:
        raw = np.asarray(lam, float)
        prev = np.zeros_like(raw) if self.background is None else self.background
        out = np.maximum(raw - prev, 0.0)  # Eq. 26
        self.background = self.alpha * prev + (1 - self.alpha) * raw  # Eq. 25
        return np.convolve(out, np.full(self.taps, 1.0 / self.taps), mode="same")  # Eq. 27


@dataclass(frozen=True)
class AngleMixture:
    """λ(θ) = Σ a_i N(θ | μ_i, σ_i²) over camera-frame bearings (Kushwaha 2010, Eq. 35); empty = no detection."""

    weights: NDArray[np.float64]
    means: NDArray[np.float64]
    sigmas: NDArray[np.float64]

    @property
    def empty(self) -> bool:
        return self.weights.size == 0

    def __call__(self, theta: ArrayLike) -> NDArray[np.float64]:
        t = np.asarray(theta, float)[..., None]
        z = (t - self.means) / self.sigmas
        return (self.weights * np.exp(-0.5 * z * z) / (np.sqrt(2 * np.pi) * self.sigmas)).sum(-1)


def fit_angle_mixture(
    lam: ArrayLike,
    angles: ArrayLike,
    rel_threshold: float = 0.1,
    min_sigma_bins: float = 2.0,
    min_mass: float = 0.0,
) -> AngleMixture:
    """Moment fit of one Gaussian per detection region (spec 003 §2.3 step 8, [C]: the paper says
    only that the parameters "are calculated from the detection function").

    A region is a run of consecutive bins above ``rel_threshold`` × max (so one blob with a rippled
    top stays one component); a_i = region mass (normalised over regions), μ_i and σ_i² the
    mass-weighted mean and variance of its bearings (σ ≥ ``min_sigma_bins`` bins). Regions with
    less than ``min_mass`` are ignored; nothing left means "no detection" (an empty mixture)."""
    v = np.asarray(lam, float)
    a = np.asarray(angles, float)
    step = float(abs(a[1] - a[0]))
    top = float(v.max()) if v.size else 0.0
    empty = AngleMixture(np.empty(0), np.empty(0), np.empty(0))
    if not top > 0:
        return empty
    above = np.concatenate([[False], v >= rel_threshold * top, [False]])
    edges = np.flatnonzero(np.diff(above.astype(np.int8)))
    w, mu, sd = [], [], []
    for lo, hi in zip(edges[::2], edges[1::2]):
        m = v[lo:hi]
        mass = float(m.sum())
        if mass <= min_mass:
            continue
        mean = float(m @ a[lo:hi] / mass)
        var = float(m @ (a[lo:hi] - mean) ** 2 / mass)
        w.append(mass)
        mu.append(mean)
        sd.append(max(np.sqrt(var), min_sigma_bins * step))
    if not w:
        return empty
    wa = np.array(w)
    return AngleMixture(wa / wa.sum(), np.array(mu), np.array(sd))


@dataclass
class VideoDetector:
    """One video node: frames in, (filtered detection function, angle mixture) out.

    ``column_angles`` are the camera's column bearings (camera frame), ``fov`` its field of view.
    """

    column_angles: NDArray[np.float64]
    fov: float
    n_bins: int = 160
    history: int = 200
    var_threshold: float = 16.0
    min_mass: float = 20.0  # foreground pixels: less is noise, not a vehicle
    post: DetectionPostFilter = field(default_factory=DetectionPostFilter)
    frames: int = 0

    def __post_init__(self) -> None:
        self._bins = column_bins(self.column_angles, self.fov, self.n_bins)
        self._mog = cv2.createBackgroundSubtractorMOG2(
            history=self.history, varThreshold=self.var_threshold, detectShadows=False
        )

    @property
    def bin_angles(self) -> NDArray[np.float64]:
        step = self.fov / self.n_bins
        return np.asarray(-self.fov / 2 + step * (np.arange(self.n_bins) + 0.5), dtype=np.float64)

    def learn_background(self, frame: NDArray[np.uint8]) -> None:
        """Feed a target-free frame (warm-up) without producing a detection."""
        self._mog.apply(frame)

    def raw_detection(self, frame: NDArray[np.uint8]) -> NDArray[np.float64]:
        if frame.ndim != 2 or frame.shape[1] != self._bins.size:
            raise ShapeError(
                invalid("frame.shape", frame.shape, f"(rows, {self._bins.size}) grey levels")
            )
        self.frames += 1
        fg = self._mog.apply(frame)
        fg = cv2.medianBlur(fg, 3)  # Kushwaha 2010, Ch. III: 3×3 median filter
        return detection_from_mask(fg, self._bins, self.n_bins)

    def process(self, frame: NDArray[np.uint8]) -> tuple[NDArray[np.float64], AngleMixture]:
        lam = self.post(self.raw_detection(frame))
        return lam, fit_angle_mixture(lam, self.bin_angles, min_mass=self.min_mass)
