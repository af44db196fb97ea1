"""Every multi-target tracker of the library on one run of ``multitarget-benchmark``, built from
its public API with the scenario's own models (:mod:`.benchmark_scenario`).

* ``GNN``, ``JPDA``, ``MHT`` -- :class:`~fusetrack.tracking.MultiTargetTracker` with
  :class:`~fusetrack.association.GlobalNearestNeighbour`,
  :class:`~fusetrack.association.JointProbabilisticDataAssociation` or
  :class:`~fusetrack.association.TrackOrientedMHT` (an :class:`~fusetrack.tracking.MHTTracker`);
  an extended Kalman filter per track (exact for the position sensor, linearised for the
  radar); tracks start from position reports only (:class:`InverseMeasurementPrior`), are
  confirmed at 4 hits in their first 5 scans, end after :data:`MAX_MISSES` missed scans in a
  row or when their existence probability falls below :data:`EXISTENCE_FLOOR`. Only the scans at
  which a track is confirmed are reported (the online output).
* ``MCMCDA`` -- :class:`~fusetrack.tracking.MCMCDATracker` (Oh, Russell & Sastry 2009) on the
  position reports (it takes position-like sensors only: the radar's reports are skipped); its
  tracks are the committed ones, a fixed-lag decision of ``window`` scans.
* ``GM-PHD`` -- :class:`~fusetrack.tracking.PHDTracker` over
  :class:`~fusetrack.filters.GMPHDFilter` (the extended-Kalman PHD for the radar), the true birth
  intensity and the true initial intensity (:func:`phd_prior`), both sensors (iterated
  corrector); its tracks are the labelled components above
  0.5; the intensity's mass is its estimate of the number of targets.
* ``PMB`` -- :class:`~fusetrack.tracking.PMBTracker` over the track-oriented Poisson
  multi-Bernoulli filter (:class:`~fusetrack.tracking.PMBFilter`, Williams 2015; marginal
  associations by loopy belief propagation) with the PHD's models, birth intensity and initial
  intensity (as its undetected-target Poisson part); its tracks are the Bernoullis with
  existence above 0.5, each keeping the identity of the report that created it.

Every tracker knows the true ``P_D``, ``P_S``, clutter density and (PHD, MCMCDA) birth rate.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...association import (
    GlobalNearestNeighbour,
    JointProbabilisticDataAssociation,
    MCMCDAConfig,
    TrackOrientedMHT,
)
from ...core import Gaussian, Measurement, Track
from ...filters import ExtendedKalmanFilter, GMPHDFilter, PhdIntensity
from ...tracking import (
    AnyOf,
    ExistenceDeleter,
    InverseMeasurementPrior,
    MCMCDATracker,
    MissedCountDeleter,
    MofNInitiator,
    MultiTargetTracker,
    PHDTracker,
    PHDTrackerState,
    PMBDensity,
    PMBFilter,
    PMBTracker,
    PMBTrackerState,
    run_tracker,
)
from .benchmark_scenario import (
    AREA,
    DT,
    POS_SIGMA,
    Q_ACCEL,
    SPEED,
    Setting,
    birth_intensity,
    clutter_volume,
    motion,
    sensors,
)

TRACKERS = ("GNN", "JPDA", "MHT", "MCMCDA", "GM-PHD", "PMB")
VELOCITY_STD = SPEED  # prior std of a new track's velocity per axis (m/s)
MAX_MISSES = 3
CONFIRM_M, CONFIRM_N = 4, 5  # confirmed at 4 hits in the first 5 scans
EXISTENCE_FLOOR = 0.3
EXTRACT = 0.5  # PHD components above this weight are tracks (Vo & Ma 2006, Table III)


@dataclass(frozen=True)
class TrackerParams:
    """The settings a user may change: MHT depth and breadth, MCMCDA chain and window."""

    mht_n_scan: int = 3
    mht_max_hypotheses: int = 10
    mcmcda_n_mc: int = 200
    mcmcda_window: int = 6


def _clutter_density(setting: Setting) -> dict[str, float]:
    """False reports per scan per unit volume, per sensor (floored: the trackers need > 0)."""
    ids = ("pos", "radar")
    return {sid: max(setting.clutter, 0.05) / clutter_volume(sid) for sid in ids}


def _mtt(setting: Setting, associator: Any) -> MultiTargetTracker:
    models = sensors(setting.p_detect)
    unobserved = Gaussian(np.zeros(4), np.diag([0.0, 0.0, VELOCITY_STD**2, VELOCITY_STD**2]))
    return MultiTargetTracker(
        ExtendedKalmanFilter(motion(), list(models.values())),
        models,
        associator,
        MofNInitiator(CONFIRM_M, CONFIRM_N, InverseMeasurementPrior([models["pos"]], unobserved)),
        AnyOf(MissedCountDeleter(MAX_MISSES), ExistenceDeleter(EXISTENCE_FLOOR)),
        setting.p_detect,
        _clutter_density(setting),
        survival_probability=setting.p_survive,
    )


def _confirmed_part(track: Track) -> Track | None:
    """The scans at which a tracker's track was confirmed (``info["confirmed"]``)."""
    on = np.asarray(track.info.get("confirmed", np.ones(len(track), bool)), bool)
    if not on.any():
        return None
    covs = None if track.covariances is None else track.covariances[on]
    return Track(track.times[on], track.means[on], covs, track.label, {}, track.id)


