"""Which k cameras to query: the LMMSE metric of Ercan et al. 2013 (Sec. 5) and the rules compared.

The metric of a subset S is the mean squared error of the best *linear* estimate of the object's
position from the readings of S (Kailath et al. 2000),

    MSE(S) = Tr(Sigma_x - Sigma_Zx' Sigma_Z^-1 Sigma_Zx),

with every moment a weighted average over the predicted particle cloud. An occluded camera is
modelled as returning its expected value (Eq. 10), which scales the moments by the probabilities
that cameras see the object, ``P{eta_i = 1}`` and ``P{eta_i = 1, eta_j = 1}`` (Secs. 4.2-4.3 and
5.1). Two camera models give the moments:

* perspective (Eqs. 11-13): ``z_i = f_i h_i/d_i + v_i`` with the noise of Eq. 2;
* weak perspective (Eqs. 14-16): ``z~_i = a_i' x + v~_i``, ``a_i = [sin theta_i, -cos theta_i]``,
  ``var(v~_i) = (s_th^2 + s_read^2/f_i^2) d_i(mu_x)^2 + s_pos^2``.

Choices where the paper is silent (spec §8 items 13-14): ``h/d`` is clipped to the image bounds
``+-tan(fov/2)`` (it explodes for particles beside or behind a camera), the expected noise
variance ``E_x var(v_i | x)`` is taken over the particles in the camera's field of view, and
``Sigma_Z`` is inverted with a pseudo-inverse (a camera that sees no particle contributes
nothing). The model ``"perspective-joint"`` is the variant of item 13 that drops the independence
of eta and x: every expectation is joint over the particles, ``sum_l w_l P{eta | u_l} (.)``
(:func:`joint_perspective_moments`). Every moment for all N cameras is computed once per selection epoch; a subset's MSE
then costs a k x k solve, so greedy (Algorithm 2) and brute force share the same numbers.

Bad input: a selection size outside ``[1, N]`` is a :class:`~fusetrack.core.errors.ConfigError`.
A camera that can see none of the predicted particles (its field of view holds none, or walls
and static occluders hide them all) gets ``P{eta} = 0``, a zero row in ``Sigma_Z`` and
``Sigma_Zx``: it lowers no subset's MSE, so the searches pick it only when k leaves no other
choice (ties go to the lowest index), and the MSE stays finite. Cameras outside the room or
seeing no free floor at all are refused earlier, when the scene is built
(:class:`fusetrack.experiments.ercan2013.scenes.Scene`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, cast

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, ShapeError, check_points, invalid
from ..sensors import MIN_DEPTH, CameraArray
from ..world import (
    OccluderPriors,
    Room,
    disks_block,
    occlusion_probability,
    pair_visibility_of_priors_kernel,
    pair_visibility_per_particle_kernel,
)

Array = NDArray[np.float64]
CameraModel = Literal["perspective", "weak", "perspective-joint"]
SELECTION_METHODS = ("greedy", "brute", "fixed", "random", "closest", "all")


@dataclass(frozen=True)
class SelectionMoments:
    """The moments every subset's MSE is built from (all N cameras)."""

    mu_x: Array  # (2,)
    sigma_x: Array  # (2, 2)
    p_visible: Array  # (N,) P{eta_i = 1}
    p_both: Array  # (N, N) P{eta_i = 1, eta_j = 1}, diagonal = p_visible
    cov_zx: dict[str, Array]  # model -> (N, 2)
    cov_z: dict[str, Array]  # model -> (N, N)

    @property
    def n_cameras(self) -> int:
        return len(self.p_visible)


def _gaussian_priors(occluders: OccluderPriors | ArrayLike | None) -> OccluderPriors:
    """The occluders of ``prior_mode="gaussian"``: they must be :class:`OccluderPriors`."""
    if not isinstance(occluders, OccluderPriors):
        raise ConfigError(invalid("occluders", type(occluders).__name__, "OccluderPriors"))
    return occluders


def _gaussian_occlusion(
    cameras: CameraArray,
    x: Array,
    occluders: OccluderPriors | ArrayLike | None,
    diameter: float,
    exclusion: float,
) -> Array:
    """``q`` ``(N, L, M)``: each occluder prior's probability of hiding each particle from each
    camera (Gaussian priors only)."""
    return occlusion_probability(
        cameras.positions, x, _gaussian_priors(occluders), diameter, exclusion
    )


