"""The grid tracker inside the node: Kushwaha 2010's sequential Bayesian estimation on a grid.

``tracker.filter: grid`` keeps the target's position as a probability per cell of the network's
``area`` (:class:`~fusetrack.filters.grid.GridTracker`: directional motion, Eq. 29, then the
product, Eq. 30, or quality-weighted sum, Eq. 31, of the sensors' per-cell likelihoods). Each
reading of a tick gives one per-cell likelihood (:class:`CellLikelihoods`):

* a ``detection_function`` (beam energies of a microphone array, per-column scores of a camera):
  the mean of the piecewise-linear detection function over the arc each cell subtends at the
  sensor (Eq. 32 with the Eq. 34 interpolant, :func:`~fusetrack.sensors.arc_mean_matrix`),
  quality ``q = max(lambda - min) / sum(lambda - min)`` (spec 003 A-III-11);
* any other reading (bearing, DOA, range, position fix, a camera's image position through its
  homography): the sensor model's own likelihood ``p(z | x)`` at each cell centre;

both floored and normalised (:func:`~fusetrack.sensors.detection_function.normalize_likelihood`)
so that no cell is ever ruled out. One grid step per tick fuses every reading of the tick at the
tick time (Kushwaha 2010 fuses at 4 Hz the same way); a tick without readings predicts only.
The published state is the posterior mean ``[x, y]`` and covariance over the cells.
Everything is deterministic, so live and offline runs over the same readings agree exactly.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ..filters.grid import DirectionalMotion, GridSpec, GridTracker, SensorLikelihoods, fuse
from ..sensors.detection_function import arc_mean_matrix, cell_arcs, normalize_likelihood
from .alignment import Reading
from .config import DetectionFunctionSensor, NetworkConfig
from .schema import TrackState

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
            shifted = v - v.min()
            total = shifted.sum()
            if not total > 0:
                return None
            return normalize_likelihood(w @ v), float(shifted.max() / total)
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
        shifted = lik - lik.min()
        return lik, float(shifted.max() / shifted.sum()) if shifted.sum() > 0 else 0.0

    def of(self, readings: Sequence[Reading]) -> SensorLikelihoods:
        """The tick's readings as the grid filter's input (one row per informative reading)."""
        rows = [lq for lq in (self(r) for r in readings) if lq is not None]
        if not rows:
            return SensorLikelihoods(np.empty((0, self.grid.size)), np.empty(0), ())
        return SensorLikelihoods(
            np.array([lk for lk, _ in rows]), np.array([q for _, q in rows]), ("all",) * len(rows)
        )

    def fused(self, readings: Sequence[Reading], rule: str) -> Array | None:
        """The tick's readings fused without any temporal prior (``(nx, ny)``), or None."""
        lik = self.of(readings)
        if lik.values.shape[0] == 0:
            return None
        return fuse(lik.values, lik.quality, rule).reshape(self.grid.shape)  # type: ignore[arg-type]


class GridEngine:
    """The node's grid tracker: one :class:`GridTracker` step per tick (module docstring)."""

    def __init__(self, cfg: NetworkConfig, start: float) -> None:
        g = cfg.tracker.grid
        self.cfg = cfg
        self.grid = grid_of(cfg)
        self.cells = CellLikelihoods(cfg, self.grid)
        self.rate = cfg.fusion.rate_hz
        self.tracker = GridTracker(
            self.grid,
            g.fusion,
            motion=DirectionalMotion(g.delta),
            first_delta=2 * g.delta,
            max_step=g.max_speed / self.rate,
        )
        self.tracker.initialize(self._prior())
        self.time = float(start)
        self.resets = 0

    def _prior(self) -> Array:
        """The configured Gaussian prior on the position, evaluated on the cells."""
        m = np.asarray(self.cfg.tracker.prior_mean[:2], float)
        sd = np.maximum(np.asarray(self.cfg.tracker.prior_std[:2], float), self.grid.cell)
        u = (self.grid.centres - m) / sd
        p = np.exp(-0.5 * np.sum(u * u, axis=1))
        return p if p.sum() > 0 else self.grid.uniform()

    def step(self, tick: int, t: float, readings: Sequence[Reading]) -> TrackState:
        mean, cov = self.tracker.step(self.cells.of(readings))
        del self.tracker.estimates[:-2], self.tracker.covariances[:-2]  # all it uses: memory flat
        if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(cov))):  # never publish NaN
            self.resets += 1
            self.tracker.initialize(self._prior())
            mean, cov = self.grid.mean_cov(self.tracker.prob)  # type: ignore[arg-type]
        self.time = t
        return TrackState(
            track=1,
            tick=tick,
            time=t,
            state=mean.tolist(),
            covariance=cov.tolist(),
            position=mean.tolist(),
            position_covariance=cov.tolist(),
            sensors=sorted({r.sensor for r in readings}),
            readings=len(readings),
        )

    def step_all(self, tick: int, t: float, readings: Sequence[Reading]) -> list[TrackState]:
        return [self.step(tick, t, readings)]
