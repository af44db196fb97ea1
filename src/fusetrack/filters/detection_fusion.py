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
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike

from ..core import ConfigError, Measurement, ShapeError, check_probability, invalid
from ..sensors import GroundPlaneDetection, apply_homography

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


@dataclass(frozen=True, eq=False)
class FusionBelief:
    """What :class:`DetectionFusion` carries from frame to frame.

    ``state`` is ``[g_x, g_vx, g_y, g_vy]`` (None before the first frame with detections);
    ``anchor`` the ground position of the frame before the last prediction (the fused velocity
    is ``g - anchor``); ``decision`` the last frame's :class:`FrameDecision`. ``mean`` is the
    ground position; ``cov`` the ``sigma^2 I`` of the presence kernel (Eq. 4.23), the only
    spread the method models.
    """

    state: Array | None = None
    anchor: Array | None = None
    decision: FrameDecision | None = None
    sigma2: float = 1.0

    @property
    def mean(self) -> Array:
        if self.state is None:
            return np.full(2, np.nan)
        return np.array([self.state[0], self.state[2]])

    @property
    def cov(self) -> Array:
        return self.sigma2 * np.eye(2)


def frame_measurements(
    time: float, detections: Sequence[ArrayLike | None], camera_ids: Sequence[str]
) -> list[Measurement]:
    """One frame's detections as measurements: camera ``j``'s image position ``(u, v)`` from
    sensor ``camera_ids[j]``; a camera that detected nothing (None) sends none."""
    if len(detections) != len(camera_ids):
        raise ShapeError(
            invalid("detections", len(detections), f"{len(camera_ids)} entries (one per camera)")
        )
    return [
        Measurement(time, cid, np.asarray(d, float))
        for cid, d in zip(camera_ids, detections)
        if d is not None
    ]


@dataclass(frozen=True)
class DetectionFusion:
    """Per-frame quality-weighted fusion over cameras with homographies (Lee 2009, Sec. 4.3), a
    :class:`~fusetrack.core.models.Filter` over :class:`FusionBelief`.

    ``predict`` moves the state by ``dt`` frames (Eq. 4.19); ``update`` takes the frame's image
    detections (``Measurement`` from sensor ``camera_ids[j]``, value ``(u, v)``; a camera without
    a measurement did not detect) and decides. ``sigma2`` is the ``sigma^2`` of Eqs. 4.20 and
    4.23 (ground units squared). The state starts at the first frame with detections (fused
    position, zero velocity, ``P1 = 0.5``); frames without any detection or decided false coast
    on the prediction. Call ``update`` every frame, also with no measurement: that no camera
    detected is evidence (every camera in ``E0``).
    """

    homographies: Sequence[Array]
    p_miss: float = 0.2
    p_false: float = 0.2
    sigma2: float = 1.0
    quality_term: str = "logW"
    use_prior: bool = True
    use_quality: bool = True
    camera_ids: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not self.camera_ids:
            ids = tuple(f"camera{j}" for j in range(len(self.homographies)))
            object.__setattr__(self, "camera_ids", ids)
        if len(self.camera_ids) != len(self.homographies):
            raise ConfigError(
                invalid("camera_ids", self.camera_ids, f"{len(self.homographies)} ids")
            )

    @property
    def sensors(self) -> list[GroundPlaneDetection]:
        """Each camera as a sensor model: its homography and the quality kernel (Eq. 4.20)."""
        return [
            GroundPlaneDetection(cid, np.asarray(h, float), self.sigma2)
            for cid, h in zip(self.camera_ids, self.homographies)
        ]

    def initial_belief(self) -> FusionBelief:
        return FusionBelief(sigma2=self.sigma2)

    def predict(
        self, belief: FusionBelief, dt: float = 1.0, rng: np.random.Generator | None = None
    ) -> FusionBelief:
        """Constant velocity over ``dt`` frames (Lee 2009, Eq. 4.19)."""
        if belief.state is None:
            return belief
        gx, vx, gy, vy = belief.state
        state = np.array([gx + vx * dt, vx, gy + vy * dt, vy])
        return replace(belief, state=state, anchor=np.array([gx, gy]))

    def update(
        self,
        belief: FusionBelief,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> FusionBelief:
        """Fuse one frame's detections (module docstring, steps 2-6)."""
        detections: list[Array | None] = [None] * len(self.camera_ids)
        for m in measurements:
            if m.sensor_id not in self.camera_ids:
                raise ShapeError(invalid("sensor_id", m.sensor_id, f"one of {self.camera_ids}"))
            detections[self.camera_ids.index(m.sensor_id)] = m.value
        decision = self.decide(belief, detections)
        if decision.real:
            g = decision.fused
            prev = belief.anchor if belief.anchor is not None else belief.mean
            vx, vy = (0.0, 0.0) if belief.state is None else (g[0] - prev[0], g[1] - prev[1])
            state = np.array([g[0], vx, g[1], vy])
            decision = replace(decision, state=state.copy())
            return replace(belief, state=state, anchor=None, decision=decision)
        return replace(belief, anchor=None, decision=decision)

    def decide(self, belief: FusionBelief, detections: Sequence[ArrayLike | None]) -> FrameDecision:
        """The decision for one frame, ``detections[j]`` camera j's image position or None;
        ``belief`` holds the predicted state (``FrameDecision.state`` is the coasted state; on
        ``G1`` :meth:`update` replaces it with the fused one)."""
        n_cam = len(self.homographies)
        det = np.array([d is not None for d in detections])
        g_pred = None if belief.state is None else belief.mean
        coast = np.full(4, np.nan) if belief.state is None else belief.state.copy()
        if not det.any():
            return FrameDecision(
                False, -math.inf, 0.0, np.full(2, np.nan), np.zeros(n_cam), coast, [None] * n_cam
            )
        cams = self.sensors
        g_cams = np.array(
            [c.ground(d) if d is not None else (np.nan, np.nan) for c, d in zip(cams, detections)],
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
            w = np.array(
                [c.quality(d, g_pred) if d is not None else 0.0 for c, d in zip(cams, detections)]
            )
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
            local: list[Array | None] = [to_image(h, g) for h in self.homographies]
            return FrameDecision(True, y, p1, g, w, coast, local)
        return FrameDecision(False, y, p1, g, w, coast, [None] * n_cam)
