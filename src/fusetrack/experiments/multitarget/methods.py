"""The five trackers compared on one run's bearings (estimation part of the experiment).

* ``GNN``, ``JPDA`` -- :class:`~fusetrack.tracking.MultiTargetTracker` (Kalman filter, nearly
  constant velocity) on the triangulated candidates, one position sensor per pair of arrays
  (a target gives at most one point per pair), each point with its own covariance
  (:func:`.triangulation.triangulation_cov`);
* ``MCMCDA`` -- online MCMCDA (:class:`~fusetrack.association.MCMCDA`, as ``kushwaha2010-mcmcda``
  runs it) on the same candidates, pooled per scan;
* ``grid+JPDA`` -- the fused likelihood of the bearings on Kushwaha's grid, its peaks
  (:mod:`.grid_peaks`) as position measurements of the JPDA tracker;
* ``direct`` -- the JPDA tracker fed the bearings themselves (extended Kalman filter, one
  :class:`~fusetrack.sensors.Bearing` per array); candidates only *start* tracks (the
  tracker's ``birth_only_sensors``), they never update one.

Clutter densities: each pair's (or the grid's) mean number of points per scan over the run,
divided by the field's area -- every point counted as clutter, an upper bound the tracker
could estimate itself; bearings: ``clutter / 2 pi`` per radian.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ...association import (
    MCMCDA,
    GlobalNearestNeighbour,
    JointProbabilisticDataAssociation,
    MCMCDAConfig,
)
from ...core import Gaussian, Measurement, Track
from ...filters import ExtendedKalmanFilter, KalmanFilter
from ...motion import ConstantVelocity
from ...sensors import Bearing, PositionFix
from ...tracking import (
    AnyOf,
    ExistenceDeleter,
    InverseMeasurementPrior,
    MissedCountDeleter,
    MofNInitiator,
    MultiTargetTracker,
)
from .grid_peaks import peak_measurements
from .scenario import Scene, Truth
from .triangulation import Candidate, as_measurements, pair_id

METHODS = ("GNN", "JPDA", "MCMCDA", "grid+JPDA", "direct")
Q_ACCEL = 0.5  # white-noise acceleration PSD of the trackers' CV model (m^2/s^3)
VELOCITY_STD = 3.0  # prior std of a new track's velocity (m/s)
EXISTENCE_FLOOR = 0.1  # a confirmed track whose existence probability falls below ends


def _pair_ids(scene: Scene) -> list[str]:
    ids = [sid for sid, _, _ in scene.arrays]
    return [pair_id(a, b) for k, a in enumerate(ids) for b in ids[k + 1 :]]


def _position_sensors(ids: Sequence[str]) -> dict[str, PositionFix]:
    return {sid: PositionFix(sid, cov=np.eye(2)) for sid in ids}


def _tracker(
    filt: Any,
    sensors: Mapping[str, Any],
    births: Mapping[str, PositionFix],
    associator: Any,
    p_detect: Mapping[str, float],
    clutter: Mapping[str, float],
    birth_only: Sequence[str] = (),
) -> MultiTargetTracker:
    """The tracker every method but MCMCDA uses: 3-of-4 confirmation, 4 misses in a row end;
    the sensors ``birth_only`` only start tracks."""
    unobserved = Gaussian(np.zeros(4), np.diag([0.0, 0.0, VELOCITY_STD**2, VELOCITY_STD**2]))
    prior = InverseMeasurementPrior(births, unobserved)
    return MultiTargetTracker(
        filt,
        sensors,
        associator,
        MofNInitiator(3, 4, prior),
        AnyOf(MissedCountDeleter(4), ExistenceDeleter(EXISTENCE_FLOOR)),
        p_detect,
        clutter,
        birth_only_sensors=birth_only,
    )


def _density(scene: Scene, counts: Sequence[int]) -> float:
    """Mean points per scan over the field's area, floored (no points: still > 0)."""
    return max(float(np.mean(counts)) if len(counts) else 0.0, 0.05) / scene.area


