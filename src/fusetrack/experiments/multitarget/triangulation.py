"""Candidate points from unlabelled bearings: every pair of bearings of two arrays, intersected.

Two arrays at ``s_a``, ``s_b`` reporting bearings ``z_a``, ``z_b`` (global frame) see one point
``p = s_a + r_a u(z_a) = s_b + r_b u(z_b)``, ``u(z) = (cos z, sin z)``, a 2x2 linear system in
the ranges. The intersection is kept when both ranges are positive (in front of both arrays),
the rays cross at more than ``min_angle`` (near-parallel rays give points far along the
baseline) and the point lies in the field. With ``n`` targets and no clutter a pair of arrays
gives up to ``n^2`` points: ``n`` true ones and ``n (n - 1)`` *ghosts* (the intersection of
target i's bearing from one array with target j's from the other).

Covariance (first order): the point solves ``h(p) = z`` with ``h`` the two bearings; with
``H = dh/dp`` (rows ``[-d_y, d_x] / r^2``, as :meth:`fusetrack.sensors.Bearing.jacobian`) and
``R = diag(sigma_a^2, sigma_b^2)``, ``Cov p = H^-1 R H^-T = (H^T R^-1 H)^-1``, the inverse Fisher
information of the two bearings at ``p`` (Bar-Shalom, Li & Kirubarajan 2001, Sec. 3.7: the
linearised transformation of a Gaussian). It grows like ``r^2 / sin^2(crossing angle)``.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ...core import Measurement
from .scenario import Array, Scene, Truth

MIN_ANGLE = np.deg2rad(5.0)


def intersect(sa: Array, za: float, sb: Array, zb: float) -> tuple[Array, float, float] | None:
    """The point where the rays from ``sa`` at bearing ``za`` and from ``sb`` at ``zb`` meet,
    with the two ranges; None when the rays are parallel."""
    ua = np.array([np.cos(za), np.sin(za)])
    ub = np.array([np.cos(zb), np.sin(zb)])
    m = np.column_stack([ua, -ub])
    det = float(np.linalg.det(m))
    if abs(det) < 1e-12:
        return None
    ra, rb = np.linalg.solve(m, np.asarray(sb, float) - np.asarray(sa, float))
    return np.asarray(sa, float) + ra * ua, float(ra), float(rb)


def triangulation_cov(p: Array, sa: Array, sb: Array, sigma_a: float, sigma_b: float) -> Array:
    """``(H^T R^-1 H)^-1`` of the two bearings at ``p`` (module docstring), ``(2, 2)``."""
    d = np.asarray(p, float)[None, :] - np.stack([np.asarray(sa, float), np.asarray(sb, float)])
    h = np.column_stack([-d[:, 1], d[:, 0]]) / np.sum(d * d, axis=1)[:, None]  # Bearing.jacobian
    info = h.T @ np.diag([sigma_a**-2, sigma_b**-2]) @ h
    cov = np.linalg.inv(info)
    return 0.5 * (cov + cov.T)


@dataclass(frozen=True)
class Candidate:
    """One intersection: its point and covariance, and the bearings (array, index) behind it."""

    point: Array
    cov: Array
    pair: tuple[str, str]
    bearings: tuple[int, int]


def pair_id(a: str, b: str) -> str:
    """The sensor id of the points triangulated from arrays ``a`` and ``b``."""
    return f"tri:{a}-{b}"


def pair_candidates(
    scene: Scene, scan: dict[str, Array], a: str, b: str, min_angle: float = MIN_ANGLE
) -> list[Candidate]:
    """Every valid intersection of a bearing of ``a`` with one of ``b`` (module docstring)."""
    sa, sb = scene.position(a), scene.position(b)
    out = []
    for (i, za), (j, zb) in itertools.product(enumerate(scan[a]), enumerate(scan[b])):
        if abs(np.sin(za - zb)) < np.sin(min_angle):
            continue
        hit = intersect(sa, float(za), sb, float(zb))
        if hit is None or hit[1] <= 0 or hit[2] <= 0 or not scene.grid.contains(hit[0]):
            continue
        cov = triangulation_cov(hit[0], sa, sb, scene.sigma, scene.sigma)
        out.append(Candidate(hit[0], cov, (a, b), (i, j)))
    return out


def scan_candidates(scene: Scene, scan: dict[str, Array]) -> list[Candidate]:
    """Candidates of every pair of arrays of one scan."""
    ids = [sid for sid, _, _ in scene.arrays]
    return [
        c for a, b in itertools.combinations(ids, 2) for c in pair_candidates(scene, scan, a, b)
    ]


def as_measurements(time: float, candidates: list[Candidate]) -> list[Measurement]:
    """Position measurements (one sensor per pair of arrays) with their own covariances."""
    return [Measurement(time, pair_id(*c.pair), c.point, covariance=c.cov) for c in candidates]


def count_ghosts(points: NDArray[np.float64], truth: NDArray[np.float64], radius: float) -> int:
    """Points farther than ``radius`` from every true position (ghosts, or clutter)."""
    p = np.asarray(points, float).reshape(-1, 2)
    t = np.asarray(truth, float).reshape(-1, 2)
    if p.shape[0] == 0:
        return 0
    if t.shape[0] == 0:
        return int(p.shape[0])
    d = np.linalg.norm(p[:, None, :] - t[None, :, :], axis=-1)
    return int(np.sum(d.min(axis=1) > radius))


def candidate_counts(
    scene: Scene, truth: Truth, candidates: list[list[Candidate]], radius: float
) -> tuple[float, float]:
    """Mean true and ghost candidates per scan (a candidate within ``radius`` of a target is true)."""
    ghosts = [
        count_ghosts(np.array([c.point for c in cs]), truth.present(k), radius)
        for k, cs in enumerate(candidates)
    ]
    totals = [len(cs) for cs in candidates]
    g = float(np.mean(ghosts)) if ghosts else 0.0
    return float(np.mean(totals)) - g if totals else 0.0, g
