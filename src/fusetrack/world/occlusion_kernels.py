"""Numba kernels for the occlusion computations of :mod:`fusetrack.world.occlusion`.

Same formulas as the NumPy references there (the tests compare them), written as loops so that
(camera, particle, occluder) triples far from each other are skipped cheaply: an occluder whose
prior puts the ray more than ``CUTOFF`` = 5 standard deviations away contributes q = 0 (the
exact value is below 3e-7), as does a triple whose across-the-ray factor is below 1e-9; the
normal CDF is a table lookup with linear interpolation (error < 3.3e-8). This makes the likelihood
for L = 1000 particles, 8 cameras and 40 occluders take about a millisecond with narrow occluder
priors instead of tens. With wide priors (sigma_psi = 32 in ``ercan2013-tradeoff``) nothing can
be skipped: about 210 of the 320 (camera, occluder) pairs of a particle have q > 0, four normal
CDF lookups each, and the inclusion-exclusion over ~4 occluded cameras has ~30 terms of 40
factors. The q of one sight line against its occluders runs in passes that vectorise
(:func:`_q_row_iso`); what that gains depends on the CPU (``benchmarks/ercan2013_q_rows.py`` and
its section of ``benchmarks/README.md``): on an AMD znver4 a triple costs ~4.5 ns (2026-12-05),
~2.8 of them the arithmetic without the four table reads, which are scalar loads, provided the
row runs on whole SIMD blocks (:func:`_row_length`; a remainder costs ~3x as much per triple).
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
_TABLE_INV_STEP = 1.0 / _TABLE_STEP
_PHI_VALUES = np.array(
    [
        0.5 * math.erfc(-(-_TABLE_HALF_WIDTH + i * _TABLE_STEP) * _SQRT1_2)
        for i in range(_TABLE_SIZE)
    ]
)
_PHI_TABLE = np.empty((_TABLE_SIZE, 2))
_PHI_TABLE[:, 0] = _PHI_VALUES
_PHI_TABLE[:-1, 1] = _PHI_VALUES[1:] - _PHI_VALUES[:-1]
_PHI_TABLE[-1, 1] = 0.0
"""Standard normal CDF on a grid over [-8.5, 8.5] and the step to the next grid value (one cache
line per lookup). Linear interpolation errs by at most h^2/8 max|Phi''| = h^2 phi(1)/8 = 3.26e-8
for the step h = 17/16383 (reached near |t| = 1; tested)."""
assert _PHI_TABLE[-1, 0] == 1.0


@numba.njit(cache=True, inline="always")
def _tails(t: float, r: float) -> float:  # pragma: no cover - jit
    """The table value ``r`` of :func:`_phi_fast` at ``t``, with its exact tails beyond -+8.5."""
    r = 1.0 if t >= _TABLE_HALF_WIDTH else r
    return 0.0 if t <= -_TABLE_HALF_WIDTH else r


@numba.njit(cache=True, inline="always")
def _table_row(pos: float) -> float:  # pragma: no cover - jit
    """The table row at or below grid position ``pos``, clamped to the table (as a float, so that
    a loop of them vectorises); a NaN position gives row 0, not an index outside the table."""
    k = pos if pos > 0.0 else 0.0
    return np.floor(k if k < _TABLE_SIZE - 1.0 else _TABLE_SIZE - 1.0)


@numba.njit(cache=True, inline="always")
def _phi_fast(t: float) -> float:  # pragma: no cover - jit
    """Standard normal CDF by table lookup and linear interpolation (|error| < 3.3e-8); exactly 0
    and 1 beyond -+8.5. Branch-free (the index clamped, the tails selected after the read), so
    that a loop of them over occluders runs in SIMD lanes."""
    pos = (t + _TABLE_HALF_WIDTH) * _TABLE_INV_STEP
    k = int(_table_row(pos))  # the last row is (1, 0): Phi(8.5) = 1.0
    return _tails(t, _PHI_TABLE[k, 0] + (pos - k) * _PHI_TABLE[k, 1])


@numba.njit(cache=True, nogil=True)
def occlusion_probability_kernel(
    cams: np.ndarray,
    x: np.ndarray,
    mu: np.ndarray,
    cov: np.ndarray,
    diameter: float,
    exclusion: float = 0.0,
) -> np.ndarray:  # pragma: no cover - jit
    """q[i, l, j] of Ercan et al. 2013, Eq. 7 (frame-free form), with far triples skipped.

    Every triple goes through :func:`_q_one` (with isotropic priors a sight line at a time
    through :func:`_q_row_iso`, the same formula), as in the fused likelihood kernel, so the
    likelihood and camera selection share one formula (and one ``exclusion`` option). With
    isotropic priors the occluders far from every sight line of a camera (exactly 0) are not
    computed (:func:`_cull_occluders`, exact)."""
    K, L, M = cams.shape[0], x.shape[0], mu.shape[0]
    out = np.zeros((K, L, M))
    general, all_iso, half, excl, use, n_use, rows, row, work, index = _sight_line_tables(
        cams, x, mu, cov, diameter, exclusion
    )
    every, q = np.ones((K, L), dtype=np.bool_), np.zeros((K, M))
    for l in range(L):
        _q_of_point(l, x, every, cams, cov, general, all_iso, half, excl, use, n_use, rows, row,
                    work, index, q)  # fmt: skip
        out[:, l, :] = q
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
def segments_cross_edges_paired_kernel(
    starts: np.ndarray, ends: np.ndarray, edge_a: np.ndarray, edge_b: np.ndarray
) -> np.ndarray:  # pragma: no cover - jit
    """(P,): the open segment ``starts[p] -> ends[p]`` properly crosses one of the edges ``a -> b``;
    the arithmetic and the test ``d1 d2 < 0 and d3 d4 < 0`` of
    :func:`fusetrack.world.geometry.segments_cross_polygon`, one segment per row."""
    P, E = starts.shape[0], edge_a.shape[0]
    out = np.zeros(P, dtype=np.bool_)
    for p in range(P):
        sx, sy = starts[p, 0], starts[p, 1]
        px, py = ends[p, 0], ends[p, 1]
        dx, dy = px - sx, py - sy
        for e in range(E):
            ax, ay = edge_a[e, 0], edge_a[e, 1]
            bx, by = edge_b[e, 0], edge_b[e, 1]
            ex, ey = bx - ax, by - ay
            d1 = ex * (sy - ay) - ey * (sx - ax)
            d2 = ex * (py - ay) - ey * (px - ax)
            d3 = dx * (ay - sy) - dy * (ax - sx)
            d4 = dx * (by - sy) - dy * (bx - sx)
            if d1 * d2 < 0.0 and d3 * d4 < 0.0:
                out[p] = True
                break
    return out


@numba.njit(cache=True, inline="always")
def _seen_by_one(q: np.ndarray, i: int) -> float:  # pragma: no cover - jit
    """P{eta_i = 1 | u} = prod_j max(1 - q_ij, 0) (Eq. 8, Q = {i}); ``q (K, M)`` of one point."""
    prod = 1.0
    for j in range(q.shape[1]):
        f = 1.0 - q[i, j]
        prod *= f if f > 0.0 else 0.0
    return prod


@numba.njit(cache=True, inline="always")
def _seen_by_both(q: np.ndarray, i: int, k: int) -> float:  # pragma: no cover - jit
    """P{eta_i = 1, eta_k = 1 | u} = prod_j max(1 - q_ij - q_kj, 0) (Eq. 8, Q = {i, k})."""
    prod = 1.0
    for j in range(q.shape[1]):
        f = 1.0 - q[i, j] - q[k, j]
        if f <= 0.0:
            return 0.0
        prod *= f
    return prod


@numba.njit(cache=True, inline="always")
def _seen_by_both4(q: np.ndarray, i: int, k: np.ndarray, at: int) -> tuple:  # pragma: no cover
    """:func:`_seen_by_both` of camera ``i`` with the four cameras ``k[at:at + 4]``, bit for bit
    (each product over the occluders in order; a factor <= 0 makes it 0), as four independent
    products in one pass over the occluders."""
    k0, k1, k2, k3 = k[at], k[at + 1], k[at + 2], k[at + 3]
    p0 = p1 = p2 = p3 = 1.0
    for j in range(q.shape[1]):
        a = 1.0 - q[i, j]
        f0, f1, f2, f3 = a - q[k0, j], a - q[k1, j], a - q[k2, j], a - q[k3, j]
        p0 *= f0 if f0 > 0.0 else 0.0
        p1 *= f1 if f1 > 0.0 else 0.0
        p2 *= f2 if f2 > 0.0 else 0.0
        p3 *= f3 if f3 > 0.0 else 0.0
    return p0, p1, p2, p3


@numba.njit(cache=True, inline="always")
def _add_pairs(
    q: np.ndarray, assigned: np.ndarray, w: float, p1: np.ndarray, p2: np.ndarray, idx: np.ndarray
) -> None:  # pragma: no cover - jit
    """Add one point's ``w P{eta_i = 1 | u}`` to ``p1`` and ``w P{eta_i = 1, eta_k = 1 | u}``
    (i < k) to ``p2``, on the cameras ``assigned (K,)`` to it; ``q (K, M)``, ``idx (K,)`` scratch.
    The pairs of a camera go four at a time (:func:`_seen_by_both4`), the same numbers."""
    n = 0
    for i in range(q.shape[0]):
        if assigned[i]:
            idx[n] = i
            n += 1
    for a in range(n):
        i = idx[a]
        p1[i] += w * _seen_by_one(q, i)
        b = a + 1
        while b + 4 <= n:
            v0, v1, v2, v3 = _seen_by_both4(q, i, idx, b)
            p2[i, idx[b]] += w * v0
            p2[i, idx[b + 1]] += w * v1
            p2[i, idx[b + 2]] += w * v2
            p2[i, idx[b + 3]] += w * v3
            b += 4
        for c in range(b, n):
            p2[i, idx[c]] += w * _seen_by_both(q, i, idx[c])


@numba.njit(cache=True, inline="always")
def _fill_pairs(p1: np.ndarray, p2: np.ndarray) -> None:  # pragma: no cover - jit
    """``p2``'s diagonal is ``p1`` and its lower triangle the upper one."""
    N = p1.shape[0]
    for i in range(N):
        p2[i, i] = p1[i]
        for k in range(i + 1, N):
            p2[k, i] = p2[i, k]


