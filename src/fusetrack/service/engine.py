"""The tracker inside the node: one fusetrack filter stepped tick by tick.

Each tick ``k`` gets the readings the :class:`~.alignment.Aligner` assigned to it. The engine
does exactly what :func:`fusetrack.filters.run_filter` does with ``times=`` the tick times and
``t0=`` the start: readings at the same time (within 1e-9 s) are one update, the filter predicts
between distinct times and to the tick, and the estimate at the tick is published. So a stretch
of live operation and the offline run over the same readings give the same track (the end-to-end
test checks this), and the durable log can be replayed exactly (:mod:`.log`).

With ``alignment="closest"`` each reading is fused as if taken at the tick time.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np

from ..core.measurement import Measurement, group_by_time
from ..filters import ExtendedKalmanFilter, UnscentedKalmanFilter
from ..filters.particle import BootstrapFilter
from .alignment import Reading
from .config import NetworkConfig
from .schema import TrackState

_TIME_TOLERANCE = 1e-9


def build_filter(cfg: NetworkConfig) -> Any:
    """The configured filter over the configured sensors."""
    motion, sensors = cfg.tracker.motion.build(), cfg.sensor_models()
    kind, joint = cfg.tracker.filter, cfg.tracker.update == "joint"
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


class FusionEngine:
    """Holds the belief; :meth:`step` advances it to the next tick."""

    def __init__(self, cfg: NetworkConfig, start: float) -> None:
        self.cfg = cfg
        self.filter = build_filter(cfg)
        self.rng = np.random.default_rng(cfg.tracker.seed)
        self.belief = self._initial()
        self.time = float(start)
        self.resets = 0
        self.position_index = list(self.filter.motion.position_index)

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

    def _step(self, tick: int, t: float, readings: Sequence[Reading]) -> TrackState:
        at = t if self.cfg.fusion.alignment == "closest" else None
        for when, group in group_by_time(as_measurements(readings, at), _TIME_TOLERANCE):
            self._predict_to(when)
            self.belief = self.filter.update(self.belief, group, self.rng)
        self._predict_to(t)
        estimate = getattr(self.filter, "estimate", None)
        summary = estimate(self.belief) if estimate is not None else self.belief
        mean, cov = np.asarray(summary.mean), np.asarray(summary.cov)
        if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(cov))):
            # never publish NaN: restart from the prior at this time, and count it
            self.resets += 1
            self.belief = self._initial()
            summary = estimate(self.belief) if estimate is not None else self.belief
            mean, cov = np.asarray(summary.mean), np.asarray(summary.cov)
        p = self.position_index
        return TrackState(
            track=1,
            tick=tick,
            time=t,
            state=mean.tolist(),
            covariance=cov.tolist(),
            position=mean[p].tolist(),
            position_covariance=cov[np.ix_(p, p)].tolist(),
            sensors=sorted({r.sensor for r in readings}),
            readings=len(readings),
        )

    def step_all(self, tick: int, t: float, readings: Sequence[Reading]) -> list[TrackState]:
        """:meth:`step` as the list every engine returns (one track here)."""
        return [self.step(tick, t, readings)]

    def _initial(self) -> Any:
        prior = self.cfg.tracker.prior()
        init = getattr(self.filter, "initialize", None)
        return init(prior, self.rng) if callable(init) else prior

    def _predict_to(self, t: float) -> None:
        dt = t - self.time
        if dt > _TIME_TOLERANCE:
            self.belief = self.filter.predict(self.belief, dt, self.rng)
            self.time = t


class Engine(Protocol):
    """What the node needs of a tracker: one call per tick, the tracks it publishes."""

    resets: int

    def step_all(self, tick: int, t: float, readings: Sequence[Reading]) -> list[TrackState]: ...


def build_engine(cfg: NetworkConfig, start: float) -> Engine:
    """The configured tracker: several targets through the association layer
    (:mod:`.multi_engine`), the grid tracker (:mod:`.grid_engine`) or one filter (this module)."""
    if cfg.tracker.association.method == "mcmcda":
        from .multi_engine import MultiTargetEngine

        return MultiTargetEngine(cfg, start)
    if cfg.tracker.filter == "grid":
        from .grid_engine import GridEngine

        return GridEngine(cfg, start)
    return FusionEngine(cfg, start)