def _certain_visibility(
    cameras: CameraArray,
    x: Array,
    occluders: OccluderPriors | ArrayLike | None,
    diameter: float,
    prior_mode: str,
    assigned: NDArray[np.bool_],
) -> NDArray[np.bool_]:
    """Visibility ``(L, N)`` under the extreme priors: occluders exactly at their means
    (``"perfect"``) or ignored (``"none"``)."""
    if prior_mode == "perfect":
        centres = occluders.mean if isinstance(occluders, OccluderPriors) else occluders
        centres = np.zeros((0, 2)) if centres is None else np.asarray(centres, float).reshape(-1, 2)
        return assigned & ~disks_block(cameras.positions, x, centres, diameter)
    if prior_mode == "none":
        return assigned
    raise ConfigError(invalid("prior_mode", prior_mode, "'gaussian', 'perfect' or 'none'"))


def visibility_probabilities(
    cameras: CameraArray,
    room: Room,
    x: Array,
    w: Array,
    occluders: OccluderPriors | ArrayLike | None,
    diameter: float,
    prior_mode: str,
    exclusion: float = 0.0,
    in_view: NDArray[np.bool_] | None = None,
) -> tuple[Array, Array]:
    """``P{eta_i = 1}`` ``(N,)`` and ``P{eta_i = 1, eta_j = 1}`` ``(N, N)`` over the particle cloud.

    ``sum_l w_l P{...| u_l}``, with the conditional probabilities of Eq. 8 (``Q = {i}`` or
    ``{i, j}``) on the cameras assigned to each particle, or the deterministic visibility of the
    extreme priors (Sec. 6.1). ``exclusion``: Eq. 7's rectangles end this far before the particle,
    the option of :class:`~fusetrack.sensors.occlusion_aware_camera.OcclusionAwareLikelihood`
    (both compute q a sight line at a time with the same per-triple formula). ``in_view``: the
    cameras' fields of view ``(L, N)`` (:meth:`CameraArray.in_fov`) when already at hand.
    """
    if in_view is None:
        in_view = cameras.in_fov(x[:, None, :])
    assigned = in_view.T & ~room.sight_blocked_grid(cameras.positions, x)
    if prior_mode == "gaussian":
        priors = _gaussian_priors(occluders)
        if not 0 <= exclusion < np.inf:
            raise ConfigError(invalid("exclusion", exclusion, "a finite length >= 0"))
        p1, p2 = pair_visibility_of_priors_kernel(
            check_points("cameras.positions", cameras.positions),
            check_points("x", x),
            priors.mean,
            np.ascontiguousarray(priors.cov),
            float(diameter),
            float(exclusion),
            np.ascontiguousarray(assigned),
            np.ascontiguousarray(w, dtype=float),
        )
        return p1, p2
    vis = _certain_visibility(cameras, x, occluders, diameter, prior_mode, assigned)
    vw = vis * w[None, :]
    return vw.sum(axis=1), vw @ vis.T.astype(float)


def visibility_per_particle(
    cameras: CameraArray,
    room: Room,
    x: Array,
    occluders: OccluderPriors | ArrayLike | None,
    diameter: float,
    prior_mode: str,
    exclusion: float = 0.0,
) -> tuple[Array, Array]:
    """``P{eta_i = 1 | u_l}`` ``(N, L)`` and ``P{eta_i = 1, eta_j = 1 | u_l}`` ``(N, N, L)``: the
    terms :func:`visibility_probabilities` sums with the particle weights (Eq. 8 with Q = {i} or
    {i, j}, factors clamped at 0; deterministic for the extreme priors)."""
    assigned = cameras.in_fov(x[:, None, :]).T & ~room.sight_blocked_grid(cameras.positions, x)
    if prior_mode == "gaussian":
        q = _gaussian_occlusion(cameras, x, occluders, diameter, exclusion)  # (N, L, M)
        return pair_visibility_per_particle_kernel(q, np.ascontiguousarray(assigned))
    vis = _certain_visibility(cameras, x, occluders, diameter, prior_mode, assigned)
    v = vis.astype(float)
    return v, v[:, None, :] * v[None, :, :]


