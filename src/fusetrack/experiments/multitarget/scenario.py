"""The scenario: several targets crossing Kushwaha's field, seen by 2 or 3 bearing arrays.

The field, the cell size, the fusion rate and the array positions are those of Kushwaha 2010's
simulated road (:mod:`fusetrack.experiments.kushwaha2010.scene`: a 35 m x 20 m field, 0.5 m
cells, 4 Hz, acoustic nodes at x = 5, 17.5, 30 m on y = 4 m and y = 16 m); the arrays used are
``A1`` (5, 4) and ``A6`` (30, 16) on opposite corners, and ``A3`` (30, 4) as the third. Each array reports, every
scan, an *unlabelled* set of bearings (:func:`fusetrack.sensors.simulate_bearings`, Lee 2009
Sec. 3.2): each target's bearing with probability ``p_detect`` (two closer than 2 degrees
merge), Gaussian noise ``sigma``, plus a Poisson number of clutter bearings, uniform on the
circle, shuffled.

Targets move on straight lines at constant speed across the field, alternately eastwards and
westwards, between random heights: most pairs cross.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ...core import Track
from ...filters import GridSpec
from ...sensors import simulate_bearings
from ..kushwaha2010 import DT, default_layout

Array = NDArray[np.float64]
ARRAYS_USED = ("A1", "A6", "A3")  # the first n of these (Kushwaha's acoustic nodes)


@dataclass(frozen=True)
class Scene:
    """What one run needs to know about the world: the field, the arrays used, the noise."""

    grid: GridSpec
    arrays: tuple[tuple[str, float, float], ...]  # (id, x, y)
    sigma: float  # bearing noise std (rad)
    p_detect: float
    clutter: float  # clutter bearings per array per scan (Poisson mean)
    dt: float = DT

    @property
    def area(self) -> float:
        g = self.grid
        return (g.x1 - g.x0) * (g.y1 - g.y0)

    def position(self, array_id: str) -> Array:
        for sid, x, y in self.arrays:
            if sid == array_id:
                return np.array([x, y])
        raise KeyError(array_id)


def make_scene(n_arrays: int, sigma_deg: float, p_detect: float, clutter: float) -> Scene:
    """Kushwaha's field with the first ``n_arrays`` of :data:`ARRAYS_USED`."""
    layout = default_layout()
    nodes = {sid: (x, y) for sid, x, y, _ in layout.audio}
    arrays = tuple((sid, *nodes[sid]) for sid in ARRAYS_USED[:n_arrays])
    return Scene(layout.grid, arrays, np.deg2rad(sigma_deg), p_detect, clutter)


@dataclass(frozen=True)
class Truth:
    """True positions ``(K, n, 2)`` at the scan times ``(K,)``, NaN while a target is absent."""

    times: Array
    positions: Array

    def present(self, k: int) -> Array:
        p = self.positions[k]
        return p[np.all(np.isfinite(p), axis=1)]

    def tracks(self) -> list[Track]:
        """One :class:`Track` per target (``id`` = target index) over the scans it is present."""
        out = []
        for i in range(self.positions.shape[1]):
            on = np.all(np.isfinite(self.positions[:, i]), axis=1)
            out.append(Track(self.times[on], self.positions[on, i], label=f"target {i}", id=i))
        return out


def simulate_truth(
    scene: Scene, n_targets: int, duration: float, rng: np.random.Generator
) -> Truth:
    """Straight crossings: target ``i`` enters at one end of the field (west for even ``i``,
    east for odd) at a uniform height in [3, 17] m, heads for a uniform height at the other
    end at 2-3.5 m/s, starting at a uniform time in [0, 2] s; absent outside the field."""
    g = scene.grid
    times = np.arange(0.0, duration + 1e-9, scene.dt)
    pos = np.full((times.size, n_targets, 2), np.nan)
    for i in range(n_targets):
        x0, x1 = (g.x0 + 0.5, g.x1 - 0.5) if i % 2 == 0 else (g.x1 - 0.5, g.x0 + 0.5)
        y0, y1 = rng.uniform(3.0, 17.0, 2)
        speed = rng.uniform(2.0, 3.5)
        t0 = rng.uniform(0.0, 2.0)
        length = float(np.hypot(x1 - x0, y1 - y0))
        s = (times - t0) * speed / length  # fraction of the path done
        on = (s >= 0) & (s <= 1)
        pos[on, i, 0] = x0 + s[on] * (x1 - x0)
        pos[on, i, 1] = y0 + s[on] * (y1 - y0)
    return Truth(times, pos)


def simulate_scans(scene: Scene, truth: Truth, rng: np.random.Generator) -> list[dict[str, Array]]:
    """Per scan, per array: the unlabelled bearing set (global frame, radians, shuffled)."""
    scans = []
    for k in range(truth.times.size):
        present = truth.present(k)
        scan = {}
        for sid, x, y in scene.arrays:
            heard = rng.random(len(present)) < scene.p_detect
            z = simulate_bearings(present, heard, (x, y), scene.sigma, rng)
            clutter = rng.uniform(-np.pi, np.pi, rng.poisson(scene.clutter))
            scan[sid] = rng.permutation(np.concatenate([z, clutter]))
        scans.append(scan)
    return scans