def candidate_trackers(
    scene: Scene, truth: Truth, candidates: list[list[Candidate]], rng: np.random.Generator
) -> dict[str, list[Track]]:
    """GNN and JPDA on the triangulated candidates (module docstring)."""
    ids = _pair_ids(scene)
    sensors = _position_sensors(ids)
    kf = KalmanFilter(ConstantVelocity(ndim=2, q=Q_ACCEL), list(sensors.values()))
    clutter = {
        sid: _density(scene, [sum(pair_id(*c.pair) == sid for c in cs) for cs in candidates])
        for sid in ids
    }
    p_d = dict.fromkeys(ids, scene.p_detect**2)
    zs = [m for t, cs in zip(truth.times, candidates) for m in as_measurements(float(t), cs)]
    out = {}
    for name, assoc in (
        ("GNN", GlobalNearestNeighbour()),
        ("JPDA", JointProbabilisticDataAssociation()),
    ):
        tracker = _tracker(kf, sensors, sensors, assoc, p_d, clutter)
        out[name] = tracker.run(zs, rng, times=truth.times)
    return out


def mcmcda_tracks(
    scene: Scene,
    truth: Truth,
    candidates: list[list[Candidate]],
    n_mc: int,
    n_targets: int,
    rng: np.random.Generator,
) -> list[Track]:
    """Online MCMCDA on the pooled candidates of every scan (as ``kushwaha2010-mcmcda``), each
    candidate with its own triangulation covariance (gate, track score, new-track prior)."""
    obs = [np.array([c.point for c in cs]).reshape(-1, 2) for cs in candidates]
    covs = [np.array([c.cov for c in cs]).reshape(-1, 2, 2) for cs in candidates]
    n_pairs = len(_pair_ids(scene))
    stds = [np.sqrt(np.trace(c.cov) / 2) for cs in candidates for c in cs]
    config = MCMCDAConfig(
        dt=scene.dt,
        max_speed=5.0,
        n_mc=n_mc,
        p_detect=min(1.0 - (1.0 - scene.p_detect**2) ** n_pairs, 0.99),
        birth_rate=n_targets / len(obs),
        false_alarm_rate=max(float(np.mean([len(o) for o in obs])) - n_targets, 0.1),
        area=scene.area,
        accel_std=1.0,
        obs_std=float(np.median(stds)) if stds else 1.0,
        init_speed_std=VELOCITY_STD,
    )
    tracker = MCMCDA(config)
    state = tracker.initial_state()
    for y, cov in zip(obs, covs):
        state = tracker.step(state, y, rng, cov)
    out = []
    for ident, (steps, pos) in tracker.tracks(tracker.finish(state)).items():
        ok = steps < truth.times.size
        out.append(Track(truth.times[steps[ok]], pos[ok], label=f"track {ident}", id=ident))
    return out


def grid_tracks(
    scene: Scene, truth: Truth, scans: list[dict[str, Any]], rng: np.random.Generator
) -> list[Track]:
    """The JPDA tracker on the peaks of the fused grid likelihood of every scan."""
    zs = [peak_measurements(scene, float(t), scan) for t, scan in zip(truth.times, scans)]
    sensors = _position_sensors(["grid"])
    kf = KalmanFilter(ConstantVelocity(ndim=2, q=Q_ACCEL), list(sensors.values()))
    clutter = {"grid": _density(scene, [len(z) for z in zs])}
    p_d = {"grid": scene.p_detect ** len(scene.arrays)}
    tracker = _tracker(kf, sensors, sensors, JointProbabilisticDataAssociation(), p_d, clutter)
    return tracker.run([m for z in zs for m in z], rng, times=truth.times)


def direct_tracks(
    scene: Scene,
    truth: Truth,
    scans: list[dict[str, Any]],
    candidates: list[list[Candidate]],
    rng: np.random.Generator,
) -> list[Track]:
    """JPDA on the bearings themselves (EKF); the candidates only start tracks."""
    bearings = {sid: Bearing(sid, position=[x, y], sigma=scene.sigma) for sid, x, y in scene.arrays}
    births = _position_sensors(_pair_ids(scene))
    ekf = ExtendedKalmanFilter(
        ConstantVelocity(ndim=2, q=Q_ACCEL), [*bearings.values(), *births.values()]
    )
    sensors: dict[str, Any] = {**bearings, **births}
    p_d = dict.fromkeys(bearings, scene.p_detect)
    clutter = dict.fromkeys(bearings, max(scene.clutter, 0.05) / (2 * np.pi))
    zs: list[Measurement] = []
    for t, scan, cs in zip(truth.times, scans, candidates):
        zs += [Measurement(float(t), sid, [z]) for sid in bearings for z in scan[sid]]
        zs += as_measurements(float(t), cs)
    assoc = JointProbabilisticDataAssociation()
    tracker = _tracker(ekf, sensors, births, assoc, p_d, clutter, birth_only=list(births))
    return tracker.run(zs, rng, times=truth.times)