def joint_perspective_moments(
    cameras: CameraArray, x: Array, w: Array, p1: Array, p2: Array
) -> tuple[Array, Array]:
    """``Sigma_Zx`` ``(N, 2)`` and ``Sigma_Z`` ``(N, N)`` of the perspective model with joint
    expectations over the particles (spec §8 item 13's variant of Eqs. 11-13): an occluded camera
    returns its expected reading ``e_i`` (Eq. 10), so ``z~_i - e_i = eta_i (z_i - e_i)`` and

        Sigma_Zx,i = sum_l w_l P{eta_i | u_l} (f_i r_il - e_i) (x_l - mu),
        Sigma_Z,ij = sum_l w_l P{eta_i, eta_j | u_l} (f_i r_il - e_i)(f_j r_jl - e_j)
                     + [i = j] sum_l w_l P{eta_i | u_l} var(v_i | x_l),

    with ``r = h/d`` clipped to the image bounds as in Eq. 11. ``p1 (N, L)``, ``p2 (N, N, L)``:
    :func:`visibility_per_particle`. With P{eta | u_l} the same for every particle this is
    Eqs. 12-13 (the noise averaged over the particles in view)."""
    mu = w @ x
    dx = x - mu
    f = cameras.focals
    d, h = cameras.depth_lateral(x[:, None, :])  # (L, N)
    bound = np.tan(cameras.fovs / 2)
    r = np.clip(h / np.where(np.abs(d) > MIN_DEPTH, d, MIN_DEPTH), -bound, bound)
    dev = f * r - f * (w @ r)  # (L, N): f_i r_il - e_i
    cov_zx = (p1 * w * dev.T) @ dx
    cov_z = np.einsum("ijl,l,li,lj->ij", p2, w, dev, dev)
    var = cameras.noise_var(x[:, None, :])  # (L, N)
    cov_z[np.diag_indices_from(cov_z)] += np.sum(p1 * w * var.T, axis=1)
    return cov_zx, cov_z


def selection_moments(
    cameras: CameraArray,
    room: Room,
    x: ArrayLike,
    w: ArrayLike,
    occluders: OccluderPriors | ArrayLike | None,
    diameter: float,
    prior_mode: str = "gaussian",
    models: Sequence[str] = ("perspective", "weak"),
    exclusion: float = 0.0,
) -> SelectionMoments:
    """Moments of the LMMSE metric from the predicted cloud ``x (L, 2)``, weights ``w (L,)``.

    ``exclusion``: shortened Eq. 7 rectangles, as in the likelihood (see
    :func:`visibility_probabilities`)."""
    x = check_points("x", np.asarray(x, float)[:, :2])
    w_in = np.asarray(w, float)
    if w_in.shape != (len(x),):
        raise ShapeError(invalid("w.shape", w_in.shape, f"({len(x)},)"))
    if not (np.all(np.isfinite(w_in)) and np.all(w_in >= 0) and w_in.sum() > 0):
        raise ConfigError(invalid("w", w_in.tolist(), "finite weights >= 0 with a positive sum"))
    w = cast(Array, w_in / w_in.sum())
    mu = w @ x
    dx = x - mu
    sigma_x = (dx * w[:, None]).T @ dx
    d, h = cameras.depth_lateral(x[:, None, :])  # (L, N)
    in_view = cameras.in_fov_of(d, h)
    p1, p2 = visibility_probabilities(
        cameras, room, x, w, occluders, diameter, prior_mode, exclusion, in_view
    )
    cov_zx: dict[str, Array] = {}
    cov_z: dict[str, Array] = {}
    f = cameras.focals
    if "perspective" in models:
        bound = np.tan(cameras.fovs / 2)
        r = np.clip(h / np.where(np.abs(d) > MIN_DEPTH, d, MIN_DEPTH), -bound, bound)
        e_z = f * (w @ r)  # Eq. 11
        cov_zx["perspective"] = (p1 * f)[:, None] * (r * w[:, None]).T @ dx  # Eq. 12
        rr = (r * w[:, None]).T @ r
        var = cameras.noise_var_of(d, h)
        wv = w[:, None] * in_view
        mass = wv.sum(axis=0)
        centre_var = cameras.noise_var(mu[None, :])
        sig2 = np.where(
            mass > 0, np.sum(wv * var, axis=0) / np.where(mass > 0, mass, 1), centre_var
        )
        cov_z["perspective"] = p2 * (
            np.outer(f, f) * rr - np.outer(e_z, e_z) + np.diag(sig2)
        )  # Eq. 13
    if "weak" in models:
        a = cameras.normals  # (N, 2)
        d_bar, _ = cameras.depth_lateral(mu[None, :])
        d_bar = np.maximum(np.abs(d_bar), MIN_DEPTH)
        var_t = (
            cameras.sigma_theta**2 + cameras.sigma_read**2 / f**2
        ) * d_bar**2 + cameras.sigma_pos**2  # Eq. 14
        cov_zx["weak"] = p1[:, None] * (a @ sigma_x)  # Eq. 15
        cov_z["weak"] = p2 * (a @ sigma_x @ a.T + np.diag(var_t))  # Eq. 16
    if "perspective-joint" in models:
        pl1, pl2 = visibility_per_particle(
            cameras, room, x, occluders, diameter, prior_mode, exclusion
        )
        cov_zx["perspective-joint"], cov_z["perspective-joint"] = joint_perspective_moments(
            cameras, x, w, pl1, pl2
        )
    return SelectionMoments(mu, sigma_x, p1, p2, cov_zx, cov_z)


