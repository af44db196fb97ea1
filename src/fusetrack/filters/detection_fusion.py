"""Quality-weighted fusion of camera detections with a dynamic prior (Lee 2009, Ch. 4).

Several cameras see one ground plane. Each camera ``j`` either detects the object (decision
``E1``, local image position ``l^j``) or not (``E0``). Local positions map to the ground plane
with a per-camera homography ``G_j`` (the text's "perspective model"). Per frame:

1. predict the ground-plane state ``g = [g_x, g_vx, g_y, g_vy]`` with constant velocity
   (Lee 2009, Eq. 4.19);
2. quality of each detecting camera: ``W^j = exp(-|g^j - g_pred|^2 / (2 sigma^2))`` (Eq. 4.20);
3. fused position ``g = sum_j W^j g^j / sum_j W^j`` (Eq. 4.22);
4. prior of presence ``P1 = exp(-|g - g_pred|^2 / (2 sigma^2))``, ``P0 = 1 - P1`` (Eqs. 4.23-4.24);
5. decide with the quality-weighted Chair-Varshney statistic (Eq. 4.13, see
   :func:`quality_weighted_statistic`): ``G1`` (object real) when ``Y > 0``;
6. on ``G1`` every camera's local position becomes ``G_j^-1 g`` (misses recovered, deviated
   detections corrected); on ``G0`` every detection is deleted and the state coasts.

The baseline without quality or prior is the Chair-Varshney rule (Eq. 4.3).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..core.errors import ConfigError, ShapeError, check_probability, invalid
from ..sensors.camera_geometry import apply_homography

Array = np.ndarray

QUALITY_TERMS = ("logW", "logit")


def _log(x: ArrayLike, base: float) -> Array:
    with np.errstate(divide="ignore"):
        return np.log(np.asarray(x, dtype=float)) / math.log(base)


def _rates(p_miss: ArrayLike, p_false: ArrayLike, n: int) -> tuple[Array, Array]:
    pm = np.broadcast_to(np.asarray(p_miss, dtype=float), (n,))
    pf = np.broadcast_to(np.asarray(p_false, dtype=float), (n,))
    for name, v in (("p_miss", pm), ("p_false", pf)):
        if np.any((v <= 0) | (v >= 1)):
            raise ConfigError(invalid(name, v.tolist(), "probabilities strictly between 0 and 1"))
    return pm, pf


def chair_varshney(
    p1: float, detected: ArrayLike, p_miss: ArrayLike, p_false: ArrayLike, base: float = 10.0
) -> float:
    """``Y = log(P1/P0) + sum_E1 log((1-PM)/PF) + sum_E0 log(PM/(1-PF))`` (Lee 2009, Eq. 4.3)."""
    det = np.asarray(detected, dtype=bool)
    pm, pf = _rates(p_miss, p_false, det.size)
    check_probability("p1", p1)
    y = _log(p1, base) - _log(1.0 - p1, base)
    y = (
        y
        + np.sum(_log((1 - pm[det]) / pf[det], base))
        + np.sum(_log(pm[~det] / (1 - pf[~det]), base))
    )
    return float(y)


def quality_weighted_statistic(
    p1: ArrayLike,
    detected: ArrayLike,
    quality: ArrayLike,
    p_miss: ArrayLike,
    p_false: ArrayLike,
    *,
    quality_term: str = "logW",
    base: float = 10.0,
) -> Array:
    """The quality-weighted decision statistic (Lee 2009, Eqs. 4.9-4.13); ``Y > 0`` decides G1.

    ``Y = log(P1/P0) + sum_E0 log(PM/(1-PF)) + sum_E1 log((1-PM)/PF) + sum_E1 q(W^j)``.
    The text prints ``q(W) = log(W/(1-W))`` (``quality_term="logit"``) and ``(1 - P_F)`` in the
    detecting cameras' numerator (a slip for ``1 - P_M``; equal when ``P_M = P_F``), but every
    case-study number it prints follows from ``q(W) = log10(W)`` (``"logW"``, the default).
    ``p1``, ``detected`` ``(..., J)`` and ``quality`` ``(..., J)`` broadcast over leading axes
    (Monte Carlo trials); ``quality`` of non-detecting cameras is ignored.
    """
    if quality_term not in QUALITY_TERMS:
        raise ConfigError(invalid("quality_term", quality_term, f"one of {QUALITY_TERMS}"))
    det = np.asarray(detected, dtype=bool)
    w = np.asarray(quality, dtype=float)
    if w.shape[-1:] != det.shape[-1:]:
        raise ShapeError(invalid("quality.shape", w.shape, f"(..., {det.shape[-1]}) like detected"))
    if np.any((w < 0) | (w > 1)):
        raise ConfigError(invalid("quality", "values outside [0, 1]", "qualities in [0, 1]"))
    pm, pf = _rates(p_miss, p_false, det.shape[-1])
    p = np.asarray(p1, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        y = _log(p, base) - _log(1.0 - p, base)
        y = y + np.sum(np.where(det, _log((1 - pm) / pf, base), _log(pm / (1 - pf), base)), -1)
        q = _log(w, base) if quality_term == "logW" else _log(w, base) - _log(1.0 - w, base)
        y = y + np.sum(np.where(det, q, 0.0), axis=-1)
    return np.asarray(y)


def quality(g_cameras: ArrayLike, g_pred: ArrayLike, sigma2: float) -> Array:
    """``W^j = exp(-|g^j - g_pred|^2 / (2 sigma^2))`` (Lee 2009, Eq. 4.20), ``(..., J)``: the
    :func:`presence_prior` kernel of every camera's position."""
    return presence_prior(g_cameras, np.asarray(g_pred, float)[..., None, :], sigma2)


