"""The tracker inside the node: one engine that steps the configured tracker tick by tick.

The engine holds a tracker (:mod:`.trackers`: ``initial_state()``, ``step(state, time,
measurements, rng)``), its state and its random numbers (``tracker.seed``). Each tick ``k``
gets the readings the :class:`~.alignment.Aligner` assigned to it; the engine turns them into
measurements, steps the tracker once per distinct measurement time (within 1e-9 s) and, when
no measurement fell at the tick time, once more to the tick with none; then it publishes every
confirmed track as a :class:`~.schema.TrackState` with its id (from 1).

* One target (``tracker.association.method: none``): the configured
  :class:`~fusetrack.core.Filter` (EKF, UKF, bootstrap particle filter or the grid filter,
  ``tracker.filter``) as a one-track tracker, so each step is one
  :func:`~fusetrack.core.filter_step` exactly as :func:`fusetrack.filters.run_filter` does with
  ``times=`` the tick times and ``t0=`` the start: a stretch of live operation and the offline
  run over the same readings give the same track (the end-to-end test checks this). With
  ``alignment="closest"`` each reading is fused as if taken at the tick time; the grid filter
  always fuses a tick's readings at the tick time, as per-cell likelihood maps
  (:mod:`.grid_cells`).
* Several targets (``gnn``, ``jpda``, ``mht``: :class:`~fusetrack.tracking.MultiTargetTracker`
  on the configured filter and sensors; ``phd``: the GM-PHD filter; ``mcmcda``: online MCMCDA
  on position detections, :mod:`.detections`): a tick is one scan, all its readings at the tick
  time, in which every sensor looked (so M-of-N confirmation and missed-count deletion count
  ticks). A tick may publish no track or several.

Everything random comes from the engine's generator, so the durable log replays exactly
(:mod:`.log`): the same readings through a fresh engine give the same tracks.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..association import (
    MCMCDA,
    GlobalNearestNeighbour,
    JointProbabilisticDataAssociation,
    MCMCDAConfig,
    TrackOrientedMHT,
)
from ..core import Filter, Measurement, group_by_time
from ..filters import (
    BootstrapFilter,
    ExtendedKalmanFilter,
    GMPHDFilter,
    GridFilter,
    KalmanFilter,
    PhdIntensity,
    UnscentedKalmanFilter,
    compile_bearing_steps,
    ekf_bearing_steps,
)
from ..tracking import (
    MissedCountDeleter,
    MofNInitiator,
    MultiTargetTracker,
    PHDTracker,
    SingleTargetState,
    SingleTargetTracker,
    Tracker,
    belief_summary,
)
from .alignment import Reading
from .config import (
    JPDAAssociation,
    MCMCDAAssociation,
    MHTAssociation,
    NetworkConfig,
    PHDAssociation,
    ScanTrackerAssociation,
)
from .detections import ReadingBirth, position_detections
from .grid_cells import CellLikelihoods, grid_filter, grid_of, grid_prior
from .schema import TrackState
from .trackers import MCMCDAAdapter

TIME_TOLERANCE = 1e-9  # readings this close in time are one update

DETECTIONS = "detections"
"""The sensor id of MCMCDA's position detections (several sensors' readings, grid peaks)."""


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


def build_tracker(cfg: NetworkConfig, start: float, cells: CellLikelihoods | None) -> Tracker:
    """The configured tracker (module docstring); ``cells``: the grid's likelihood maps, with
    ``filter: grid``."""
    a = cfg.tracker.association
    if isinstance(a, ScanTrackerAssociation):
        return _scan_tracker(cfg, a)
    if isinstance(a, PHDAssociation):
        return _phd_tracker(cfg, a)
    if isinstance(a, MCMCDAAssociation):
        x0, x1, y0, y1 = cfg.area
        section = a.model_dump(exclude={"method"})  # the section's fields are MCMCDAConfig's
        config = MCMCDAConfig(dt=1.0 / cfg.fusion.rate_hz, area=(x1 - x0) * (y1 - y0), **section)
        return MCMCDAAdapter(MCMCDA(config))
    filt = build_filter(cfg)

    def prior(rng: np.random.Generator | None) -> Any:
        if isinstance(filt, GridFilter) and cells is not None:
            return filt.initial(grid_prior(cfg, cells.grid))
        init = getattr(filt, "initialize", None)
        return init(cfg.tracker.prior(), rng) if callable(init) else cfg.tracker.prior()

    return SingleTargetTracker(filt, prior, start)


def _scan_tracker(cfg: NetworkConfig, a: ScanTrackerAssociation) -> MultiTargetTracker:
    """GNN, JPDA or MHT in the multi-target tracker: M-of-N confirmation of tracks started by
    position readings (:class:`~.detections.ReadingBirth`), missed-count deletion."""
    associator: Any = GlobalNearestNeighbour()
    if isinstance(a, JPDAAssociation):
        associator = JointProbabilisticDataAssociation(
            max_exact_events=a.max_exact_events, unassociated_below=a.unassociated_below
        )
    elif isinstance(a, MHTAssociation):
        associator = TrackOrientedMHT(max_hypotheses=a.max_hypotheses)
    return MultiTargetTracker(
        build_filter(cfg),
        cfg.sensor_models(),
        associator,
        MofNInitiator(a.confirm_m, a.confirm_n, ReadingBirth(cfg)),
        MissedCountDeleter(a.delete_misses),
        a.p_detect,
        a.clutter_density,
        a.gate_probability,
        survival_probability=a.survival_probability,
    )


def _phd_tracker(cfg: NetworkConfig, a: PHDAssociation) -> PHDTracker:
    """The GM-PHD filter on the configured motion and sensors, births over the whole area."""
    phd = GMPHDFilter(
        cfg.tracker.motion.build(),
        cfg.sensor_models(),
        birth_intensity(cfg, a.birth_cells, a.birth_weight),
        survival_probability=a.survival_probability,
        detection_probability=a.p_detect,
        clutter_intensity=a.clutter_density,
        truncation_threshold=a.truncation_threshold,
        merge_threshold=a.merge_threshold,
        max_components=a.max_components,
    )
    return PHDTracker(phd, a.extract_threshold)


def birth_intensity(cfg: NetworkConfig, cells: int, weight: float) -> PhdIntensity:
    """``cells`` x ``cells`` Gaussians of total weight ``weight`` centred on a grid over
    ``area``, each with the cell's width as position standard deviation; the other state entries
    (velocities) from ``prior_mean``/``prior_std``."""
    x0, x1, y0, y1 = cfg.area
    wx, wy = (x1 - x0) / cells, (y1 - y0) / cells
    cx, cy = np.meshgrid(x0 + wx * (np.arange(cells) + 0.5), y0 + wy * (np.arange(cells) + 0.5))
    px, py = cfg.tracker.motion.build().position_index[:2]
    prior = cfg.tracker.prior()
    means = np.tile(prior.mean, (cells * cells, 1))
    means[:, px], means[:, py] = cx.ravel(), cy.ravel()
    cov = prior.cov.copy()
    cov[px, :], cov[py, :], cov[:, px], cov[:, py] = 0.0, 0.0, 0.0, 0.0
    cov[px, px], cov[py, py] = wx**2, wy**2
    n = cells * cells
    return PhdIntensity(np.full(n, weight / n), means, np.tile(cov, (n, 1, 1)))


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
    """What the engine publishes for one track at one tick."""
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


class FusionEngine:
    """The node's engine (module docstring): :meth:`step_all` advances the tracker to a tick."""

    def __init__(self, cfg: NetworkConfig, start: float) -> None:
        self.cfg = cfg
        self.method = cfg.tracker.association.method
        grid = cfg.tracker.filter == "grid"
        self.cells = CellLikelihoods(cfg, grid_of(cfg)) if grid else None
        self.tracker = build_tracker(cfg, start, self.cells)
        self.filter = self.tracker.filter
        positions = grid or self.method == "mcmcda"
        self.position_index = (
            [0, 1] if positions else list(cfg.tracker.motion.build().position_index)
        )
        self.rng = np.random.default_rng(cfg.tracker.seed)
        self.state = self.tracker.initial_state()
        self.time = float(start)
        self.resets = 0  # estimates that were not finite (never published)
        if type(self.filter) in (ExtendedKalmanFilter, KalmanFilter) and self.method == "none":
            if cfg.fusion.alignment == "all":  # the loop of _bearing_steps, compiled before use
                compile_bearing_steps()

    @property
    def belief(self) -> Any:
        """The single target's belief (``method: none``), or None."""
        return getattr(self.state, "belief", None)

    def step_all(self, tick: int, t: float, readings: Sequence[Reading]) -> list[TrackState]:
        """Fuse ``readings`` (already in fusion order), advance to the tick time ``t`` and
        publish every confirmed track.

        All or nothing: if anything raises, the state, time and random state are as before.
        """
        saved = (self.state, self.time, self.rng.bit_generator.state, self.resets)
        try:
            return self._step(tick, t, readings)
        except Exception:
            self.state, self.time, self.rng.bit_generator.state, self.resets = saved
            raise

    def step(self, tick: int, t: float, readings: Sequence[Reading]) -> TrackState:
        """:meth:`step_all` for one target: its one state."""
        (state,) = self.step_all(tick, t, readings)
        return state

    def measurements(self, readings: Sequence[Reading], t: float) -> list[Measurement]:
        """The tick's readings as the tracker's measurements (module docstring)."""
        if self.method == "none":
            if self.cells is not None:
                return self.cells.of(readings).measurements(t)
            return as_measurements(readings, t if self.cfg.fusion.alignment == "closest" else None)
        if self.method == "mcmcda":
            y = position_detections(self.cfg, readings, self.cells)
            return [Measurement(t, DETECTIONS, p) for p in y]
        return as_measurements(readings, t)

    def _step(self, tick: int, t: float, readings: Sequence[Reading]) -> list[TrackState]:
        measurements = self.measurements(readings, t)
        if not self._bearing_steps(measurements):
            for when, group in group_by_time(measurements, TIME_TOLERANCE):
                self._scan(when, group)
        if t - self.time > TIME_TOLERANCE:
            self._scan(t, [])
        out = []
        for track in self.state.confirmed:
            mean, cov = belief_summary(self.filter, track.belief)
            if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(cov))):
                self.resets += 1  # never publish NaN: one target restarts from the prior now
                if not isinstance(self.tracker, SingleTargetTracker):
                    continue
                self.state = self.tracker.restart(self.state, self.rng)
                mean, cov = belief_summary(self.filter, self.state.belief)
            out.append(track_state(track.id + 1, tick, t, mean, cov, self.position_index, readings))
        return out

    def _bearing_steps(self, measurements: Sequence[Measurement]) -> bool:
        """One target, readings each at its own time (``alignment: all``), an EKF and bearing
        sensors: the tick's steps in one loop (:func:`~fusetrack.filters.ekf_bearing_steps`, the
        same numbers to rounding as one :meth:`_scan` per reading); False when it does not
        apply (the scans then run)."""
        state = self.state
        if (
            len(measurements) < 2
            or not isinstance(self.tracker, SingleTargetTracker)
            or not isinstance(state, SingleTargetState)
            or state.belief is None
            or any(b.time - a.time <= TIME_TOLERANCE for a, b in itertools.pairwise(measurements))
        ):
            return False
        done = ekf_bearing_steps(
            self.filter, state.belief, state.time, measurements, TIME_TOLERANCE
        )
        if done is None:
            return False
        self.state = SingleTargetState(*done)
        self.time = max(self.time, done[1])
        return True

    def _scan(self, when: float, measurements: Sequence[Measurement]) -> None:
        self.state = self.tracker.step(self.state, when, measurements, self.rng)
        self.time = max(self.time, when)


Engine = FusionEngine
"""The node's one engine (the name :mod:`.log` and the node use)."""


def build_engine(cfg: NetworkConfig, start: float) -> FusionEngine:
    """The engine of the configured tracker."""
    return FusionEngine(cfg, start)