CONDITION_LIMIT = 1e6
"""Largest bound ``tr(A) tr(A^-1)`` on the condition number of a subset's scaled ``Sigma_Z`` that
:func:`subset_mse` solves by Cholesky; above it (and for a matrix that is not positive definite)
the pseudo-inverse is used, whose cut-off (1e-10 of the largest eigenvalue) then may matter."""


@numba.njit(cache=True, nogil=True)
def _subset_gain_kernel(
    cov_zx: Array, cov_z: Array, subsets: NDArray[np.intp], limit: float
) -> Array:  # pragma: no cover - jit
    """``Tr(Sigma_Zx' Sigma_Z^-1 Sigma_Zx)`` of each subset by a Cholesky factor ``A = L L'`` of
    ``Sigma_Z / max|Sigma_Z|`` (rows of cameras with ``Sigma_Z,ii = 0`` left out, as the
    pseudo-inverse does); NaN where ``A`` is not positive definite or the bound
    ``tr(A) tr(A^-1) = tr(A) |L^-1|_F^2`` on its condition number exceeds ``limit``."""
    n_sub, k = subsets.shape
    out = np.empty(n_sub)
    chol = np.zeros((k, k))
    inv = np.zeros((k, k))
    idx = np.empty(k, dtype=np.int64)
    for b in range(n_sub):
        scale = 0.0
        for r in range(k):
            for c in range(k):
                scale = max(scale, abs(cov_z[subsets[b, r], subsets[b, c]]))
        scale = max(scale, 1e-300)
        n, ok = 0, True
        for r in range(k):
            i = subsets[b, r]
            if cov_z[i, i] != 0.0:
                idx[n] = i
                n += 1
                continue
            for c in range(k):  # a zero diagonal with a non-zero row: not a covariance
                ok = ok and cov_z[i, subsets[b, c]] == 0.0 and cov_z[subsets[b, c], i] == 0.0
        trace_a = 0.0
        for r in range(n):
            if not ok:
                break
            for c in range(r + 1):
                v = cov_z[idx[r], idx[c]] / scale
                for p in range(c):
                    v -= chol[r, p] * chol[c, p]
                if r != c:
                    chol[r, c] = v / chol[c, c]
                elif v > 0.0:
                    chol[r, r] = math.sqrt(v)
                    trace_a += cov_z[idx[r], idx[r]] / scale
                else:
                    ok = False
        if not ok:
            out[b] = np.nan
            continue
        inv_norm2 = 0.0  # |L^-1|_F^2 = tr(A^-1), column by column of L^-1
        for c in range(n):
            for r in range(n):
                v = 1.0 if r == c else 0.0
                for p in range(c, r):
                    v -= chol[r, p] * inv[p, c]
                inv[r, c] = v / chol[r, r] if r >= c else 0.0
                inv_norm2 += inv[r, c] * inv[r, c]
        if trace_a * inv_norm2 > limit:
            out[b] = np.nan
            continue
        gain = 0.0  # sum over the two columns of |L^-1 Sigma_Zx|^2, over the scale
        for col in range(cov_zx.shape[1]):
            for r in range(n):
                v = 0.0
                for p in range(r + 1):
                    v += inv[r, p] * cov_zx[idx[p], col]
                gain += v * v
        out[b] = gain / scale
    return out


def _subset_mse_pinv(czx_all: Array, cz_all: Array, s: NDArray[np.intp], trace: float) -> Array:
    """:func:`subset_mse` by the batched pseudo-inverse (every subset, any conditioning)."""
    czx = czx_all[s]  # (B, k, 2)
    cz = cz_all[s[:, :, None], s[:, None, :]]  # (B, k, k)
    scale = np.maximum(np.abs(cz).max(axis=(1, 2), keepdims=True), 1e-300)
    inv = np.linalg.pinv(cz / scale, rcond=1e-10, hermitian=True) / scale
    gain = np.einsum("bki,bkl,blj->bij", czx, inv, czx)
    return np.asarray(trace - np.trace(gain, axis1=1, axis2=2))


