"""The tracker inside the node: one engine that steps any fusetrack filter tick by tick.

Each tick ``k`` gets the readings the :class:`~.alignment.Aligner` assigned to it. The engine
turns them into measurements and runs the configured :class:`~fusetrack.core.Filter` (EKF, UKF,
bootstrap particle filter or the grid filter, ``tracker.filter``) through
:func:`~fusetrack.core.filter_step`, exactly as :func:`fusetrack.filters.run_filter` does with
``times=`` the tick times and ``t0=`` the start: readings at the same time (within 1e-9 s) are
one update, the filter predicts between distinct times and to the tick, and the estimate at the
tick is published. So a stretch of live operation and the offline run over the same readings
give the same track (the end-to-end test checks this), and the durable log can be replayed
exactly (:mod:`.log`).

With ``alignment="closest"`` each reading is fused as if taken at the tick time. The grid filter
always fuses a tick's readings at the tick time, as per-cell likelihood maps
(:mod:`.grid_cells`). Several targets (``tracker.association``) run behind the same
:class:`Engine` interface (:mod:`.multi_engine`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np

from ..core import Filter, Measurement, filter_step, group_by_time
from ..filters import ExtendedKalmanFilter, UnscentedKalmanFilter
from ..filters.grid import GridFilter
from ..filters.particle import BootstrapFilter
from .alignment import Reading
from .config import NetworkConfig
from .grid_cells import CellLikelihoods, grid_filter, grid_of, grid_prior
from .schema import TrackState

_TIME_TOLERANCE = 1e-9


def build_filter(cfg: NetworkConfig) -> Filter[Any]:
    """The configured filter over the configured sensors."""
    kind, joint = cfg.tracker.filter, cfg.tracker.update == "joint"
    if kind == "grid":
        return grid_filter(cfg, grid_of(cfg))
    motion, sensors = cfg.tracker.motion.build(), cfg.sensor_models()
    if kind == "ukf":
        return UnscentedKalmanFilter(motion, sensors, joint=joint)
    if kind == "pf":
        return BootstrapFilter(
            motion, sensors, n_particles=cfg.tracker.particles, ess_threshold=0.5
        )
    return ExtendedKalmanFilter(motion, sensors, joint=joint)


def as_measurements(readings: Sequence[Reading], at: float | None = None) -> list[Measurement]:
    """Readings as filter measurements (``at``: stamp them all with this time instead)."""
    return [
        Measurement(r.time if at is None else at, r.sensor, r.value, r.covariance) for r in readings
    ]


def track_state(
    track: int,
    tick: int,
    t: float,
    mean: np.ndarray,
    cov: np.ndarray,
    position_index: Sequence[int],
    readings: Sequence[Reading],
) -> TrackState:
    """What an engine publishes for one track at one tick."""
    p = list(position_index)
    return TrackState(
        track=track,
        tick=tick,
        time=t,
        state=mean.tolist(),
        covariance=cov.tolist(),
        position=mean[p].tolist(),
        position_covariance=cov[np.ix_(p, p)].tolist(),
        sensors=sorted({r.sensor for r in readings}),
        readings=len(readings),
    )


class Engine(Protocol):
    """What the node needs of a tracker: one call per tick, the tracks it publishes."""

    resets: int

    def step_all(self, tick: int, t: float, readings: Sequence[Reading]) -> list[TrackState]: ...


class FusionEngine:
    """One target, any filter: holds the belief; :meth:`step` advances it to the next tick."""

    def __init__(self, cfg: NetworkConfig, start: float) -> None:
        self.cfg = cfg
        self.filter = build_filter(cfg)
        grid = cfg.tracker.filter == "grid"
        self.cells = CellLikelihoods(cfg, grid_of(cfg)) if grid else None
        self.position_index = [0, 1] if grid else list(cfg.tracker.motion.build().position_index)
        self.rng = np.random.default_rng(cfg.tracker.seed)
        self.belief = self._initial()
        self.time = float(start)
        self.resets = 0

    def step(self, tick: int, t: float, readings: Sequence[Reading]) -> TrackState:
        """Fuse ``readings`` (already in fusion order) and predict to the tick time ``t``.

        All or nothing: if anything raises, the belief, time and random state are as before.
        """
        saved = (self.belief, self.time, self.rng.bit_generator.state, self.resets)
        try:
            return self._step(tick, t, readings)
        except Exception:
            self.belief, self.time, self.rng.bit_generator.state, self.resets = saved
            raise

    def step_all(self, tick: int, t: float, readings: Sequence[Reading]) -> list[TrackState]:
        """:meth:`step` as the list every engine returns (one track here)."""
        return [self.step(tick, t, readings)]

    def measurements(self, readings: Sequence[Reading], t: float) -> list[Measurement]:
        """The tick's readings as the filter's measurements (module docstring)."""
        if self.cells is not None:
            return self.cells.of(readings).measurements(t)
        return as_measurements(readings, t if self.cfg.fusion.alignment == "closest" else None)

    def _step(self, tick: int, t: float, readings: Sequence[Reading]) -> TrackState:
        for when, group in group_by_time(self.measurements(readings, t), _TIME_TOLERANCE):
            self._advance(when, group)
        self._advance(t, [])
        mean, cov = self._summary()
        if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(cov))):
            # never publish NaN: restart from the prior at this time, and count it
            self.resets += 1
            self.belief = self._initial()
            mean, cov = self._summary()
        return track_state(1, tick, t, mean, cov, self.position_index, readings)

    def _advance(self, when: float, measurements: Sequence[Measurement]) -> None:
        """One :func:`filter_step` to ``when`` (a predict only when it is later than now)."""
        dt = when - self.time
        if dt > _TIME_TOLERANCE:
            self.belief = filter_step(self.filter, self.belief, dt, measurements, self.rng)
            self.time = when
        elif measurements:
            self.belief = filter_step(self.filter, self.belief, 0.0, measurements, self.rng)

    def _summary(self) -> tuple[np.ndarray, np.ndarray]:
        estimate = getattr(self.filter, "estimate", None)
        summary = estimate(self.belief) if estimate is not None else self.belief
        return np.asarray(summary.mean), np.asarray(summary.cov)

    def _initial(self) -> Any:
        if isinstance(self.filter, GridFilter) and self.cells is not None:
            return self.filter.initial(grid_prior(self.cfg, self.cells.grid))
        prior = self.cfg.tracker.prior()
        init = getattr(self.filter, "initialize", None)
        return init(prior, self.rng) if callable(init) else prior


def build_engine(cfg: NetworkConfig, start: float) -> Engine:
    """The configured tracker: several targets through the association layer
    (:mod:`.multi_engine`) or one target through any filter (:class:`FusionEngine`)."""
    if cfg.tracker.association.method == "mcmcda":
        from .multi_engine import MultiTargetEngine

        return MultiTargetEngine(cfg, start)
    return FusionEngine(cfg, start)
