"""People walking on a floor: one walker model for every simulated scene.

A :class:`Walk` is one person's floor positions ``xy (T, 2)`` at ``times (T,)``; it is made
either along a scripted path (:func:`polyline_walk`, the Nott 2009 rendered videos) or by
:class:`WaypointWalkers`, people walking between random waypoints and going around each other
(Ercan et al. 2013, Sec. 6), whose whole crowd moves at once.

Random waypoints (procedure ``move_objects``): each walker heads for a destination at a constant
speed ``s`` with white Gaussian noise,

    x(t) = x(t-1) + s (tau - x(t-1)) / |tau - x(t-1)| + v(t),  v ~ N(0, sigma^2 I)   # Eq. 5 form

and picks a new destination, uniform over the free floor and reachable in a straight line, when
it has arrived (distance < s) or when its next step would leave the room or enter a static
occluder (spec §8 items 19-21). Walkers go around each other instead of colliding: a step that
would bring a walker's centre within ``D`` of another one is turned by +-15, +-30, ..., +-90
degrees, and a walker that finds no free heading stands still for one step (spec §8 item 20).
Two additions keep a crowd from jamming for good: turns continue past 90 degrees up to straight
back, and a walker that had to stand still picks a new destination.
All walkers move at once (each tests its step against the others' current positions).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, check_positive, invalid
from .geometry import Array
from .room import Room


@dataclass(frozen=True)
class Walk:
    """Foot positions ``xy`` ``(T, 2)`` at ``times`` ``(T,)`` (s) of one person."""

    times: Array
    xy: Array

    @property
    def velocity(self) -> Array:
        return (
            np.gradient(self.xy, self.times, axis=0)
            if len(self.times) > 1
            else np.zeros_like(self.xy)
        )


def polyline_walk(waypoints: ArrayLike, speed: float, fps: float, t0: float = 0.0) -> Walk:
    """Constant-speed walk through ``waypoints`` ``(K, 2)``, sampled at ``fps``."""
    w = np.asarray(waypoints, float)
    if w.ndim != 2 or w.shape[1] != 2 or len(w) < 2:
        raise ConfigError(invalid("waypoints", w.tolist(), "(K >= 2, 2) floor points"))
    seg = np.linalg.norm(np.diff(w, axis=0), axis=1)
    s_way = np.concatenate([[0.0], np.cumsum(seg)])
    n = int(np.floor(s_way[-1] / speed * fps)) + 1
    s = np.arange(n) * speed / fps
    xy = np.column_stack([np.interp(s, s_way, w[:, 0]), np.interp(s, s_way, w[:, 1])])
    return Walk(t0 + np.arange(n) / fps, xy)


def first_free_heading_reference(
    cand: Array, ok: NDArray[np.bool_], pos: Array, min_gap2: float
) -> NDArray[np.intp]:
    """NumPy reference of :func:`first_free_heading_kernel`: all ``(n, T, n)`` gaps at once."""
    n = len(pos)
    diff = cand[:, :, None, :] - pos[None, None, :, :]
    gap2 = np.einsum("ntmk,ntmk->ntm", diff, diff)  # (n, T, n)
    gap2[np.arange(n), :, np.arange(n)] = np.inf
    free = ok & np.all(gap2 >= min_gap2, axis=-1)
    return np.asarray(np.where(free.any(axis=1), np.argmax(free, axis=1), -1))


@numba.njit(cache=True, nogil=True)
def first_free_heading_kernel(
    cand: np.ndarray, ok: np.ndarray, pos: np.ndarray, min_gap2: float
) -> np.ndarray:  # pragma: no cover - jit
    """Per walker, the first candidate step (in the order of ``_TURNS``) that the room allows and
    that keeps its centre at least ``sqrt(min_gap2)`` from every other walker; -1 if none. Stops
    at the first free heading instead of testing all ``(n, T, n)`` gaps."""
    n, n_turns = cand.shape[0], cand.shape[1]
    out = np.full(n, -1, dtype=np.intp)
    for a in range(n):
        for t in range(n_turns):
            if not ok[a, t]:
                continue
            cx, cy = cand[a, t, 0], cand[a, t, 1]
            free = True
            for b in range(n):
                if b == a:
                    continue
                dx, dy = cx - pos[b, 0], cy - pos[b, 1]
                if dx * dx + dy * dy < min_gap2:
                    free = False
                    break
            if free:
                out[a] = t
                break
    return out


_TURNS_SPEC = (0, 15, -15, 30, -30, 45, -45, 60, -60, 75, -75, 90, -90)  # spec §8 item 20
_TURNS_BACK = (105, -105, 120, -120, 135, -135, 150, -150, 165, -165, 180)
_TURNS = np.deg2rad(np.array([*_TURNS_SPEC, *_TURNS_BACK], float))
"""Headings tried in order: straight on, then turned away by growing angles up to +-90 degrees
(spec §8 item 20), then further round to straight back. The turns beyond 90 degrees are ours: with
+-90 only, a crowd jams for good (two walkers heading at each other with others beside them can
never move again; at M = 150 in the 100 x 100 room 95% of the walkers stood still)."""


@dataclass(frozen=True)
class WaypointWalkers:
    """Random-waypoint walkers of diameter ``diameter`` in ``room``; the first may be the object."""

    room: Room
    speed: float = 1.0
    noise: float = 0.33
    diameter: float = 3.33
    avoid: bool = True

    def __post_init__(self) -> None:
        check_positive("speed", self.speed)
        check_positive("noise", self.noise, allow_zero=True)
        check_positive("diameter", self.diameter, allow_zero=True)

    def initial(self, n: int, rng: np.random.Generator) -> tuple[Array, Array]:
        """Positions and destinations ``(n, 2)``: uniform over the free floor, no two closer than D."""
        pos = np.empty((0, 2))
        for _ in range(200):
            cand = self.room.sample_free(rng, max(2 * (n - len(pos)), 4))
            for c in cand:
                if len(pos) >= n:
                    break
                if len(pos) == 0 or np.min(np.hypot(*(pos - c).T)) >= self.diameter:
                    pos = np.vstack([pos, c])
            if len(pos) >= n:
                break
        dest = self._destinations(pos, rng)
        return pos, dest

    def _destinations(self, pos: Array, rng: np.random.Generator) -> Array:
        """A destination for each walker, uniform over the free floor and in straight sight."""
        dest = self.room.sample_free(rng, len(pos))
        if self.room.convex and not self.room.static_occluders:
            return dest
        todo = ~self.room.segment_free(pos, dest)
        for _ in range(100):
            if not todo.any():
                break
            dest[todo] = self.room.sample_free(rng, int(todo.sum()))
            todo[todo] = ~self.room.segment_free(pos[todo], dest[todo])
        return dest

    def step(self, pos: Array, dest: Array, rng: np.random.Generator) -> tuple[Array, Array]:
        """One time step for every walker; returns new positions and destinations."""
        n = len(pos)
        dest = dest.copy()
        noise = self.noise * rng.standard_normal((n, 2))
        to_dest = dest - pos
        dist = np.hypot(to_dest[:, 0], to_dest[:, 1])
        heading = np.arctan2(to_dest[:, 1], to_dest[:, 0])
        cand, ok = self._candidates(pos, heading, noise)
        change = (dist < self.speed) | ~ok[:, 0]
        if change.any():  # CD regime: a new destination, then an MTD step towards it
            dest[change] = self._destinations(pos[change], rng)
            d = dest[change] - pos[change]
            cand[change], ok[change] = self._candidates(
                pos[change], np.arctan2(d[:, 1], d[:, 0]), noise[change]
            )
        if self.avoid and n > 1:
            first = first_free_heading_kernel(
                np.ascontiguousarray(cand), np.ascontiguousarray(ok), pos, self.diameter**2
            )
        else:
            first = np.where(ok.any(axis=1), np.argmax(ok, axis=1), -1)
        found = first >= 0
        new = np.where(found[:, None], cand[np.arange(n), np.maximum(first, 0)], pos)
        if not found.all():  # boxed in: stand still this step and pick another destination
            dest[~found] = self._destinations(pos[~found], rng)
        return new, dest

    def _candidates(
        self, pos: Array, heading: Array, noise: Array
    ) -> tuple[Array, NDArray[np.bool_]]:
        """Steps straight on and turned away by growing angles ``(n, T, 2)``, and which are free."""
        ang = heading[:, None] + _TURNS[None, :]
        cand = pos[:, None, :] + self.speed * np.stack([np.cos(ang), np.sin(ang)], -1)
        cand += noise[:, None, :]
        return cand, self.room.segment_free(pos[:, None, :], cand)

    def trajectory(self, n: int, steps: int, rng: np.random.Generator) -> Array:
        """Positions ``(steps + 1, n, 2)``; row 0 is the start."""
        pos, dest = self.initial(n, rng)
        out = np.empty((steps + 1, n, 2))
        out[0] = pos
        for t in range(1, steps + 1):
            pos, dest = self.step(pos, dest, rng)
            out[t] = pos
        return out

    def walks(self, n: int, steps: int, dt: float, rng: np.random.Generator) -> list[Walk]:
        """The :meth:`trajectory` of ``n`` walkers as one :class:`Walk` each, a step every ``dt`` s."""
        xy = self.trajectory(n, steps, rng)
        times = dt * np.arange(steps + 1, dtype=np.float64)
        return [Walk(times, np.ascontiguousarray(xy[:, i])) for i in range(n)]