def subset_mse(moments: SelectionMoments, subsets: ArrayLike, model: str = "perspective") -> Array:
    """``MSE(S) = Tr(Sigma_x - Sigma_Zx' Sigma_Z^+ Sigma_Zx)`` for each row of ``subsets (B, k)``.

    A Cholesky solve per subset where ``Sigma_Z`` (less the cameras it gives zero variance) is
    positive definite with a condition number below :data:`CONDITION_LIMIT` -- there the
    pseudo-inverse's cut-off removes nothing, so both give the same value up to rounding -- and
    the pseudo-inverse for the rest."""
    if model not in moments.cov_z:
        raise ConfigError(invalid("model", model, f"one of {sorted(moments.cov_z)}"))
    s = np.asarray(subsets, dtype=np.intp)
    if s.ndim == 1:
        s = s[None, :]
    trace = float(np.trace(moments.sigma_x))
    if s.shape[1] == 0:
        return np.full(len(s), trace)
    czx_all, cz_all = moments.cov_zx[model], moments.cov_z[model]
    if s.min() < 0 or s.max() >= len(cz_all):
        raise ConfigError(invalid("subsets", s.tolist(), f"camera indices in [0, {len(cz_all)})"))
    mse = trace - _subset_gain_kernel(
        np.ascontiguousarray(czx_all), np.ascontiguousarray(cz_all), np.ascontiguousarray(s),
        CONDITION_LIMIT,
    )  # fmt: skip
    rest = np.isnan(mse)
    if rest.any():
        mse[rest] = _subset_mse_pinv(czx_all, cz_all, s[rest], trace)
    return np.asarray(mse)


def _check_k(k: int, n: int) -> int:
    if not (isinstance(k, int | np.integer) and 1 <= k <= n):
        raise ConfigError(invalid("k", k, f"an integer number of cameras in [1, {n}]"))
    return int(k)


def greedy_selection(moments: SelectionMoments, k: int, model: str = "perspective") -> list[int]:
    """Ercan et al. 2013, Algorithm 2: add the camera that lowers the MSE most, k times.

    Ties go to the lowest camera index (strict ``<`` of the algorithm).
    """
    n = moments.n_cameras
    k = _check_k(k, n)
    chosen: list[int] = []
    for _ in range(k):
        rest = [i for i in range(n) if i not in chosen]
        trials = np.array([[*chosen, i] for i in rest], dtype=np.intp)
        e = subset_mse(moments, trials, model)
        chosen.append(rest[int(np.argmin(e))])
    return sorted(chosen)


def brute_force_selection(
    moments: SelectionMoments, k: int, model: str = "perspective", chunk: int = 4096
) -> list[int]:
    """The k-subset with the smallest MSE among all ``C(N, k)`` (first in lexicographic order on ties)."""
    n = moments.n_cameras
    k = _check_k(k, n)
    best, best_e = None, math.inf
    combos = itertools.combinations(range(n), k)
    while True:
        block = np.array(list(itertools.islice(combos, chunk)), dtype=np.intp)
        if len(block) == 0:
            break
        e = subset_mse(moments, block, model)
        j = int(np.argmin(e))
        if e[j] < best_e:
            best, best_e = block[j].tolist(), float(e[j])
    assert best is not None
    return best


def fixed_selection(order: Sequence[int], k: int) -> list[int]:
    """The first k cameras of a preselected list (0-based indices)."""
    k = _check_k(k, len(order))
    return sorted(int(i) for i in order[:k])


def random_selection(n: int, k: int, rng: np.random.Generator) -> list[int]:
    """A uniform random k-subset (drawn afresh at every selection epoch, spec §8 item 26)."""
    k = _check_k(k, n)
    return sorted(rng.choice(n, size=k, replace=False).tolist())


def closest_selection(positions: Array, target: Array, k: int) -> list[int]:
    """The k cameras nearest the predicted mean position (ties: lowest index)."""
    k = _check_k(k, len(positions))
    dist = np.hypot(*(np.asarray(positions, float) - np.asarray(target, float)).T)
    return sorted(np.argsort(dist, kind="stable")[:k].tolist())


def information_form_mse(sigma_x: Array, normals: Array, noise_var: Array) -> float:
    """``Tr((Sigma_x^-1 + sum_i a_i a_i' / var_i)^-1)``: the weak-perspective MSE when every
    camera surely sees the object (spec C10; equal to Eqs. 15-16 with all P{eta} = 1)."""
    info = np.linalg.inv(sigma_x) + (normals / noise_var[:, None]).T @ normals
    return float(np.trace(np.linalg.inv(info)))
