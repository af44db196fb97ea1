"""How likely moving occluders hide an object from cameras (Ercan et al. 2013, Secs. 4.2-4.3, App. C).

A moving occluder is a disc of diameter ``D`` whose centre is known only through a Gaussian prior
``N(mu_j, Sigma_j)``. It hides a point ``x`` from camera ``i`` when its centre falls in the
rectangle ``A_i(x)`` of width ``D`` that runs from the camera to ``x`` (the paper's rectangle
approximation of the disc sweeping the line of sight). Its probability ``q_ij(x)`` has the closed
form of Eq. 7; :func:`occlusion_probability` evaluates the equivalent frame-free form

    m_a = u' P m / u' P u,   s_a = (u' P u)^(-1/2)      (along the ray, conditional on the ray)
    phi = n' m,              s_p = (n' Sigma n)^(1/2)   (across the ray, marginal)
    q ~= [Phi((r - m_a)/s_a) - Phi(-m_a/s_a)] [Phi((D/2 - phi)/s_p) - Phi((-D/2 - phi)/s_p)]

(``r = |x - c|``, ``u`` the unit ray, ``n`` its normal, ``m = mu - c``, ``P = Sigma^-1``), which is
Eq. 7 written without rotating into the prior's eigenframe (the test suite checks the two agree to
rounding error); :func:`occlusion_probability_eq7` is Eq. 7 exactly as printed, for reference.

With several cameras and occluders (Eq. 8, occluders independent, rectangles nearly disjoint):

    P(all of Q see x) ~= prod_j (1 - sum_{i in Q} q_ij(x))

and a pattern ``eta`` (1 = sees, 0 = occluded) follows by inclusion-exclusion (the closed form of
the recursion Eq. 9): ``p(eta) = sum_{B subset O} (-1)^|B| p_{V u B}`` with ``V`` the cameras that
see and ``O`` those occluded. Factors are clamped to [0, 1] (spec §8 item 8).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import erf, ndtr

from ..core import ConfigError, ShapeError, check_points, invalid
from .geometry import Array, segment_point_distance
from .occlusion_kernels import (
    disks_block_kernel,
    occlusion_probability_kernel,
    pattern_probability_kernel,
)

MIN_PRIOR_VARIANCE = 1e-9
"""Eigenvalues of an occluder prior covariance are floored here: a singular (point or line)
prior is treated as a very sharp Gaussian, so probabilities stay finite (never NaN)."""


@dataclass(frozen=True)
class OccluderPriors:
    """Gaussian priors of M moving occluders: ``mean (M, 2)``, ``cov (M, 2, 2)``.

    Covariances must be symmetric with no negative eigenvalue; singular ones are regularised
    (eigenvalues floored at :data:`MIN_PRIOR_VARIANCE`).
    """

    mean: Array
    cov: Array

    def __post_init__(self) -> None:
        mu = np.asarray(self.mean, float).reshape(-1, 2) if np.size(self.mean) else np.zeros((0, 2))
        cov = np.asarray(self.cov, float)
        if cov.size == 0:
            cov = np.zeros((0, 2, 2))
        if cov.ndim == 2 and cov.shape == (2, 2):
            cov = np.broadcast_to(cov, (len(mu), 2, 2)).copy()
        if cov.shape != (len(mu), 2, 2):
            raise ShapeError(invalid("occluder cov.shape", cov.shape, f"({len(mu)}, 2, 2)"))
        if not (np.all(np.isfinite(mu)) and np.all(np.isfinite(cov))):
            raise ConfigError(
                invalid("occluder priors", "non-finite", "finite means and covariances")
            )
        diagonal = bool(np.all(cov[:, 0, 1] == 0) and np.all(cov[:, 1, 0] == 0))
        if not diagonal and not np.allclose(cov, np.swapaxes(cov, -1, -2), atol=1e-9):
            raise ConfigError(invalid("occluder cov", cov.tolist(), "symmetric 2x2 matrices"))
        if len(mu) and diagonal and np.all(cov[:, [0, 1], [0, 1]] >= MIN_PRIOR_VARIANCE):
            pass  # already valid (the Kalman priors): keep it exactly, so kernels see it isotropic
        elif len(mu):
            vals, vecs = np.linalg.eigh(cov)
            scale = np.maximum(1.0, np.abs(vals).max(axis=-1, keepdims=True))
            if np.any(vals < -1e-9 * scale):
                bad = int(np.argmin(vals.min(axis=-1)))
                raise ConfigError(
                    invalid(
                        f"occluder cov[{bad}]", cov[bad].tolist(), "a positive semi-definite matrix"
                    )
                )
            vals = np.maximum(vals, MIN_PRIOR_VARIANCE)
            cov = np.einsum("mij,mj,mkj->mik", vecs, vals, vecs)
        object.__setattr__(self, "mean", mu)
        object.__setattr__(self, "cov", cov)

    @classmethod
    def isotropic(cls, mean: ArrayLike, var: float) -> OccluderPriors:
        """Priors ``N(mean_j, var I)`` for every occluder (the Kalman priors of
        :mod:`~fusetrack.world.occluder_priors`): the same object as ``OccluderPriors(mean,
        var * I)``, with only one variance to check (a tracker builds one per step)."""
        if not (np.isfinite(var) and var >= MIN_PRIOR_VARIANCE) or not np.size(mean):
            return cls(np.asarray(mean, float), float(var) * np.eye(2))  # the general checks
        mu = check_points("occluder priors' means", mean)
        cov = np.zeros((len(mu), 2, 2))
        cov[:, 0, 0] = var
        cov[:, 1, 1] = var
        priors = object.__new__(cls)
        object.__setattr__(priors, "mean", mu)
        object.__setattr__(priors, "cov", cov)
        return priors

    def __len__(self) -> int:
        return len(self.mean)


def occlusion_probability(
    viewers: ArrayLike,
    points: ArrayLike,
    priors: OccluderPriors,
    diameter: float,
    exclusion: float = 0.0,
) -> Array:
    """``q[i, l, j]``: probability that occluder ``j`` hides ``points[l]`` from ``viewers[i]``.

    ``viewers (K, 2)``, ``points (L, 2)``; returns ``(K, L, M)``. Frame-free form of
    Ercan et al. 2013, Eq. 7 (see the module docstring); Numba kernel, values below 1e-12 set
    to 0 (:func:`occlusion_probability_reference` is the NumPy reference). ``exclusion``: the
    rectangle ``A_i(x)`` ends this far before the point (0: Eq. 7 as printed); the same
    per-triple function as the fused likelihood kernel, so camera selection and the likelihood
    agree for the same option.
    """
    if not 0 <= exclusion < np.inf:
        raise ConfigError(invalid("exclusion", exclusion, "a finite length >= 0"))
    c, x = check_points("viewers", viewers), check_points("points", points)
    return np.asarray(
        occlusion_probability_kernel(
            c, x, priors.mean, np.ascontiguousarray(priors.cov), float(diameter), float(exclusion)
        )
    )


def occlusion_probability_reference(
    viewers: ArrayLike,
    points: ArrayLike,
    priors: OccluderPriors,
    diameter: float,
    exclusion: float = 0.0,
) -> Array:
    """NumPy reference of :func:`occlusion_probability` (every triple evaluated).

    ``exclusion``: the rectangle ``A_i(x)`` ends this far before the point (0: Eq. 7 as printed;
    see :class:`fusetrack.sensors.occlusion_aware_camera.OcclusionAwareLikelihood`).
    """
    c = np.asarray(viewers, float).reshape(-1, 2)
    x = np.asarray(points, float).reshape(-1, 2)
    mu, cov = priors.mean, priors.cov
    K, L, M = len(c), len(x), len(mu)
    if M == 0:
        return np.zeros((K, L, 0))
    rel = x[None, :, :] - c[:, None, :]  # (K, L, 2)
    r = np.hypot(rel[..., 0], rel[..., 1])
    safe = np.where(r > 0, r, 1.0)
    u1 = (rel[..., 0] / safe)[..., None]  # (K, L, 1)
    u2 = (rel[..., 1] / safe)[..., None]
    det = cov[:, 0, 0] * cov[:, 1, 1] - cov[:, 0, 1] ** 2
    p11, p12, p22 = cov[:, 1, 1] / det, -cov[:, 0, 1] / det, cov[:, 0, 0] / det
    m = mu[None, :, :] - c[:, None, :]  # (K, M, 2)
    pm1 = (p11 * m[..., 0] + p12 * m[..., 1])[:, None, :]  # (K, 1, M)
    pm2 = (p12 * m[..., 0] + p22 * m[..., 1])[:, None, :]
    a = p11 * u1 * u1 + 2 * p12 * u1 * u2 + p22 * u2 * u2  # u'Pu, (K, L, M)
    s_a = 1.0 / np.sqrt(a)
    m_a = (u1 * pm1 + u2 * pm2) / a
    phi = -u2 * m[:, None, :, 0] + u1 * m[:, None, :, 1]
    s_p = np.sqrt(cov[:, 0, 0] * u2 * u2 - 2 * cov[:, 0, 1] * u1 * u2 + cov[:, 1, 1] * u1 * u1)
    r_eff = np.maximum(r - float(exclusion), 0.0)[..., None]
    along = np.where(r_eff > 0, ndtr((r_eff - m_a) / s_a) - ndtr(-m_a / s_a), 0.0)
    half = 0.5 * float(diameter)
    across = ndtr((half - phi) / s_p) - ndtr((-half - phi) / s_p)
    return np.asarray(np.clip(along * across, 0.0, 1.0))


def occlusion_probability_eq7(
    viewer: ArrayLike, point: ArrayLike, mean: ArrayLike, cov: ArrayLike, diameter: float
) -> float:
    """Ercan et al. 2013, Eq. 7 exactly as printed, for one camera, point and occluder.

    The frame: camera at the origin, axes rotated so the prior's major axis is horizontal,
    ``Sigma = diag(sigma^2, sigma^2 / alpha)``.
    """
    c, x, mu = (np.asarray(v, float) for v in (viewer, point, mean))
    vals, vecs = np.linalg.eigh(np.asarray(cov, float))
    major, minor = vecs[:, 1], vecs[:, 0]
    rot = np.array([major, minor])  # rows: new axes
    xp, mup = rot @ (x - c), rot @ (mu - c)
    sigma2, alpha = vals[1], vals[1] / vals[0]
    theta = np.arctan2(xp[1], xp[0])
    norm_x = float(np.hypot(*xp))
    o1 = np.array([np.cos(theta), alpha * np.sin(theta)])
    g1 = np.array([np.cos(theta), np.sqrt(alpha) * np.sin(theta)])
    g1p = np.sqrt(2 * sigma2) * np.linalg.norm(g1)
    phi = np.array([-np.sin(theta), np.cos(theta)]) @ mup
    half = diameter / 2
    across = erf(np.sqrt(alpha) / g1p * (half - phi)) + erf(np.sqrt(alpha) / g1p * (half + phi))
    along = erf((norm_x * (g1 @ g1) - mup @ o1) / g1p) + erf((mup @ o1) / g1p)
    return float(0.25 * across * along)


def occlusion_probability_mc(
    viewer: ArrayLike,
    point: ArrayLike,
    mean: ArrayLike,
    cov: ArrayLike,
    diameter: float,
    n: int,
    rng: np.random.Generator,
    shape: str = "rectangle",
) -> float:
    """Monte Carlo estimate of ``q``: the fraction of ``n`` prior draws that hide the point.

    ``shape="rectangle"``: centre inside ``A_i(x)`` (what Eq. 7 integrates);
    ``shape="disk"``: the disc of diameter D touches the segment (the physical occlusion).
    """
    c, x = np.asarray(viewer, float), np.asarray(point, float)
    draws = rng.multivariate_normal(np.asarray(mean, float), np.asarray(cov, float), size=n)
    if shape == "disk":
        return float(np.mean(segment_point_distance(c, x, draws) < diameter / 2))
    if shape != "rectangle":
        raise ConfigError(invalid("shape", shape, "'rectangle' or 'disk'"))
    ray = x - c
    r = float(np.hypot(*ray))
    u = ray / r
    rel = draws - c
    along = rel @ u
    across = rel @ np.array([-u[1], u[0]])
    return float(np.mean((along >= 0) & (along <= r) & (np.abs(across) <= diameter / 2)))


def disks_block(
    viewers: ArrayLike, points: ArrayLike, centers: ArrayLike, diameter: float
) -> NDArray[np.bool_]:
    """``(K, L)``: does any disc (centres ``(M, 2)``, diameter D) touch segment viewer -> point?"""
    c, x = check_points("viewers", viewers), check_points("points", points)
    o = check_points("centers", centers)
    return np.asarray(disks_block_kernel(c, x, o, float(diameter)))


def disks_block_reference(
    viewers: ArrayLike, points: ArrayLike, centers: ArrayLike, diameter: float
) -> NDArray[np.bool_]:
    """NumPy reference of :func:`disks_block`."""
    c = np.asarray(viewers, float).reshape(-1, 2)
    x = np.asarray(points, float).reshape(-1, 2)
    o = np.asarray(centers, float).reshape(-1, 2)
    if len(o) == 0:
        return np.zeros((len(c), len(x)), dtype=bool)
    out = np.zeros((len(c), len(x)), dtype=bool)
    for i in range(len(c)):  # one camera at a time keeps the (L, M) temporaries small
        dist = segment_point_distance(c[i], x[:, None, :], o[None, :, :])
        out[i] = np.any(dist < diameter / 2, axis=-1)
    return out


def all_visible_probability(q: Array, cameras: NDArray[np.bool_] | None = None) -> Array:
    """``p_Q(x) ~= prod_j clamp(1 - sum_{i in Q} q_ij(x))`` (Ercan et al. 2013, Eq. 8).

    ``q (K, L, M)``; ``cameras`` a boolean ``(K,)`` choosing Q (default: all). Returns ``(L,)``.
    """
    qq = q if cameras is None else q[np.asarray(cameras, bool)]
    s = qq.sum(axis=0)
    return np.asarray(np.prod(np.clip(1.0 - s, 0.0, 1.0), axis=-1))


def pattern_probability(
    q: Array, eta: ArrayLike, assigned: NDArray[np.bool_] | None = None, clamp: bool = True
) -> Array:
    """``p(eta | u)`` for each particle: Ercan et al. 2013, Eq. 9 with the partition of Sec. 4.3.

    ``q (K, L, M)`` for the K queried cameras; ``eta (K,)`` booleans (True = the camera sees the
    object); ``assigned (K, L)``: camera i's field of view contains particle l and no static
    occluder or wall blocks it (default: all True). A particle is impossible (probability 0)
    when a camera that is not assigned to it claims to see it; the cameras not assigned to a
    particle are deterministically occluded and drop out. Then, with V the cameras that see and
    O the assigned cameras that do not,

        p = sum_{B subset O} (-1)^|B| prod_j clamp(1 - sum_{i in V u B} q_ij)

    (the closed form of the recursion Eq. 9). The result is clamped to [0, 1] (spec §8 item 8);
    with ``clamp=False`` it is returned as computed, and then sums to exactly 1 over all 2^K
    patterns (the inclusion-exclusion identity; the approximations of Eq. 8 can make single
    patterns slightly negative, which clamping removes at the price of that identity). Numba kernel; :func:`pattern_probability_reference` is the NumPy reference.
    """
    eta = np.asarray(eta, bool)
    K, L = q.shape[0], q.shape[1]
    if eta.shape != (K,):
        raise ShapeError(invalid("eta.shape", eta.shape, f"({K},)"))
    A = np.ones((K, L), dtype=bool) if assigned is None else np.asarray(assigned, bool)
    return np.asarray(
        pattern_probability_kernel(
            np.ascontiguousarray(q, dtype=float), eta, np.ascontiguousarray(A), clamp
        )
    )


def pattern_probability_reference(
    q: Array, eta: ArrayLike, assigned: NDArray[np.bool_] | None = None, clamp: bool = True
) -> Array:
    """NumPy reference of :func:`pattern_probability` (loops over subsets, vectorised over particles)."""
    eta = np.asarray(eta, bool)
    K, L = q.shape[0], q.shape[1]
    if eta.shape != (K,):
        raise ShapeError(invalid("eta.shape", eta.shape, f"({K},)"))
    A = np.ones((K, L), dtype=bool) if assigned is None else np.asarray(assigned, bool)
    possible = ~np.any(eta[:, None] & ~A, axis=0)
    s_v = q[eta].sum(axis=0)  # (L, M)
    zeros = np.flatnonzero(~eta)
    p = np.zeros(L)
    for size in range(len(zeros) + 1):
        sign = -1.0 if size % 2 else 1.0
        for subset in itertools.combinations(zeros, size):
            idx = list(subset)
            mask = possible & np.all(A[idx], axis=0) if idx else possible
            if not mask.any():
                continue
            s = s_v[mask] + q[idx][:, mask].sum(axis=0) if idx else s_v[mask]
            p[mask] += sign * np.prod(np.clip(1.0 - s, 0.0, 1.0), axis=-1)
    return np.asarray(np.clip(p, 0.0, 1.0)) if clamp else p
