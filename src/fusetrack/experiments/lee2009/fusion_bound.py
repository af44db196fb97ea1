"""What no method can beat on lee2009-detection-fusion's synthetic sequence (issue 19, item 3):
the posterior mean of the object's ground position, beside the sequence table.

**Model** (:func:`~fusetrack.experiments.lee2009.detection_fusion.run_sequence`). The object
starts at a known point and moves ``x_n = x_{n-1} + v + w_n``, ``w_n ~ N(0, s_w^2 I)`` (known
drift ``v``); camera ``j`` detects it with probability ``1 - P_M`` at the image point
``l = G_j^-1 x_n + e``, ``e ~ N(0, s_px^2 I)``, and while the object is present a detection is
never false. Mapped to the ground (Eq. 4.22's inputs), ``g = G_j l = x_n + J_j e + O(e^2)`` with
``J_j`` the homography's Jacobian at the detection (:func:`homography_jacobian`): to first order
a position fix with covariance ``R_j = s_px^2 J_j J_j^T`` (:func:`ground_detection`); the
second-order term (``s_px^2`` times the homography's curvature) biases a fix by less than 1e-4 m
along the sequence's path, against some 0.04 m of noise.

**Bounds.** On that linear-Gaussian model the Kalman filter from the known start
(:func:`posterior_track`) is the posterior mean ``E[x_n | g_1..n]``; its error is ``N(0, P_n)``
and independent of the detections, so on any frames chosen from the detections (the frames a
method accepted) its mean Euclidean error is the mean of ``E|N(0, P_n)|``
(:func:`~fusetrack.evaluation.expected_norm`), and no estimator that sees the same detections
has a smaller expected Euclidean error at any frame (the posterior is Gaussian, so its mean
minimises every symmetric convex loss: Anderson's lemma). An estimator that uses one frame's
detections alone, as Eq. 4.22 combines them, can at best weight them by their information
(:func:`frame_fusion`, the CRLB of one frame): a reference for the weights of Eq. 4.22, not a
bound on the method, whose weights also use the prediction.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from ...core import ConfigError, Gaussian, Measurement, invalid
from ...evaluation import expected_norm
from ...filters import KalmanFilter
from ...motion import LinearGaussianMotion
from ...sensors import PositionFix, apply_homography

Array = np.ndarray
Frame = tuple[Array, Array]
"""One frame's ground detections ``(k, 2)`` and their covariances ``(k, 2, 2)`` (``k`` may be 0)."""


def homography_jacobian(homography: ArrayLike, uv: ArrayLike) -> Array:
    """``d pi(H [u, v, 1]) / d(u, v)`` ``(..., 2, 2)`` at points ``uv`` ``(..., 2)``:
    ``(H[:2, :2] - p H[2, :2]) / w`` with ``p`` the mapped point and ``w`` its third coordinate."""
    h = np.asarray(homography, float)
    x = np.asarray(uv, float)
    w = x @ h[2, :2] + h[2, 2]
    p = apply_homography(h, x)
    return np.asarray((h[:2, :2] - p[..., :, None] * h[2, :2]) / w[..., None, None])


def ground_detection(homography: ArrayLike, uv: ArrayLike, pixel_sigma: float) -> Frame:
    """An image detection ``uv`` ``(..., 2)`` with ``N(0, pixel_sigma^2 I)`` noise as a ground
    fix: ``(G uv, pixel_sigma^2 J J^T)`` (first order, module docstring)."""
    if not pixel_sigma > 0:
        raise ConfigError(invalid("pixel_sigma", pixel_sigma, "an image noise > 0 (pixels)"))
    j = homography_jacobian(homography, uv)
    return apply_homography(homography, uv), pixel_sigma**2 * j @ np.swapaxes(j, -1, -2)


def frame_fusion(ground: ArrayLike, covs: ArrayLike) -> Frame:
    """One frame's fixes ``(k, 2)`` with covariances ``(k, 2, 2)`` fused by their information:
    ``P = (sum R_j^-1)^-1``, ``x = P sum R_j^-1 g_j`` (the best unbiased combination, its
    covariance the CRLB of the frame); NaN for ``k = 0``."""
    g, r = np.asarray(ground, float), np.asarray(covs, float)
    if len(g) == 0:
        return np.full(2, np.nan), np.full((2, 2), np.nan)
    info = np.linalg.inv(r)
    cov = np.linalg.inv(info.sum(axis=0))
    return cov @ np.einsum("kij,kj->i", info, g), cov


def posterior_track(
    frames: Sequence[Frame], start: ArrayLike, drift: ArrayLike, step_sigma: float
) -> tuple[Array, Array]:
    """Posterior means ``(T, 2)`` and covariances ``(T, 2, 2)`` of ``x_n`` given the fixes of
    frames ``0..n``, from the known ``x_-1 = start`` with ``x_n = x_{n-1} + drift + N(0,
    step_sigma^2 I)``: the Kalman filter on the state ``[x, y, 1]`` (the constant carries the
    drift)."""
    if not step_sigma > 0:
        raise ConfigError(invalid("step_sigma", step_sigma, "a per-frame motion noise > 0"))
    d = np.asarray(drift, float)
    motion = LinearGaussianMotion(
        F=[[1.0, 0.0, d[0]], [0.0, 1.0, d[1]], [0.0, 0.0, 1.0]],
        Q=np.diag([step_sigma**2, step_sigma**2, 0.0]),
    )
    kf = KalmanFilter(motion, [PositionFix("ground", cov=np.eye(2))])
    belief = Gaussian(np.array([*np.asarray(start, float), 1.0]), np.zeros((3, 3)))
    means, covs = [], []
    for n, (g, r) in enumerate(frames):
        belief = kf.predict(belief, 1.0)
        fixes = [Measurement(float(n), "ground", gi, covariance=ri) for gi, ri in zip(g, r)]
        if fixes:
            belief = kf.update(belief, fixes)
        means.append(belief.mean[:2])
        covs.append(belief.cov[:2, :2])
    return np.array(means), np.array(covs)


def block_se(values: ArrayLike, block: int = 10) -> float:
    """Standard error of the mean of a serially correlated series: the spread of the means of
    consecutive blocks of ``block`` values (batch means; the last partial block dropped), NaN
    with fewer than two blocks."""
    v = np.asarray(values, float)
    n = len(v) // block
    if n < 2:
        return float("nan")
    means = v[: n * block].reshape(n, block).mean(axis=1)
    return float(np.std(means, ddof=1) / np.sqrt(n))


def mean_error_bound(covs: ArrayLike) -> Array:
    """``E|e|`` per frame for ``e ~ N(0, P_n)``: the posterior mean's expected Euclidean error."""
    return np.asarray(expected_norm(np.asarray(covs, float)))


__all__ = [
    "Frame",
    "block_se",
    "frame_fusion",
    "ground_detection",
    "homography_jacobian",
    "mean_error_bound",
    "posterior_track",
]
