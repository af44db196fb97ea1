"""Numba kernels for the occlusion computations of :mod:`fusetrack.world.occlusion`.

Same formulas as the NumPy references there (the tests compare them), written as loops so that
(camera, particle, occluder) triples far from each other are skipped cheaply: an occluder whose
prior puts the ray more than ``CUTOFF`` = 5 standard deviations away contributes q = 0 (the
exact value is below 3e-7), as does a triple whose across-the-ray factor is below 1e-9; the
normal CDF is a table lookup with linear interpolation (error < 4e-8). This makes the likelihood
for L = 1000 particles, 8 cameras and 40 occluders take about a millisecond instead of tens.
"""

from __future__ import annotations

import math

import numba
import numpy as np

CUTOFF = 5.0
_SQRT1_2 = 1.0 / math.sqrt(2.0)


@numba.njit(cache=True, inline="always")
def _erfc(x: float) -> float:  # pragma: no cover - jit
    """erfc with fractional error < 1.2e-7 everywhere (Numerical Recipes ``erfcc``), one exp."""
    z = abs(x)
    t = 1.0 / (1.0 + 0.5 * z)
    r = t * math.exp(
        -z * z
        - 1.26551223
        + t
        * (
            1.00002368
            + t
            * (
                0.37409196
                + t
                * (
                    0.09678418
                    + t
                    * (
                        -0.18628806
                        + t
                        * (
                            0.27886807
                            + t
                            * (-1.13520398 + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277)))
                        )
                    )
                )
            )
        )
    )
    return r if x >= 0.0 else 2.0 - r


@numba.njit(cache=True, inline="always")
def _phi(t: float) -> float:  # pragma: no cover - jit
    return 0.5 * _erfc(-t * _SQRT1_2)


_TABLE_HALF_WIDTH = 8.5
_TABLE_SIZE = 1 << 14
_TABLE_STEP = 2 * _TABLE_HALF_WIDTH / (_TABLE_SIZE - 1)
_PHI_TABLE = np.array(
    [
        0.5 * math.erfc(-(-_TABLE_HALF_WIDTH + i * _TABLE_STEP) * _SQRT1_2)
        for i in range(_TABLE_SIZE)
    ]
)
"""Standard normal CDF on a grid over [-8.5, 8.5]; linear interpolation errs by < 2e-8."""


@numba.njit(cache=True, inline="always")
def _phi_fast(t: float) -> float:  # pragma: no cover - jit
    """Standard normal CDF by table lookup and linear interpolation (|error| < 2e-8)."""
    if t <= -_TABLE_HALF_WIDTH:
        return 0.0
    if t >= _TABLE_HALF_WIDTH:
        return 1.0
    pos = (t + _TABLE_HALF_WIDTH) / _TABLE_STEP
    k = int(pos)
    if k >= _TABLE_SIZE - 1:
        return 1.0
    frac = pos - k
    return _PHI_TABLE[k] + frac * (_PHI_TABLE[k + 1] - _PHI_TABLE[k])


@numba.njit(cache=True, nogil=True)
def occlusion_probability_kernel(
    cams: np.ndarray, x: np.ndarray, mu: np.ndarray, cov: np.ndarray, diameter: float
) -> np.ndarray:  # pragma: no cover - jit
    """q[i, l, j] of Ercan et al. 2013, Eq. 7 (frame-free form), with far triples skipped."""
    K, L, M = cams.shape[0], x.shape[0], mu.shape[0]
    out = np.zeros((K, L, M))
    half = 0.5 * diameter
    p11 = np.empty(M)
    p12 = np.empty(M)
    p22 = np.empty(M)
    for j in range(M):
        det = cov[j, 0, 0] * cov[j, 1, 1] - cov[j, 0, 1] * cov[j, 0, 1]
        p11[j] = cov[j, 1, 1] / det
        p12[j] = -cov[j, 0, 1] / det
        p22[j] = cov[j, 0, 0] / det
    iso = np.empty(M, dtype=np.bool_)
    inv_sd = np.empty(M)
    reach = np.empty(M)
    for j in range(M):
        iso[j] = cov[j, 0, 1] == 0.0 and cov[j, 0, 0] == cov[j, 1, 1]
        sd = math.sqrt(cov[j, 0, 0])
        inv_sd[j] = 1.0 / sd
        reach[j] = CUTOFF * sd
    m1 = np.empty(M)
    m2 = np.empty(M)
    pm1 = np.empty(M)
    pm2 = np.empty(M)
    for i in range(K):
        cx, cy = cams[i, 0], cams[i, 1]
        for j in range(M):
            m1[j] = mu[j, 0] - cx
            m2[j] = mu[j, 1] - cy
            pm1[j] = p11[j] * m1[j] + p12[j] * m2[j]
            pm2[j] = p12[j] * m1[j] + p22[j] * m2[j]
        for l in range(L):
            rx, ry = x[l, 0] - cx, x[l, 1] - cy
            r = math.sqrt(rx * rx + ry * ry)
            if r <= 0.0:
                continue
            u1, u2 = rx / r, ry / r
            for j in range(M):
                phi = -u2 * m1[j] + u1 * m2[j]
                if iso[j]:  # isotropic prior (the Kalman priors): both spreads are sqrt(var)
                    if abs(phi) - half > reach[j]:
                        continue
                    isp = inv_sd[j]
                    isa = inv_sd[j]
                    m_a = u1 * m1[j] + u2 * m2[j]
                else:
                    sp2 = (
                        cov[j, 0, 0] * u2 * u2
                        - 2.0 * cov[j, 0, 1] * u1 * u2
                        + cov[j, 1, 1] * u1 * u1
                    )
                    if (abs(phi) - half) ** 2 > CUTOFF * CUTOFF * sp2 and abs(phi) > half:
                        continue
                    isp = 1.0 / math.sqrt(sp2)
                    a = p11[j] * u1 * u1 + 2.0 * p12[j] * u1 * u2 + p22[j] * u2 * u2
                    isa = math.sqrt(a)
                    m_a = (u1 * pm1[j] + u2 * pm2[j]) / a
                across = _phi_fast((half - phi) * isp) - _phi_fast((-half - phi) * isp)
                if across < 1e-9:
                    continue
                along = _phi_fast((r - m_a) * isa) - _phi_fast(-m_a * isa)
                v = along * across
                out[i, l, j] = min(max(v, 0.0), 1.0)
    return out