def fused_position(g_cameras: ArrayLike, w: ArrayLike) -> Array:
    """``sum_j W^j g^j / sum_j W^j`` (Lee 2009, Eq. 4.22); plain mean if every weight is 0."""
    g = np.asarray(g_cameras, float)
    ww = np.asarray(w, float)
    tot = ww.sum(axis=-1, keepdims=True)
    safe = np.where(tot > 0, ww / np.where(tot > 0, tot, 1.0), 1.0 / ww.shape[-1])
    return np.einsum("...j,...jk->...k", safe, g)


def presence_prior(g: ArrayLike, g_pred: ArrayLike, sigma2: float) -> Array:
    """``P1 = exp(-|g - g_pred|^2 / (2 sigma^2))`` (Lee 2009, Eqs. 4.23-4.24)."""
    d = np.asarray(g, float) - np.asarray(g_pred, float)
    return np.exp(-np.sum(d * d, axis=-1) / (2.0 * sigma2))


def to_ground(homography: ArrayLike, local: ArrayLike) -> Array:
    """Image point(s) ``(..., 2)`` to the ground plane with a 3x3 homography
    (:func:`~fusetrack.sensors.camera_geometry.apply_homography`)."""
    return apply_homography(homography, local)


def to_image(homography: ArrayLike, ground: ArrayLike) -> Array:
    """Ground point(s) back into a camera's image: ``G^-1 g``."""
    return to_ground(np.linalg.inv(np.asarray(homography, float)), ground)


@dataclass(frozen=True)
class FrameDecision:
    """What the fusion decided at one frame."""

    real: bool  # G1
    statistic: float  # Y
    prior: float  # P1
    fused: Array  # fused ground position (NaN if nobody detected)
    quality: Array  # (J,) W^j (0 for non-detecting cameras)
    state: Array  # [g_x, g_vx, g_y, g_vy] after the frame
    local: list[Array | None]  # per camera: recovered/corrected image position, or None


@dataclass
class DetectionFusion:
    """Per-frame quality-weighted fusion over cameras with homographies (Lee 2009, Sec. 4.3).

    ``sigma2`` is the ``sigma^2`` of Eqs. 4.20 and 4.23 (ground units squared). The state starts
    at the first frame with detections (fused position, zero velocity, ``P1 = 0.5``); frames
    without any detection or decided false coast on the prediction.
    """

    homographies: list[Array]
    p_miss: float = 0.2
    p_false: float = 0.2
    sigma2: float = 1.0
    quality_term: str = "logW"
    use_prior: bool = True
    use_quality: bool = True
    state: Array | None = None

    def reset(self) -> None:
        self.state = None

    def predicted(self) -> Array | None:
        if self.state is None:
            return None
        gx, vx, gy, vy = self.state
        return np.array([gx + vx, gy + vy])  # Lee 2009, Eq. 4.19 with T = 1 frame

    def step(self, detections: list[ArrayLike | None]) -> FrameDecision:
        """Fuse one frame: ``detections[j]`` is camera j's image position or None (no detection)."""
        n_cam = len(self.homographies)
        if len(detections) != n_cam:
            raise ShapeError(
                invalid("detections", len(detections), f"{n_cam} entries (one per camera)")
            )
        det = np.array([d is not None for d in detections])
        g_pred = self.predicted()
        if not det.any():
            state = self._coast(g_pred)
            return FrameDecision(
                False, -math.inf, 0.0, np.full(2, np.nan), np.zeros(n_cam), state, [None] * n_cam
            )
        g_cams = np.array(
            [
                to_ground(h, d) if d is not None else (np.nan, np.nan)
                for h, d in zip(self.homographies, detections)
            ],
            dtype=float,
        )
        if not np.all(np.isfinite(g_cams[det])):
            raise ShapeError(
                invalid("detections", "non-finite image position", "finite (u, v) or None")
            )
        if g_pred is None:
            w = np.where(det, 1.0, 0.0)
            g = g_cams[det].mean(axis=0)
            p1 = 0.5
        else:
            w = np.where(det, quality(np.nan_to_num(g_cams), g_pred, self.sigma2), 0.0)
            g = fused_position(g_cams[det], w[det]) if self.use_quality else g_cams[det].mean(0)
            p1 = float(presence_prior(g, g_pred, self.sigma2)) if self.use_prior else 0.5
        p1 = min(max(p1, 1e-300), 1.0 - 1e-16)
        if self.use_quality:
            y = float(
                quality_weighted_statistic(
                    p1,
                    det,
                    np.clip(w, 0, 1),
                    self.p_miss,
                    self.p_false,
                    quality_term=self.quality_term,
                )
            )
        else:
            y = chair_varshney(p1, det, self.p_miss, self.p_false)
        if y > 0:
            prev = self.state
            vx, vy = (0.0, 0.0) if prev is None else (g[0] - prev[0], g[1] - prev[2])
            self.state = np.array([g[0], vx, g[1], vy])
            local: list[Array | None] = [to_image(h, g) for h in self.homographies]
            return FrameDecision(True, y, p1, g, w, self.state.copy(), local)
        state = self._coast(g_pred)
        return FrameDecision(False, y, p1, g, w, state, [None] * n_cam)

    def _coast(self, g_pred: Array | None) -> Array:
        if self.state is None or g_pred is None:
            return np.full(4, np.nan)
        self.state = np.array([g_pred[0], self.state[1], g_pred[1], self.state[3]])
        return self.state.copy()
