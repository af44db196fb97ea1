"""Rooms: a floor polygon, static occluders (polygons known exactly) and line-of-sight tests.

The line of sight from a camera to a point is blocked when the segment between them crosses a
wall of the room (only possible in a non-convex room, e.g. the L-shaped room of Ercan et al.
2013, Sec. 6.2) or a static occluder, or when the point lies inside a static occluder.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, invalid
from .geometry import (
    Array,
    as_polygon,
    is_convex,
    points_in_polygon,
    rectangle,
    signed_area,
)
from .occlusion_kernels import (
    points_in_polygon_kernel,
    segments_cross_edges_kernel,
    segments_cross_edges_paired_kernel,
)


def _in_polygon(points: ArrayLike, v: Array) -> NDArray[np.bool_]:
    """:func:`points_in_polygon` (same arithmetic) as a Numba loop, for any leading shape."""
    p = np.asarray(points, dtype=float)
    flat = np.ascontiguousarray(p.reshape(-1, 2))
    return np.asarray(points_in_polygon_kernel(flat, v).reshape(p.shape[:-1]))


def _sight_edges(
    boundary: Array, static_occluders: tuple[Array, ...], convex: bool
) -> tuple[Array, Array]:
    """Start and end points ``(E, 2)`` of the edges that can block sight: the walls of a
    non-convex room, then every static occluder's."""
    polys = ([] if convex else [boundary]) + list(static_occluders)
    if not polys:
        return np.zeros((0, 2)), np.zeros((0, 2))
    a = np.concatenate(list(polys))
    b = np.concatenate([np.concatenate([p[1:], p[:1]]) for p in polys])
    return np.ascontiguousarray(a), np.ascontiguousarray(b)