@numba.njit(cache=True, nogil=True)
def pattern_probability_kernel(
    q: np.ndarray, eta: np.ndarray, assigned: np.ndarray, clamp: bool = True
) -> np.ndarray:  # pragma: no cover - jit
    """p(eta | u) per particle: Eq. 8 and the inclusion-exclusion of Eq. 9 on assigned cameras."""
    K, L, M = q.shape
    p = np.zeros(L)
    s_v = np.empty(M)
    s = np.empty(M)
    zeros = np.empty(K, dtype=np.int64)
    for l in range(L):
        ok = True
        for i in range(K):
            if eta[i] and not assigned[i, l]:
                ok = False
                break
        if not ok:
            continue
        for j in range(M):
            s_v[j] = 0.0
        nz = 0
        for i in range(K):
            if eta[i]:
                for j in range(M):
                    s_v[j] += q[i, l, j]
            elif assigned[i, l]:
                zeros[nz] = i
                nz += 1
        total = 0.0
        for mask in range(1 << nz):
            sign = 1.0
            for j in range(M):
                s[j] = s_v[j]
            for b in range(nz):
                if mask & (1 << b):
                    sign = -sign
                    i = zeros[b]
                    for j in range(M):
                        s[j] += q[i, l, j]
            prod = 1.0
            for j in range(M):
                f = 1.0 - s[j]
                if f <= 0.0:
                    prod = 0.0
                    break
                if f < 1.0:
                    prod *= f
            total += sign * prod
        p[l] = min(max(total, 0.0), 1.0) if clamp else total
    return p


@numba.njit(cache=True, nogil=True)
def disks_block_kernel(
    cams: np.ndarray, x: np.ndarray, centres: np.ndarray, diameter: float
) -> np.ndarray:  # pragma: no cover - jit
    """(K, L): some disc of the given diameter touches the segment camera -> point."""
    K, L, M = cams.shape[0], x.shape[0], centres.shape[0]
    out = np.zeros((K, L), dtype=np.bool_)
    r2 = 0.25 * diameter * diameter
    for i in range(K):
        cx, cy = cams[i, 0], cams[i, 1]
        for l in range(L):
            dx, dy = x[l, 0] - cx, x[l, 1] - cy
            len2 = dx * dx + dy * dy
            for j in range(M):
                px, py = centres[j, 0] - cx, centres[j, 1] - cy
                t = (px * dx + py * dy) / len2 if len2 > 0 else 0.0
                t = min(max(t, 0.0), 1.0)
                ex, ey = px - t * dx, py - t * dy
                if ex * ex + ey * ey < r2:
                    out[i, l] = True
                    break
    return out


@numba.njit(cache=True, nogil=True)
def segments_cross_edges_kernel(
    viewers: np.ndarray, points: np.ndarray, edge_a: np.ndarray, edge_b: np.ndarray
) -> np.ndarray:  # pragma: no cover - jit
    """(K, L): the open segment viewer -> point properly crosses one of the edges ``a -> b``."""
    K, L, E = viewers.shape[0], points.shape[0], edge_a.shape[0]
    out = np.zeros((K, L), dtype=np.bool_)
    for i in range(K):
        sx, sy = viewers[i, 0], viewers[i, 1]
        for l in range(L):
            dx, dy = points[l, 0] - sx, points[l, 1] - sy
            for e in range(E):
                ax, ay = edge_a[e, 0], edge_a[e, 1]
                bx, by = edge_b[e, 0], edge_b[e, 1]
                ex, ey = bx - ax, by - ay
                d1 = ex * (sy - ay) - ey * (sx - ax)
                d2 = ex * (points[l, 1] - ay) - ey * (points[l, 0] - ax)
                if d1 * d2 >= 0.0:
                    continue
                d3 = dx * (ay - sy) - dy * (ax - sx)
                d4 = dx * (by - sy) - dy * (bx - sx)
                if d3 * d4 < 0.0:
                    out[i, l] = True
                    break
    return out


@numba.njit(cache=True, nogil=True)
def pair_visibility_kernel(
    q: np.ndarray, assigned: np.ndarray, w: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - jit
    """P{eta_i = 1} and P{eta_i = 1, eta_j = 1} averaged over weighted particles (Eq. 8, Q = {i, j})."""
    N, L, M = q.shape
    p1 = np.zeros(N)
    p2 = np.zeros((N, N))
    for l in range(L):
        for i in range(N):
            if not assigned[i, l]:
                continue
            prod = 1.0
            for j in range(M):
                f = 1.0 - q[i, l, j]
                prod *= f if f > 0.0 else 0.0
            p1[i] += w[l] * prod
            for k in range(i + 1, N):
                if not assigned[k, l]:
                    continue
                prod = 1.0
                for j in range(M):
                    f = 1.0 - q[i, l, j] - q[k, l, j]
                    if f <= 0.0:
                        prod = 0.0
                        break
                    prod *= f
                p2[i, k] += w[l] * prod
    for i in range(N):
        p2[i, i] = p1[i]
        for k in range(i + 1, N):
            p2[k, i] = p2[i, k]
    return p1, p2