@numba.njit(cache=True, nogil=True)
def pair_visibility_kernel(
    q: np.ndarray, assigned: np.ndarray, w: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - jit
    """P{eta_i = 1} and P{eta_i = 1, eta_j = 1} averaged over weighted particles (Eq. 8, Q = {i, j})."""
    N, L = q.shape[0], q.shape[1]
    p1 = np.zeros(N)
    p2 = np.zeros((N, N))
    idx = np.empty(N, dtype=np.int64)
    for l in range(L):
        _add_pairs(q[:, l, :], assigned[:, l], w[l], p1, p2, idx)
    _fill_pairs(p1, p2)
    return p1, p2


@numba.njit(cache=True, nogil=True)
def pair_visibility_of_priors_kernel(
    cams: np.ndarray,
    x: np.ndarray,
    mu: np.ndarray,
    cov: np.ndarray,
    diameter: float,
    exclusion: float,
    assigned: np.ndarray,
    w: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - jit
    """:func:`pair_visibility_kernel` of :func:`occlusion_probability_kernel`'s q, bit for bit,
    without the ``(K, L, M)`` array: q one particle at a time, and only on the cameras assigned
    to it (the others' q is never read)."""
    K, M = cams.shape[0], mu.shape[0]
    general, all_iso, half, excl, use, n_use, rows, row, work, index = _sight_line_tables(
        cams, x, mu, cov, diameter, exclusion
    )
    q = np.zeros((K, M))
    p1 = np.zeros(K)
    p2 = np.zeros((K, K))
    idx = np.empty(K, dtype=np.int64)
    for l in range(x.shape[0]):
        _q_of_point(l, x, assigned, cams, cov, general, all_iso, half, excl, use, n_use, rows, row,
                    work, index, q)  # fmt: skip
        _add_pairs(q, assigned[:, l], w[l], p1, p2, idx)
    _fill_pairs(p1, p2)
    return p1, p2


@numba.njit(cache=True, nogil=True)
def pair_visibility_per_particle_kernel(
    q: np.ndarray, assigned: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - jit
    """The terms :func:`pair_visibility_kernel` sums: P{eta_i = 1 | u_l} ``(N, L)`` and
    P{eta_i = 1, eta_k = 1 | u_l} ``(N, N, L)`` (0 off the assigned cameras; the diagonal is
    the first)."""
    N, L = q.shape[0], q.shape[1]
    p1 = np.zeros((N, L))
    p2 = np.zeros((N, N, L))
    for i in range(N):
        for l in range(L):
            if assigned[i, l]:
                p1[i, l] = _seen_by_one(q[:, l, :], i)
                p2[i, i, l] = p1[i, l]
        for k in range(i + 1, N):
            for l in range(L):
                if assigned[i, l] and assigned[k, l]:
                    v = _seen_by_both(q[:, l, :], i, k)
                    p2[i, k, l] = v
                    p2[k, i, l] = v
    return p1, p2


@numba.njit(cache=True, inline="always")
def _sight_line(rx: float, ry: float, exclusion: float) -> tuple:  # pragma: no cover - jit
    """Unit direction ``(u1, u2)`` of the sight line ``r = (rx, ry)`` and the length ``|r| -
    exclusion`` of its Eq. 7 rectangle (<= 0: no rectangle, every q is 0)."""
    r = math.sqrt(rx * rx + ry * ry)
    if r <= 0.0:
        return 0.0, 0.0, 0.0
    return rx / r, ry / r, r - exclusion


@numba.njit(cache=True, inline="always")
def _q_factors(
    phi: float, m_a: float, r_eff: float, isp: float, isa: float, half: float
) -> float:  # pragma: no cover - jit
    """Eq. 7's across- and along-the-ray factors of one triple and their product, clamped to
    [0, 1] (0 when the across factor is below 1e-9): ``phi`` the occluder mean's offset from the
    sight line, ``m_a`` its position along it, ``isp`` / ``isa`` the inverse standard deviations
    across / along."""
    across = _phi_fast((half - phi) * isp) - _phi_fast((-half - phi) * isp)
    along = _phi_fast((r_eff - m_a) * isa) - _phi_fast(-m_a * isa)
    v = min(max(along * across, 0.0), 1.0)
    return 0.0 if across < 1e-9 else v


@numba.njit(cache=True, inline="always")
def _q_iso(
    u1: float,
    u2: float,
    r_eff: float,
    m1: float,
    m2: float,
    inv_sd: float,
    reach: float,
    half: float,
) -> float:  # pragma: no cover - jit
    """q of one triple with an isotropic occluder prior (sd ``1 / inv_sd``), 0 when the ray is
    farther than ``reach`` from it; branch-free so that :func:`_q_row_iso` runs in SIMD lanes."""
    phi = -u2 * m1 + u1 * m2
    m_a = u1 * m1 + u2 * m2
    far = (abs(phi) - half > reach) | (m_a - r_eff > reach) | (m_a < -reach)
    v = _q_factors(phi, m_a, r_eff, inv_sd, inv_sd, half)
    return 0.0 if far else v


_LANES = 8
"""Doubles per AVX-512 register: :func:`_q_row_iso`'s passes run in blocks of this many occluders."""


@numba.njit(cache=True, inline="always")
def _row_length(n: int) -> int:  # pragma: no cover - jit
    """The length a row of ``n`` occluders is computed on: ``n`` rounded up to whole blocks of
    :data:`_LANES` unless only one or two are left over. LLVM vectorises the row's passes
    ``_LANES`` wide and leaves the last ``n % _LANES`` occluders to a scalar loop, which costs
    more than a whole block from three left over on (a znver4, 2026-12-05, ns per sight line on
    ``n`` / rounded up: 25 occluders 122 / 142, 27 147 / 146, 29 172 / 142, 31 191 / 143;
    ``benchmarks/ercan2013_q_rows.py --lengths``). The padding entries are zero rows of the row
    tables (finite; their q is computed and never read)."""
    r = n % _LANES
    return n if r < 3 else n + _LANES - r


_ROW_WORK = 9
"""Rows of the scratch array :func:`_q_row_iso` works in: 0-3 the four normal-CDF arguments of a
triple, 4-7 their table offsets and then the CDF values, 8 whether the triple is far (1.0)."""


@numba.njit(cache=True, inline="always")
def _q_row_iso(
    u1: float,
    u2: float,
    r_eff: float,
    m1: np.ndarray,
    m2: np.ndarray,
    inv_sd: np.ndarray,
    reach: np.ndarray,
    half: float,
    n: int,
    out: np.ndarray,
    work: np.ndarray,
    index: np.ndarray,
) -> None:  # pragma: no cover - jit
    """``out[u] = q`` of one sight line against ``n`` isotropic occluders given by contiguous rows:
    :func:`_q_iso` bit for bit, in four passes over the occluders so that all but the table reads
    run in SIMD lanes (one loop with the reads in it does not vectorise). Pass 1: the four CDF
    arguments and the far test; 2: table rows and offsets (:func:`_phi_fast`); 3: the table reads,
    kept scalar (AVX-512 gathers, which LLVM emits for this loop otherwise, cost 5.6 instead of 4.5
    ns per triple on an AMD znver4); 4: the tails, Eq. 7's product and the clamps. ``work (9,
    >= n)`` and ``index (4, >= n) int32``: scratch."""
    for u in range(n):
        phi = -u2 * m1[u] + u1 * m2[u]
        m_a = u1 * m1[u] + u2 * m2[u]
        far = 1.0 if abs(phi) - half > reach[u] else 0.0
        far = 1.0 if m_a - r_eff > reach[u] else far
        work[8, u] = 1.0 if m_a < -reach[u] else far
        s = inv_sd[u]
        work[0, u] = (half - phi) * s
        work[1, u] = (-half - phi) * s
        work[2, u] = (r_eff - m_a) * s
        work[3, u] = -m_a * s
    for c in range(4):
        for u in range(n):
            pos = (work[c, u] + _TABLE_HALF_WIDTH) * _TABLE_INV_STEP
            k = _table_row(pos)
            index[c, u] = np.int32(k)
            work[4 + c, u] = pos - k
    for c in range(4):
        u = 0
        while u < n:  # scalar loads: the early exit (never taken) keeps LLVM from vectorising
            row = np.uint32(index[c, u])  # unsigned: no wrap-around test for negative indices
            if row >= _TABLE_SIZE:
                break
            work[4 + c, u] = _PHI_TABLE[row, 0] + work[4 + c, u] * _PHI_TABLE[row, 1]
            u += 1
    for u in range(n):
        a0 = _tails(work[0, u], work[4, u])
        a1 = _tails(work[1, u], work[5, u])
        a2 = _tails(work[2, u], work[6, u])
        a3 = _tails(work[3, u], work[7, u])
        across = a0 - a1
        along = a2 - a3
        v = min(max(along * across, 0.0), 1.0)
        v = 0.0 if across < 1e-9 else v
        out[u] = 0.0 if work[8, u] != 0.0 else v


@numba.njit(cache=True, inline="always")
def _q_one(
    u1: float,
    u2: float,
    r_eff: float,
    m1: float,
    m2: float,
    pm1: float,
    pm2: float,
    c00: float,
    c01: float,
    c11: float,
    p11: float,
    p12: float,
    p22: float,
    iso: bool,
    inv_sd: float,
    reach: float,
    half: float,
) -> float:  # pragma: no cover - jit
    """q for one (camera, point, occluder) triple (Eq. 7, frame-free form), with far triples
    skipped: ``(u1, u2)`` the unit direction camera -> point, ``r_eff > 0`` the length of the
    rectangle (the distance less ``exclusion``), computed once per (camera, point) by the caller
    (:func:`_sight_line`); shared by :func:`occlusion_probability_kernel` (camera selection) and
    :func:`camera_likelihood_kernel`."""
    if iso:
        return _q_iso(u1, u2, r_eff, m1, m2, inv_sd, reach, half)
    phi = -u2 * m1 + u1 * m2
    sp2 = c00 * u2 * u2 - 2.0 * c01 * u1 * u2 + c11 * u1 * u1
    if (abs(phi) - half) ** 2 > CUTOFF * CUTOFF * sp2 and abs(phi) > half:
        return 0.0
    a = p11 * u1 * u1 + 2.0 * p12 * u1 * u2 + p22 * u2 * u2
    return _q_factors(
        phi, (u1 * pm1 + u2 * pm2) / a, r_eff, 1.0 / math.sqrt(sp2), math.sqrt(a), half
    )


@numba.njit(cache=True, inline="always")
def _occluder_precisions(occ_cov: np.ndarray) -> tuple:  # pragma: no cover - jit
    """Per occluder prior: precision entries ``(p11, p12, p22)``, whether it is isotropic, ``1/sd``
    and the tail cutoff ``CUTOFF sd`` (Ercan et al. 2013, Eq. 7)."""
    M = occ_cov.shape[0]
    p11, p12, p22 = np.zeros(M), np.zeros(M), np.zeros(M)
    iso = np.zeros(M, dtype=np.bool_)
    inv_sd, reach = np.zeros(M), np.zeros(M)
    for j in range(M):
        det = occ_cov[j, 0, 0] * occ_cov[j, 1, 1] - occ_cov[j, 0, 1] * occ_cov[j, 0, 1]
        p11[j] = occ_cov[j, 1, 1] / det
        p12[j] = -occ_cov[j, 0, 1] / det
        p22[j] = occ_cov[j, 0, 0] / det
        iso[j] = occ_cov[j, 0, 1] == 0.0 and occ_cov[j, 0, 0] == occ_cov[j, 1, 1]
        sd = math.sqrt(occ_cov[j, 0, 0])
        inv_sd[j] = 1.0 / sd
        reach[j] = CUTOFF * sd
    return p11, p12, p22, iso, inv_sd, reach


@numba.njit(cache=True, inline="always")
def _cull_occluders(
    x: np.ndarray,
    cam_pos: np.ndarray,
    occ_mu: np.ndarray,
    occ_cov: np.ndarray,
    half: float,
    exact: bool = False,
    exclusion: float = 0.0,
) -> tuple:  # pragma: no cover - jit
    """Per camera, the occluders that can block a sight line to the particle cloud: ``use[i, :n]``.

    Every sight line of the cloud lies within rho of the segment camera -> centre of the cloud's
    bounding box, so an occluder farther than rho + D/2 + 5.5 sd from that segment has q < 3e-7
    for every particle (2-D Gaussian tail) and is skipped (the likelihood's cull).

    ``exact`` (isotropic priors): skip only the occluders that :func:`_q_iso` calls far for every
    particle, so that no q changes: every point of its not-far rectangle (``|phi| <= D/2 + 5 sd``,
    ``-5 sd <= m_a <= r + 5 sd``) lies within sqrt((D/2 + 5 sd)^2 + (5 sd)^2) of the sight line
    segment, which lies within rho of the camera's segment to the centre (plus ``-exclusion`` if
    that is negative: the rectangle then reaches past the point); a rounding margin is added,
    and a cloud with a non-finite point skips nothing."""
    L, K, M = x.shape[0], cam_pos.shape[0], occ_mu.shape[0]
    use = np.zeros((K, M), dtype=np.int64)
    n_use = np.zeros(K, dtype=np.int64)
    if exact:  # a non-finite point: keep every occluder
        for l in range(L):
            if not (abs(x[l, 0]) < np.inf and abs(x[l, 1]) < np.inf):
                for i in range(K):
                    for j in range(M):
                        use[i, j] = j
                    n_use[i] = M
                return use, n_use
    lo_x, hi_x, lo_y, hi_y = np.inf, -np.inf, np.inf, -np.inf
    for l in range(L):
        lo_x = min(lo_x, x[l, 0])
        hi_x = max(hi_x, x[l, 0])
        lo_y = min(lo_y, x[l, 1])
        hi_y = max(hi_y, x[l, 1])
    bx, by = 0.5 * (lo_x + hi_x), 0.5 * (lo_y + hi_y)
    rho = 0.5 * math.sqrt((hi_x - lo_x) ** 2 + (hi_y - lo_y) ** 2)
    for i in range(K):
        sx, sy = bx - cam_pos[i, 0], by - cam_pos[i, 1]
        len2 = sx * sx + sy * sy
        n_use[i] = 0
        for j in range(M):
            ox, oy = occ_mu[j, 0] - cam_pos[i, 0], occ_mu[j, 1] - cam_pos[i, 1]
            t = (ox * sx + oy * sy) / len2 if len2 > 0 else 0.0
            t = min(max(t, 0.0), 1.0)
            fx, fy = ox - t * sx, oy - t * sy
            if exact:
                r = CUTOFF * math.sqrt(occ_cov[j, 0, 0])  # _occluder_precisions' reach
                lim = rho + max(-exclusion, 0.0) + math.sqrt((half + r) ** 2 + r * r)
                lim += 1e-9 * (1.0 + lim + math.sqrt(ox * ox + oy * oy) + math.sqrt(len2))
            else:
                sd_max = math.sqrt(  # Gershgorin bound on the largest eigenvalue
                    max(occ_cov[j, 0, 0], occ_cov[j, 1, 1]) + abs(occ_cov[j, 0, 1])
                )
                lim = rho + half + 1.1 * CUTOFF * sd_max
            if fx * fx + fy * fy <= lim * lim:
                use[i, n_use[i]] = j
                n_use[i] += 1
    return use, n_use


@numba.njit(cache=True, inline="always")
def _log_reading(
    z: float, d: float, h: float, focal: float, var_theta: float, var_pos: float, var_read: float
) -> float:  # pragma: no cover - jit
    """``log N(z; f h/d, var(v | x))`` of one camera's image coordinate (Ercan et al. 2013, Eq. 6)."""
    dd = max(d, 1e-6)  # MIN_DEPTH of perspective_camera
    ratio = h / dd
    rr = ratio * ratio
    f2 = focal * focal
    var = f2 * (1.0 + rr) ** 2 * var_theta + f2 * (1.0 + rr) / (dd * dd) * var_pos + var_read
    res = z - focal * ratio
    return -0.5 * (res * res / var + math.log(2.0 * math.pi * var))


@numba.njit(cache=True, inline="always")
def _disc_pattern(
    px: float,
    py: float,
    assigned: np.ndarray,
    eta: np.ndarray,
    cam_pos: np.ndarray,
    occ_mu: np.ndarray,
    r2disk: float,
) -> float:  # pragma: no cover - jit
    """``p(eta | x)`` with occluders as discs at known centres: 1 when every camera's visibility
    equals ``eta``, else 0 (Sec. 6.1, RMSE_occ = 0)."""
    for i in range(cam_pos.shape[0]):
        vis = assigned[i]
        if vis:
            rx, ry = px - cam_pos[i, 0], py - cam_pos[i, 1]
            len2 = rx * rx + ry * ry
            for j in range(occ_mu.shape[0]):
                ox, oy = occ_mu[j, 0] - cam_pos[i, 0], occ_mu[j, 1] - cam_pos[i, 1]
                t = (ox * rx + oy * ry) / len2 if len2 > 0 else 0.0
                t = min(max(t, 0.0), 1.0)
                fx, fy = ox - t * rx, oy - t * ry
                if fx * fx + fy * fy < r2disk:
                    vis = False
                    break
        if vis != eta[i]:
            return 0.0
    return 1.0


@numba.njit(cache=True, inline="always")
def _camera_offsets(
    cam_pos: np.ndarray, occ_mu: np.ndarray, p11: np.ndarray, p12: np.ndarray, p22: np.ndarray
) -> tuple:  # pragma: no cover - jit
    """Occluder means relative to each camera ``m (K, M)`` and their products with the occluder
    precision ``P m`` (the camera-fixed parts of Eq. 7)."""
    K, M = cam_pos.shape[0], occ_mu.shape[0]
    m1, m2, pm1, pm2 = np.zeros((K, M)), np.zeros((K, M)), np.zeros((K, M)), np.zeros((K, M))
    for i in range(K):
        for j in range(M):
            m1[i, j] = occ_mu[j, 0] - cam_pos[i, 0]
            m2[i, j] = occ_mu[j, 1] - cam_pos[i, 1]
            pm1[i, j] = p11[j] * m1[i, j] + p12[j] * m2[i, j]
            pm2[i, j] = p12[j] * m1[i, j] + p22[j] * m2[i, j]
    return m1, m2, pm1, pm2


@numba.njit(cache=True, inline="always")
def _sight_line_tables(
    cams: np.ndarray,
    x: np.ndarray,
    mu: np.ndarray,
    cov: np.ndarray,
    diameter: float,
    exclusion: float,
) -> tuple:  # pragma: no cover - jit
    """What :func:`_q_of_point` reads for sight lines to the points ``x``: the general path's
    tables (the occluders' precisions and the per-(camera, occluder) offsets of
    :func:`_camera_offsets`), whether every prior is isotropic, D/2, ``exclusion``, each camera's
    occluders that are not far from every sight line (:func:`_cull_occluders`, exact) and their
    rows (:func:`_iso_rows`), and the row's scratch."""
    M, K = mu.shape[0], cams.shape[0]
    p11, p12, p22, iso, inv_sd, reach = _occluder_precisions(cov)
    m1, m2, pm1, pm2 = _camera_offsets(cams, mu, p11, p12, p22)
    if np.all(iso):
        use, n_use = _cull_occluders(x, cams, mu, cov, 0.5 * diameter, True, exclusion)
    else:
        use, n_use = np.zeros((K, M), dtype=np.int64), np.zeros(K, dtype=np.int64)
    all_iso, rows = _iso_rows(use, n_use, m1, m2, inv_sd, reach, iso)
    n = _row_length(M)
    work, index = np.empty((_ROW_WORK, n)), np.empty((4, n), dtype=np.int32)
    general = (p11, p12, p22, iso, inv_sd, reach, m1, m2, pm1, pm2)
    return general, all_iso, 0.5 * diameter, exclusion, use, n_use, rows, np.empty(n), work, index


@numba.njit(cache=True)
def _q_sight_line_general(
    general: tuple,
    i: int,
    u1: float,
    u2: float,
    r_eff: float,
    half: float,
    cov: np.ndarray,
    out: np.ndarray,
) -> None:  # pragma: no cover - jit
    """``out[:M]``: q of camera ``i``'s sight line ``(u1, u2, r_eff)`` (:func:`_sight_line`)
    against every occluder a triple at a time (:func:`_q_one`, any priors; all 0 when the
    rectangle is empty), from the ``general`` tables of :func:`_sight_line_tables`. Out of line,
    so that the isotropic path of :func:`_q_of_point` compiles lean."""
    p11, p12, p22, iso, inv_sd, reach, m1, m2, pm1, pm2 = general
    for j in range(out.shape[0]):
        out[j] = 0.0 if r_eff <= 0.0 else _q_one(
            u1, u2, r_eff, m1[i, j], m2[i, j], pm1[i, j], pm2[i, j],
            cov[j, 0, 0], cov[j, 0, 1], cov[j, 1, 1],
            p11[j], p12[j], p22[j], iso[j], inv_sd[j], reach[j], half,
        )  # fmt: skip


@numba.njit(cache=True, inline="always")
def _q_of_point(
    l: int,
    x: np.ndarray,
    assigned: np.ndarray,
    cams: np.ndarray,
    cov: np.ndarray,
    general: tuple,
    all_iso: bool,
    half: float,
    excl: float,
    use: np.ndarray,
    n_use: np.ndarray,
    rows: np.ndarray,
    row: np.ndarray,
    work: np.ndarray,
    index: np.ndarray,
    q: np.ndarray,
) -> None:  # pragma: no cover - jit
    """``q[i, :M]``: q of the sight line from each camera ``i`` with ``assigned[i, l]`` to the
    point ``x[l]`` against every occluder (Eq. 7; the other rows are left as they are), from the
    tables of :func:`_sight_line_tables`: the per-point step of the selection kernels. Isotropic
    priors: one row (:func:`_q_row_iso`) over the occluders not culled for the camera (the
    others' q is exactly 0)."""
    px, py = x[l, 0], x[l, 1]
    for i in range(cams.shape[0]):
        if not assigned[i, l]:
            continue
        u1, u2, r_eff = _sight_line(px - cams[i, 0], py - cams[i, 1], excl)
        if not all_iso:
            _q_sight_line_general(general, i, u1, u2, r_eff, half, cov, q[i])
            continue
        for j in range(q.shape[1]):
            q[i, j] = 0.0
        n = 0 if r_eff <= 0.0 else n_use[i]  # a NaN sight line gives NaN q
        _q_row_iso(u1, u2, r_eff, rows[0, i], rows[1, i], rows[2, i], rows[3, i], half,
                   _row_length(n), row, work, index)  # fmt: skip
        for u in range(n):
            q[i, use[i, u]] = row[u]


@numba.njit(cache=True, inline="always")
def _split_touched(
    q: np.ndarray,
    s_v: np.ndarray,
    zeros: np.ndarray,
    nz: int,
    s: np.ndarray,
    active: np.ndarray,
    qa: np.ndarray,
) -> tuple:  # pragma: no cover - jit
    """Occluders that no occluded camera's rectangle reaches give the same factor
    ``1 - s_v[j]`` to every term of the inclusion-exclusion: their product ``common``. The rest,
    ``active[:na]``, get their seeing sums in ``s[:na]`` and the occluded cameras' ``q`` in
    contiguous rows ``qa[b, :na]``. (``s`` first holds each occluder's largest q over the occluded
    cameras, row by row so that the loops vectorise.)"""
    M = s_v.shape[0]
    for j in range(M):
        s[j] = 0.0
    for b in range(nz):
        i = zeros[b]
        for j in range(M):
            s[j] = max(s[j], q[i, j])
    common = 1.0
    na = 0
    for j in range(M):  # in order: active[na] = j and s[na] = s_v[j] only overwrite read entries
        if s[j] > 0.0:
            active[na] = j
            s[na] = s_v[j]
            na += 1
        else:
            f = 1.0 - s_v[j]
            if f <= 0.0:
                return 0.0, 0
            if f < 1.0:
                common *= f
    for b in range(nz):
        i = zeros[b]
        if na == M:
            for a in range(M):
                qa[b, a] = q[i, a]
        else:
            for a in range(na):
                qa[b, a] = q[i, active[a]]
    return common, na


@numba.njit(cache=True, inline="always")
def _odd(g: int) -> bool:  # pragma: no cover - jit
    """Parity of the number of set bits of ``g``."""
    odd = False
    while g:
        odd = not odd
        g &= g - 1
    return odd


@numba.njit(cache=True, inline="always")
def _gray_move(step: int, in_b: int) -> tuple:  # pragma: no cover - jit
    """Gray-code subset ``step`` from subset ``in_b`` of ``step - 1``: the camera (bit) that
    changes, +1 if it is added or -1 if removed, and the new subset."""
    bit = 0
    while not (step >> bit) & 1:
        bit += 1
    sign = -1.0 if in_b & (1 << bit) else 1.0
    return bit, sign, in_b ^ (1 << bit)


@numba.njit(cache=True, inline="always")
def _clamped(s: float) -> float:  # pragma: no cover - jit
    """One factor ``1 - s`` of Eq. 8, clamped to [0, 1]."""
    return min(max(1.0 - s, 0.0), 1.0)


@numba.njit(cache=True, inline="always")
def _inclusion_exclusion(
    q: np.ndarray,
    s_v: np.ndarray,
    zeros: np.ndarray,
    nz: int,
    s: np.ndarray,
    active: np.ndarray,
    qa: np.ndarray,
) -> float:  # pragma: no cover - jit
    """``Σ_{B ⊆ occluded} (-1)^|B| Π_j (1 - Σ_{i ∈ seen ∪ B} q_ij)`` (Eqs. 8-9) from the per-camera,
    per-occluder probabilities ``q`` and their sums over the seeing cameras ``s_v``.

    Occluders that no occluded camera's rectangle reaches are multiplied once
    (:func:`_split_touched`). The subsets are enumerated in Gray-code order (one camera added or
    removed per term), four consecutive ones per pass over the occluders, so that their four
    products (each over the occluders in order, factors clamped to [0, 1]) run side by side."""
    common, na = _split_touched(q, s_v, zeros, nz, s, active, qa)
    if common == 0.0:
        return 0.0
    if nz < 2:  # one or two terms
        p0 = p1 = 1.0
        for a in range(na):
            p0 *= _clamped(s[a])
            if nz == 1:
                p1 *= _clamped(s[a] + qa[0, a])
        return min(max((p0 - p1 if nz == 1 else p0) * common, 0.0), 1.0)
    # no factor leaves [0, 1] when even the largest sums (all occluded cameras) stay below 1
    # by more than the rounding of the Gray-code path: then the clamps are skipped
    free = True
    for a in range(na):
        f = 1.0 - s[a]
        for b in range(nz):
            f -= qa[b, a]
        if f <= 1e-9:
            free = False
            break
    total = 0.0
    in_b = 0
    for base in range(0, 1 << nz, 4):
        r0, g0 = 0, 0.0  # step base: the first camera change of the block (none at 0)
        if base > 0:
            r0, g0, in_b = _gray_move(base, in_b)
        odd0 = _odd(in_b)
        g1 = -1.0 if in_b & 1 else 1.0  # steps base + 1, 2, 3 change bits 0, 1, 0
        g2 = -1.0 if in_b & 2 else 1.0
        g3 = -g1
        in_b ^= 2  # after the block: bit 0 back as it was, bit 1 flipped
        p0 = p1 = p2 = p3 = 1.0
        for a in range(na):
            s0 = s[a] + g0 * qa[r0, a]
            s1 = s0 + g1 * qa[0, a]
            s2 = s1 + g2 * qa[1, a]
            s3 = s2 + g3 * qa[0, a]
            s[a] = s3
            if free:
                p0 *= 1.0 - s0
                p1 *= 1.0 - s1
                p2 *= 1.0 - s2
                p3 *= 1.0 - s3
            else:
                p0 *= _clamped(s0)
                p1 *= _clamped(s1)
                p2 *= _clamped(s2)
                p3 *= _clamped(s3)
        # subset sizes of the block alternate in parity: base even/odd, then odd/even, ...
        total += -p0 if odd0 else p0
        total += p1 if odd0 else -p1
        total += -p2 if odd0 else p2
        total += p3 if odd0 else -p3
    return min(max(total * common, 0.0), 1.0)


@numba.njit(cache=True, nogil=True, inline="always")
def _edges_clear(px, py, rx, ry, cx, cy, edge_a, edge_b):  # pragma: no cover - jit
    """True when the segment camera ``(cx, cy)`` -> particle ``(px, py)`` (``r = p - c``)
    crosses no edge (walls of a non-convex room, static occluders)."""
    for e in range(edge_a.shape[0]):
        ax, ay = edge_a[e, 0], edge_a[e, 1]
        ex, ey = edge_b[e, 0] - ax, edge_b[e, 1] - ay
        d1 = ex * (cy - ay) - ey * (cx - ax)
        d2 = ex * (py - ay) - ey * (px - ax)
        if d1 * d2 >= 0.0:
            continue
        d3 = rx * (ay - cy) - ry * (ax - cx)
        d4 = rx * (edge_b[e, 1] - cy) - ry * (edge_b[e, 0] - cx)
        if d3 * d4 < 0.0:
            return False
    return True


@numba.njit(cache=True, nogil=True)
def _prior_tables(x, cam_pos, occ_mu, occ_cov, half, mode):  # pragma: no cover - jit
    """Per-occluder precisions, the occluders each camera cannot skip and the per-(camera,
    occluder) offsets of the Gaussian priors (mode 2); zeros otherwise."""
    K, M = cam_pos.shape[0], occ_mu.shape[0]
    if mode == 2:
        p11, p12, p22, iso, inv_sd, reach = _occluder_precisions(occ_cov)
        use, n_use = _cull_occluders(x, cam_pos, occ_mu, occ_cov, half)
        m1, m2, pm1, pm2 = _camera_offsets(cam_pos, occ_mu, p11, p12, p22)
        return p11, p12, p22, iso, inv_sd, reach, use, n_use, m1, m2, pm1, pm2
    z, zk = np.zeros(M), np.zeros((K, M))
    return (
        z, z.copy(), z.copy(), np.zeros(M, dtype=np.bool_), z.copy(), z.copy(),
        np.zeros((K, M), dtype=np.int64), np.zeros(K, dtype=np.int64),
        zk, zk.copy(), zk.copy(), zk.copy(),
    )  # fmt: skip


@numba.njit(cache=True, inline="always")
def _iso_rows(
    use: np.ndarray,
    n_use: np.ndarray,
    m1: np.ndarray,
    m2: np.ndarray,
    inv_sd: np.ndarray,
    reach: np.ndarray,
    iso: np.ndarray,
) -> tuple:  # pragma: no cover - jit
    """Whether every occluder is isotropic, and then per camera the rows :func:`_q_row_iso` reads:
    ``m1, m2, inv_sd, reach`` of the occluders it cannot skip (``use[i, :n_use[i]]``) side by side,
    zeros after them up to :func:`_row_length` ``(M)``."""
    K, M = m1.shape
    rows = np.zeros((4, K, _row_length(M)))
    for j in range(M):
        if not iso[j]:
            return False, rows
    for i in range(K):
        for u in range(n_use[i]):
            j = use[i, u]
            rows[0, i, u] = m1[i, j]
            rows[1, i, u] = m2[i, j]
            rows[2, i, u] = inv_sd[j]
            rows[3, i, u] = reach[j]
    return M > 0, rows


@numba.njit(cache=True, nogil=True)
def camera_likelihood_kernel(
    x: np.ndarray,
    z: np.ndarray,
    cam_pos: np.ndarray,
    cam_yaw: np.ndarray,
    cam_tan_half: np.ndarray,
    cam_focal: np.ndarray,
    cam_var_theta: np.ndarray,
    cam_var_pos: np.ndarray,
    cam_var_read: np.ndarray,
    edge_a: np.ndarray,
    edge_b: np.ndarray,
    in_static: np.ndarray,
    mode: int,
    occ_mu: np.ndarray,
    occ_cov: np.ndarray,
    diameter: float,
    exclusion: float,
    floor: float,
    occlusion_power: float = 1.0,
) -> np.ndarray:  # pragma: no cover - jit
    """``log f(Z | x)`` of Ercan et al. 2013 (Eq. 6) for every particle in one pass.

    ``mode``: 0 no occluder information, 1 known occluder centres ``occ_mu`` (discs), 2 Gaussian
    priors ``(occ_mu, occ_cov)`` (Eqs. 7-9 on the assigned cameras). A particle that a reporting
    camera cannot see (field of view, walls, static occluders) is impossible (-inf); otherwise the
    pattern probability is floored at ``floor`` and raised to ``occlusion_power``. Same formulas as
    :meth:`fusetrack.sensors.occlusion_aware_camera.OcclusionAwareLikelihood.log_likelihood_reference`.
    """
    L, K, M = x.shape[0], cam_pos.shape[0], occ_mu.shape[0]
    out = np.empty(L)
    half = 0.5 * diameter
    cy_ = np.cos(cam_yaw)
    sy_ = np.sin(cam_yaw)
    eta = ~np.isnan(z)  # the cameras that saw the object
    p11, p12, p22, iso, inv_sd, reach, use, n_use, m1, m2, pm1, pm2 = _prior_tables(
        x, cam_pos, occ_mu, occ_cov, half, mode
    )
    all_iso, rows = _iso_rows(use, n_use, m1, m2, inv_sd, reach, iso)
    n_row = _row_length(M)
    q_row = np.empty(n_row)
    work, index = np.empty((_ROW_WORK, n_row)), np.empty((4, n_row), dtype=np.int32)
    assigned = np.empty(K, dtype=np.bool_)
    q = np.zeros((K, M))
    s_v = np.empty(M)
    s = np.empty(M)
    zeros = np.empty(K, dtype=np.int64)
    active = np.empty(M, dtype=np.int64)
    qa = np.empty((K, M))
    log_floor = math.log(floor) if floor > 0.0 else -np.inf
    for l in range(L):
        px, py = x[l, 0], x[l, 1]
        log_g = 0.0
        possible = True
        for i in range(K):
            rx, ry = px - cam_pos[i, 0], py - cam_pos[i, 1]
            d = cy_[i] * rx + sy_[i] * ry
            h = -sy_[i] * rx + cy_[i] * ry
            ok = d > 0.0 and abs(h) <= cam_tan_half[i] * d and not in_static[l]
            if ok:
                ok = _edges_clear(px, py, rx, ry, cam_pos[i, 0], cam_pos[i, 1], edge_a, edge_b)
            assigned[i] = ok
            if eta[i]:
                if not ok:
                    possible = False
                    break
                log_g += _log_reading(
                    z[i], d, h, cam_focal[i], cam_var_theta[i], cam_var_pos[i], cam_var_read[i]
                )
        if not possible:
            out[l] = -np.inf
            continue
        p = 1.0
        if mode == 1:
            p = _disc_pattern(px, py, assigned, eta, cam_pos, occ_mu, half * half)
        elif mode == 2 and M > 0:
            for j in range(M):
                s_v[j] = 0.0
            nz = 0
            for i in range(K):  # q[i, j] (Eq. 7) on the assigned cameras, summed over the seeing
                if not assigned[i]:
                    continue
                u1, u2, r_eff = _sight_line(px - cam_pos[i, 0], py - cam_pos[i, 1], exclusion)
                for j in range(M):
                    q[i, j] = 0.0
                n = n_use[i] if r_eff > 0.0 else 0
                if all_iso:
                    _q_row_iso(u1, u2, r_eff, rows[0, i], rows[1, i], rows[2, i], rows[3, i],
                               half, _row_length(n), q_row, work, index)  # fmt: skip
                if all_iso:
                    for u in range(n):
                        q[i, use[i, u]] = q_row[u]
                else:
                    for u in range(n):
                        j = use[i, u]
                        q[i, j] = _q_one(
                            u1, u2, r_eff, m1[i, j], m2[i, j], pm1[i, j], pm2[i, j],
                            occ_cov[j, 0, 0], occ_cov[j, 0, 1], occ_cov[j, 1, 1],
                            p11[j], p12[j], p22[j], iso[j], inv_sd[j], reach[j], half,
                        )  # fmt: skip
                if eta[i]:  # a loop apart: with the branch inside, ~7% of the call more
                    for u in range(n):
                        s_v[use[i, u]] += q[i, use[i, u]]
                if not eta[i]:
                    zeros[nz] = i
                    nz += 1
            p = _inclusion_exclusion(q, s_v, zeros, nz, s, active, qa)
        out[l] = log_g + occlusion_power * (math.log(p) if p > floor else log_floor)
    return out


@numba.njit(cache=True, nogil=True)
def prior_draw_hits_kernel(
    x: np.ndarray, mu: np.ndarray, chol: np.ndarray, z: np.ndarray, diameter: float
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - jit
    """Monte Carlo check of Eq. 7 (Ercan et al. 2013, App. C), camera at the origin: for each
    point ``x[p]`` the share of the prior draws ``mu[p] + chol[p] z[p, n]`` whose centre lies in
    the rectangle ``A(x)`` (along the sight line in ``[0, |x|]``, across within ``D/2``) and the
    share within ``D/2`` of the segment origin -> ``x`` (the disc touches the sight line)."""
    P, N = z.shape[0], z.shape[1]
    half = 0.5 * diameter
    rect = np.zeros(P)
    disk = np.zeros(P)
    for p in range(P):
        x0, x1 = x[p, 0], x[p, 1]
        r = math.hypot(x0, x1)
        u0, u1 = x0 / r, x1 / r
        len2 = x0 * x0 + x1 * x1
        n_rect = 0
        n_disk = 0
        for n in range(N):
            z0, z1 = z[p, n, 0], z[p, n, 1]
            d0 = mu[p, 0] + (chol[p, 0, 0] * z0 + chol[p, 0, 1] * z1)
            d1 = mu[p, 1] + (chol[p, 1, 0] * z0 + chol[p, 1, 1] * z1)
            along = d0 * u0 + d1 * u1
            across = d1 * u0 - d0 * u1
            if along >= 0.0 and along <= r and abs(across) <= half:
                n_rect += 1
            t = (d0 * x0 + d1 * x1) / len2 if len2 > 0.0 else 0.0
            t = min(max(t, 0.0), 1.0)
            e0, e1 = d0 - t * x0, d1 - t * x1
            if math.sqrt(e0 * e0 + e1 * e1) < half:
                n_disk += 1
        rect[p] = n_rect / N
        disk[p] = n_disk / N
    return rect, disk


@numba.njit(cache=True, nogil=True)
def points_in_polygon_kernel(points: np.ndarray, v: np.ndarray) -> np.ndarray:  # pragma: no cover
    """Even-odd test of ``points (n, 2)`` against polygon ``v``: the arithmetic of
    :func:`fusetrack.world.geometry.points_in_polygon`, one loop."""
    n, m = points.shape[0], v.shape[0]
    out = np.zeros(n, dtype=np.bool_)
    for k in range(n):
        x, y = points[k, 0], points[k, 1]
        inside = False
        for e in range(m):
            ax, ay = v[e, 0], v[e, 1]
            b = e + 1 if e + 1 < m else 0
            bx, by = v[b, 0], v[b, 1]
            if (ay > y) != (by > y) and x < ax + (y - ay) * (bx - ax) / (by - ay):
                inside = not inside
        out[k] = inside
    return out