def mtt_tracks(
    name: str, setting: Setting, params: TrackerParams, zs: list[Measurement], times: Any, rng: Any
) -> list[Track]:
    """GNN, JPDA or MHT over the run (module docstring)."""
    associator: Any = {
        "GNN": GlobalNearestNeighbour(),
        "JPDA": JointProbabilisticDataAssociation(),
        "MHT": TrackOrientedMHT(params.mht_n_scan, params.mht_max_hypotheses),
    }[name]
    tracks = _mtt(setting, associator).run(zs, rng, times=times)
    return [c for c in map(_confirmed_part, tracks) if c is not None]


def mcmcda_tracks(
    setting: Setting, params: TrackerParams, zs: list[Measurement], rng: Any
) -> list[Track]:
    """Online MCMCDA on the position reports (module docstring)."""
    config = MCMCDAConfig(
        dt=DT,
        max_speed=3 * SPEED,
        window=params.mcmcda_window,
        n_mc=params.mcmcda_n_mc,
        p_detect=setting.p_detect,
        p_terminate=1.0 - setting.p_survive,
        birth_rate=setting.birth_rate,
        false_alarm_rate=max(setting.clutter, 0.05),
        area=AREA,
        accel_std=float(np.sqrt(Q_ACCEL)),
        obs_std=POS_SIGMA,
        init_speed_std=VELOCITY_STD,
    )
    pos = sensors(setting.p_detect)["pos"]
    return MCMCDATracker([pos], config, unknown_sensors="skip").run(zs, rng)


def phd_tracker(setting: Setting) -> PHDTracker:
    """The GM-PHD tracker of the module docstring."""
    phd = GMPHDFilter(
        motion(),
        sensors(setting.p_detect),
        birth_intensity(setting.birth_rate),
        survival_probability=setting.p_survive,
        detection_probability=setting.p_detect,
        clutter_intensity=_clutter_density(setting),
    )
    return PHDTracker(phd, EXTRACT)


def pmb_tracker(setting: Setting) -> PMBTracker:
    """The PMB tracker of the module docstring (the PHD's models)."""
    pmb = PMBFilter(
        motion(),
        sensors(setting.p_detect),
        birth_intensity(setting.birth_rate),
        survival_probability=setting.p_survive,
        detection_probability=setting.p_detect,
        clutter_intensity=_clutter_density(setting),
    )
    return PMBTracker(pmb, EXTRACT)


def phd_prior(setting: Setting) -> PhdIntensity:
    """The PHD's intensity before the first scan: the first scan's targets are Poisson with
    the steady-state mean ``birth_rate / (1 - P_S)`` from the birth regions
    (:mod:`.benchmark_scenario`), and the first prediction (``dt = 0``: survival, then the
    births) maps this prior to exactly that intensity."""
    return birth_intensity(setting.birth_rate / (1.0 - setting.p_survive))


def run_trackers(
    setting: Setting, params: TrackerParams, zs: list[Measurement], times: Any, seed: int
) -> tuple[dict[str, list[Track]], list[float]]:
    """Every tracker of :data:`TRACKERS` on the same reports (each its own generator from
    ``seed``); also the PHD's expected number of targets at each scan."""
    out = {
        name: mtt_tracks(name, setting, params, zs, times, np.random.default_rng(seed + k))
        for k, name in enumerate(("GNN", "JPDA", "MHT"))
    }
    out["MCMCDA"] = mcmcda_tracks(setting, params, zs, np.random.default_rng(seed + 3))
    count: list[float] = []
    out["GM-PHD"] = run_tracker(
        phd_tracker(setting),
        zs,
        np.random.default_rng(seed + 4),
        times=times,
        order="reorder",
        state=PHDTrackerState(phd_prior(setting)),
        observe=lambda _, s: count.append(float(s.intensity.expected_count)),
    )
    prior = PMBDensity(phd_prior(setting), PhdIntensity.empty(4))
    out["PMB"] = run_tracker(
        pmb_tracker(setting),
        zs,
        np.random.default_rng(seed + 5),
        times=times,
        order="reorder",
        state=PMBTrackerState(prior),
    )
    return out, count
