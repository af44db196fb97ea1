"""The node's grid (``tracker.filter: grid``; Kushwaha 2010, Ch. III): cells over the network's
``area``, the readings as per-cell likelihood maps, the prior on the cells and the grid filter.

The node's engine (:mod:`.engine`) runs :class:`~fusetrack.filters.grid.GridFilter` like any
other filter: directional motion (Eq. 29), then the product (Eq. 30) or quality-weighted sum
(Eq. 31) of the sensors' per-cell likelihoods. Each reading of a tick gives one likelihood map
(:class:`CellLikelihoods`):

* a ``detection_function`` (beam energies of a microphone array, per-column scores of a camera):
  the mean of the piecewise-linear detection function over the arc each cell subtends at the
  sensor (Eq. 32 with the Eq. 34 interpolant, :func:`~fusetrack.sensors.arc_mean_matrix`),
  quality ``q = max(lambda - min) / sum(lambda - min)`` (spec 003 A-III-11);
* any other reading (bearing, DOA, range, position fix, a camera's image position through its
  homography): the sensor model's own likelihood ``p(z | x)`` at each cell centre;

both floored and normalised (:func:`~fusetrack.sensors.detection_function.normalize_likelihood`)
so that no cell is ever ruled out. The maps travel to the filter as measurements (value: the
map, ``metadata["quality"]``), interpreted by one
:class:`~fusetrack.sensors.likelihood_map.LikelihoodMapSensor` per sensor. The grid filter fuses
every reading of a tick at the tick time (Kushwaha 2010 fuses at 4 Hz the same way); a tick
without readings predicts only. Everything is deterministic, so live and offline runs over the
same readings agree exactly.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ..filters.grid import (
    DirectionalMotion,
    GridFilter,
    GridSpec,
    SensorLikelihoods,
    fuse,
    map_sensors,
)
from ..sensors.detection_function import arc_mean_matrix, cell_arcs, normalize_likelihood
from ..sensors.likelihood_map import detection_quality
from .alignment import Reading
from .config import DetectionFunctionSensor, NetworkConfig

Array = NDArray[np.float64]


def grid_of(cfg: NetworkConfig) -> GridSpec:
    x0, x1, y0, y1 = cfg.area
    return GridSpec(x0, x1, y0, y1, cfg.tracker.grid.cell)


class CellLikelihoods:
    """Per-cell likelihood and quality of one reading (see the module docstring)."""

    def __init__(self, cfg: NetworkConfig, grid: GridSpec) -> None:
        self.grid = grid
        self.models = cfg.sensor_models()
        d = cfg.tracker.motion.build().dim
        self.states = np.zeros((grid.size, d))  # cell centres as states (velocities 0)
        self.states[:, :2] = grid.centres
        self.arc_means: dict[str, Array] = {}
        for sid, model in self.models.items():
            if isinstance(model, DetectionFunctionSensor):
                lo, hi, _ = cell_arcs(model.position, model.heading, grid.centres, grid.cell / 2)
                self.arc_means[sid] = arc_mean_matrix(model.sampling, lo, hi)

    def __call__(self, reading: Reading) -> tuple[Array, float] | None:
        """``(likelihood (cells,), quality)``, or None for a detection function that is flat
        (the sensor saw nothing)."""
        w = self.arc_means.get(reading.sensor)
        if w is not None:
            v = np.asarray(reading.value, float)
            q = detection_quality(v)
            return None if q is None else (normalize_likelihood(w @ v), q)
        model = self.models[reading.sensor]
        if reading.covariance is not None:  # a reading's own noise: the Gaussian it implies
            z_pred = model.predict(self.states)
            r = model.residual(reading.value, z_pred)
            sol = np.linalg.solve(reading.covariance, r.T).T
            ll = -0.5 * np.sum(r * sol, axis=-1)
        else:
            ll = np.asarray(model.log_likelihood(reading.value, self.states), float)
        lik = np.exp(ll - ll.max())
        lik = normalize_likelihood(lik)
        q = detection_quality(lik)
        return lik, 0.0 if q is None else q

    def of(self, readings: Sequence[Reading]) -> SensorLikelihoods:
        """The tick's readings as the grid filter's input (one row per informative reading)."""
        rows = [(r.sensor, lq) for r, lq in ((r, self(r)) for r in readings) if lq is not None]
        if not rows:
            return SensorLikelihoods(np.empty((0, self.grid.size)), np.empty(0), ())
        return SensorLikelihoods(
            np.array([lk for _, (lk, _) in rows]),
            np.array([q for _, (_, q) in rows]),
            ("all",) * len(rows),
            tuple(sid for sid, _ in rows),
        )

    def fused(self, readings: Sequence[Reading], rule: str) -> Array | None:
        """The tick's readings fused without any temporal prior (``(nx, ny)``), or None."""
        lik = self.of(readings)
        if lik.values.shape[0] == 0:
            return None
        return fuse(lik.values, lik.quality, rule).reshape(self.grid.shape)  # type: ignore[arg-type]


def grid_filter(cfg: NetworkConfig, grid: GridSpec) -> GridFilter:
    """The configured grid filter over every sensor's likelihood maps (one modality)."""
    g = cfg.tracker.grid
    return GridFilter(
        grid,
        map_sensors(grid, [s.id for s in cfg.sensors]),
        g.fusion,
        motion=DirectionalMotion(g.delta),
        first_delta=2 * g.delta,
        max_speed=g.max_speed,
    )


def grid_prior(cfg: NetworkConfig, grid: GridSpec) -> Array:
    """The configured Gaussian prior on the position, evaluated on the cells."""
    m = np.asarray(cfg.tracker.prior_mean[:2], float)
    sd = np.maximum(np.asarray(cfg.tracker.prior_std[:2], float), grid.cell)
    u = (grid.centres - m) / sd
    p = np.exp(-0.5 * np.sum(u * u, axis=1))
    return p if p.sum() > 0 else grid.uniform()