@dataclass(frozen=True)
class Room:
    """A floor polygon with static occluders inside it.

    ``boundary``: vertices ``(n, 2)`` of a simple polygon (any orientation; stored anticlockwise).
    ``static_occluders``: simple polygons that block sight and cannot be walked through; each
    must lie inside the room.
    """

    boundary: Array
    static_occluders: tuple[Array, ...] = ()
    name: str = "room"
    convex: bool = field(init=False)
    _free_area: float = field(init=False, repr=False, compare=False)
    _edges: tuple[Array, Array] = field(init=False, repr=False, compare=False)
    _box: tuple[float, float, float, float] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        b = as_polygon(self.boundary, "room.boundary")
        occ = tuple(
            as_polygon(o, f"room.static_occluders[{i}]")
            for i, o in enumerate(self.static_occluders)
        )
        for i, o in enumerate(occ):
            if not np.all(points_in_polygon(o, b)):
                raise ConfigError(
                    invalid(f"room.static_occluders[{i}]", o.tolist(), "a polygon inside the room")
                )
        object.__setattr__(self, "boundary", b)
        object.__setattr__(self, "static_occluders", occ)
        object.__setattr__(self, "convex", is_convex(b))
        area = signed_area(b) - sum(signed_area(o) for o in occ)
        object.__setattr__(self, "_free_area", area)  # sample_free needs it every call
        object.__setattr__(self, "_edges", _sight_edges(b, occ, self.convex))
        lo, hi = b.min(axis=0), b.max(axis=0)
        object.__setattr__(self, "_box", (float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1])))

    @property
    def bounding_box(self) -> tuple[float, float, float, float]:
        """``(xmin, xmax, ymin, ymax)``."""
        return self._box

    @property
    def center(self) -> Array:
        """Centre of the bounding box: where a tracker with no information puts an object."""
        x0, x1, y0, y1 = self.bounding_box
        return np.array([(x0 + x1) / 2, (y0 + y1) / 2])

    @property
    def free_area(self) -> float:
        return self._free_area

    def inside(self, points: ArrayLike) -> NDArray[np.bool_]:
        """Inside the floor polygon (static occluders ignored)."""
        return _in_polygon(points, self.boundary)

    def in_static_occluder(self, points: ArrayLike) -> NDArray[np.bool_]:
        p = np.asarray(points, dtype=float)
        out = np.zeros(p.shape[:-1], dtype=bool)
        for o in self.static_occluders:
            out |= _in_polygon(p, o)
        return out

    def free(self, points: ArrayLike) -> NDArray[np.bool_]:
        """Inside the room and outside every static occluder: where objects may stand."""
        if not self.static_occluders:  # the common case, asked every prediction step
            return self.inside(points)
        return self.inside(points) & ~self.in_static_occluder(points)

    def sight_blocked(self, viewer: ArrayLike, points: ArrayLike) -> NDArray[np.bool_]:
        """True where walls or static occluders block the segment ``viewer -> points``.

        Both arguments broadcast (``(..., 2)``). A point inside a static occluder is blocked.
        """
        v = np.asarray(viewer, dtype=float)
        p = np.asarray(points, dtype=float)
        shape = np.broadcast_shapes(v.shape, p.shape)
        ea, eb = self._edges
        if len(ea):  # walls (non-convex room) and static occluders, one Numba pass
            starts = np.ascontiguousarray(np.broadcast_to(v, shape).reshape(-1, 2))
            ends = np.ascontiguousarray(np.broadcast_to(p, shape).reshape(-1, 2))
            blocked = segments_cross_edges_paired_kernel(starts, ends, ea, eb).reshape(shape[:-1])
        else:
            blocked = np.zeros(shape[:-1], dtype=bool)
        for o in self.static_occluders:
            blocked |= points_in_polygon(p, o)
        return np.asarray(blocked)

    def sight_blocked_grid(self, viewers: ArrayLike, points: ArrayLike) -> NDArray[np.bool_]:
        """``(K, L)`` :meth:`sight_blocked` for every viewer ``(K, 2)`` and point ``(L, 2)`` (Numba)."""
        v = np.ascontiguousarray(np.asarray(viewers, float).reshape(-1, 2))
        p = np.ascontiguousarray(np.asarray(points, float).reshape(-1, 2))
        ea, eb = self._blocking_edges
        blocked = (
            segments_cross_edges_kernel(v, p, ea, eb)
            if len(ea)
            else np.zeros((len(v), len(p)), bool)
        )
        if self.static_occluders:
            blocked |= self.in_static_occluder(p)[None, :]
        return np.asarray(blocked)

    @property
    def _blocking_edges(self) -> tuple[Array, Array]:
        """Start and end points ``(E, 2)`` of every edge that can block sight (made once)."""
        return self._edges

    def segment_free(self, start: ArrayLike, end: ArrayLike) -> NDArray[np.bool_]:
        """True where an object can walk straight from ``start`` to ``end``."""
        return ~self.sight_blocked(start, end) & self.free(end)

    def sample_free(self, rng: np.random.Generator, n: int) -> Array:
        """``n`` points uniform over the free floor (rejection from the bounding box)."""
        x0, x1, y0, y1 = self._box
        accept = max(self._free_area / ((x1 - x0) * (y1 - y0)), 1e-3)
        parts: list[Array] = []
        got = 0
        for _ in range(1000):
            m = int(1.3 * (n - got) / accept) + 8
            cand = np.empty((m, 2))
            cand[:, 0] = rng.uniform(x0, x1, m)
            cand[:, 1] = rng.uniform(y0, y1, m)
            parts.append(cand[self.free(cand)])
            got += len(parts[-1])
            if got >= n:  # almost always after the first round
                return np.concatenate(parts)[:n]
        raise ConfigError(
            invalid("room", self.name, "a room with free floor area")
        )  # pragma: no cover


def square_room(
    side: float = 100.0, static_occluders: Sequence[ArrayLike] = (), name: str = "square"
) -> Room:
    """Square room ``[0, side]^2`` (Ercan et al. 2013, Sec. 6.1: side 100 units)."""
    return Room(
        rectangle(0, side, 0, side), tuple(np.asarray(o, float) for o in static_occluders), name
    )


def l_shaped_room(size: float = 200.0) -> Room:
    """The L-shaped room of Fig. 11 (spec default): a ``size`` square minus its upper-right quarter."""
    h = size / 2
    return Room(
        np.array([[0, 0], [size, 0], [size, h], [h, h], [h, size], [0, size]], dtype=float),
        (),
        "L-shaped",
    )
