"""Plane geometry for rooms and occluders: polygons, segments and discs, vectorised over points.

Every function takes points as arrays ``(..., 2)`` and broadcasts the leading axes, so one call
tests a whole particle cloud against a camera (``(L, 2)`` against ``(2,)``) or every camera
against every particle (``(K, 1, 2)`` against ``(1, L, 2)``).

Segment tests are *proper*: two segments that only touch at an end point, or run along each
other, do not cross. A camera standing exactly on a wall therefore does not block its own view
(rooms still inset their cameras a little, see :mod:`fusetrack.world.room`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, ShapeError, invalid

Array = NDArray[np.float64]


def as_polygon(vertices: ArrayLike, field: str = "polygon") -> Array:
    """Vertices ``(n, 2)`` of a simple polygon, anticlockwise; :class:`ConfigError` otherwise.

    A polygon must have at least three finite vertices, a non-zero area and no two non-adjacent
    edges that cross (a simple polygon). A clockwise polygon is reversed; a repeated closing
    vertex is dropped.
    """
    try:
        v = np.array(vertices, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(invalid(field, vertices, "a list of [x, y] vertices")) from None
    if v.ndim != 2 or v.shape[1] != 2:
        raise ShapeError(invalid(f"{field}.shape", v.shape, "(n, 2) with n >= 3"))
    if len(v) > 3 and np.allclose(v[0], v[-1]):
        v = v[:-1]
    if len(v) < 3:
        raise ConfigError(invalid(field, v.tolist(), "at least 3 vertices"))
    if not np.all(np.isfinite(v)):
        raise ConfigError(invalid(field, v.tolist(), "finite vertices"))
    area = signed_area(v)
    if abs(area) <= 1e-12 * max(1.0, float(np.abs(v).max()) ** 2):
        raise ConfigError(invalid(field, v.tolist(), "a polygon with non-zero area"))
    if not is_simple(v):
        raise ConfigError(
            invalid(field, v.tolist(), "a simple polygon (no two edges cross or touch)")
        )
    return v if area > 0 else v[::-1].copy()


def signed_area(v: Array) -> float:
    """Shoelace area: positive for anticlockwise vertices."""
    x, y = v[:, 0], v[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def edges(v: Array) -> tuple[Array, Array]:
    """Start and end points ``(n, 2)`` of the polygon's edges."""
    return v, np.concatenate([v[1:], v[:1]])


def is_simple(v: Array) -> bool:
    """True if no two non-adjacent edges of the closed polygon ``v`` intersect (touching counts)."""
    a, b = edges(v)
    n = len(v)
    for i in range(n):
        for j in range(i + 1, n):
            if j == i + 1 or (i == 0 and j == n - 1):
                continue
            if _segments_touch(a[i], b[i], a[j], b[j]):
                return False
    # adjacent edges folding back onto each other (a spike) also make a non-simple polygon
    for i in range(n):
        p, q, r = v[i - 1], v[i], v[(i + 1) % n]
        if abs(_cross(q - p, r - q)) < 1e-12 and np.dot(q - p, r - q) < 0:
            return False
    return True


def _cross(u: Array, w: Array) -> Array:
    return u[..., 0] * w[..., 1] - u[..., 1] * w[..., 0]


def _segments_touch(p1: Array, p2: Array, q1: Array, q2: Array) -> bool:
    """Closed-segment intersection (touching and collinear overlap count)."""
    d1 = _cross(q2 - q1, p1 - q1)
    d2 = _cross(q2 - q1, p2 - q1)
    d3 = _cross(p2 - p1, q1 - p1)
    d4 = _cross(p2 - p1, q2 - p1)
    if ((d1 > 0) != (d2 > 0)) and ((d3 > 0) != (d4 > 0)) and d1 * d2 < 0 and d3 * d4 < 0:
        return True

    def on(a: Array, b: Array, c: Array, d: Any) -> bool:
        return (
            abs(d) < 1e-12
            and min(a[0], b[0]) - 1e-12 <= c[0] <= max(a[0], b[0]) + 1e-12
            and min(a[1], b[1]) - 1e-12 <= c[1] <= max(a[1], b[1]) + 1e-12
        )

    return bool(
        on(q1, q2, p1, d1) or on(q1, q2, p2, d2) or on(p1, p2, q1, d3) or on(p1, p2, q2, d4)
    )


def points_in_polygon(points: ArrayLike, v: Array) -> NDArray[np.bool_]:
    """Even-odd (ray casting) test of ``points`` ``(..., 2)`` against polygon ``v``; ``(...)``.

    Points exactly on an edge may fall either way.
    """
    p = np.asarray(points, dtype=float)
    x, y = p[..., 0, None], p[..., 1, None]
    a, b = edges(v)
    ax, ay, bx, by = a[:, 0], a[:, 1], b[:, 0], b[:, 1]
    straddle = (ay > y) != (by > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = ax + (y - ay) * (bx - ax) / (by - ay)
    hits = straddle & (x < x_cross)
    return np.asarray(np.count_nonzero(hits, axis=-1) % 2 == 1)


def segments_cross_polygon(start: ArrayLike, end: ArrayLike, v: Array) -> NDArray[np.bool_]:
    """True where the open segment ``start -> end`` properly crosses an edge of polygon ``v``.

    ``start`` and ``end`` broadcast against each other (``(..., 2)``); the result has their
    broadcast leading shape. Touching a vertex or running along an edge is not a crossing.
    """
    s = np.asarray(start, dtype=float)[..., None, :]
    e = np.asarray(end, dtype=float)[..., None, :]
    a, b = edges(v)
    seg = e - s
    edge = b - a
    d1 = _cross(edge, s - a)
    d2 = _cross(edge, e - a)
    d3 = _cross(seg, a - s)
    d4 = _cross(seg, b - s)
    crosses = (d1 * d2 < 0) & (d3 * d4 < 0)
    return np.asarray(np.any(crosses, axis=-1))


def segment_point_distance(start: ArrayLike, end: ArrayLike, points: ArrayLike) -> Array:
    """Distance from ``points`` to the closed segments ``start -> end`` (all broadcast, ``(..., 2)``)."""
    s = np.asarray(start, dtype=float)
    e = np.asarray(end, dtype=float)
    p = np.asarray(points, dtype=float)
    seg = e - s
    length_sq = np.sum(seg * seg, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.sum((p - s) * seg, axis=-1) / length_sq
    t = np.clip(np.nan_to_num(t, nan=0.0), 0.0, 1.0)
    closest = s + t[..., None] * seg
    return np.asarray(np.linalg.norm(p - closest, axis=-1))


def rectangle(x0: float, x1: float, y0: float, y1: float) -> Array:
    """Axis-aligned rectangle ``[x0, x1] x [y0, y1]`` as an anticlockwise polygon."""
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)


def is_convex(v: Array) -> bool:
    """True for a convex (anticlockwise) polygon."""
    a = np.roll(v, 1, axis=0)
    c = np.roll(v, -1, axis=0)
    return bool(np.all(_cross(v - a, c - v) >= -1e-12))
