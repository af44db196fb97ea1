"""Multi-target tracking speed: fusetrack against Stone Soup, GNN, JPDA and GM-PHD (issue 17).

The same simulated scenario, the same models, gates, clutter density and (as close as the two
libraries allow) the same initiation and deletion rules on both sides; time per scan beside the
GOSPA, so a speed-up is never bought with a worse tracker.

    python benchmarks/multitarget.py [--trackers gnn jpda phd] [--targets 10 50]
        [--clutter 10] [--scans 100] [--seeds 10] [--budget SECONDS] [--threads T] [--json]
        [--save | --out PATH]

**Scenario** (:class:`Scenario`, plain NumPy, one per seed, shared by both libraries): state
``[x, vx, y, vy]`` (Stone Soup's order, used on both sides), ``dt = 1`` s, constant velocity
with continuous white-noise acceleration (PSD ``q = 1 m^2/s^3`` per axis); ``--targets`` targets
alive from the first scan to the last, starting uniformly in ``[-900, 900]^2`` m with velocities
``N(0, 3^2)`` m/s per axis; each is detected with ``P_D = 0.9`` per scan, position measured with
``sigma = 5`` m; ``--clutter`` false alarms per scan (Poisson mean) uniform over the surveillance
square ``[-1000, 1000]^2`` m, so the clutter density is ``clutter / 4e6`` per m^2. Measurements
of a scan are shuffled.

**Trackers** (both sides: the Kalman predictor/updater of these models; ``P_G = 0.99``;
association scores ``log P_D N(z; Hx, S) - log kappa`` against ``log(1 - P_D P_G)`` for a miss):

* ``gnn`` -- optimal 2-D assignment. fusetrack: ``MultiTargetTracker`` with
  ``GlobalNearestNeighbour``. Stone Soup: ``MultiTargetTracker`` with ``GNNWith2DAssignment``
  over a ``PDAHypothesiser`` (the same likelihood-ratio scores; its per-track normalisation
  does not change a 2-D assignment, where every track row is used once).
* ``jpda`` -- fusetrack: ``MultiTargetTracker`` with ``JointProbabilisticDataAssociation``
  (exact marginals per gated cluster). Stone Soup: ``MultiTargetMixtureTracker`` with
  ``JPDAwithEHM`` (exact marginals by Efficient Hypothesis Management) over the same
  ``PDAHypothesiser``.
* initiation, both trackers: a measurement no confirmed track took starts a tentative track
  (position from the measurement with covariance ``R``, velocity ``0`` with ``sigma = 5`` m/s:
  fusetrack ``InverseMeasurementPrior``, Stone Soup ``SimpleMeasurementInitiator``, the same
  numbers), confirmed after 3 detections in its first 3 scans, dropped at its first miss
  (fusetrack ``MofNInitiator(3, 3)``; Stone Soup ``MultiMeasurementInitiator(min_points=3)``
  with an ``UpdateTimeStepsDeleter(1)`` on its tentative tracks). Stone Soup's initiator
  associates its tentative tracks by GNN also in the JPDA tracker (it cannot take JPDA's
  mixtures); fusetrack uses the tracker's associator for them.
* deletion: a confirmed track ends at its 3rd missed scan in a row (fusetrack
  ``MissedCountDeleter(3)``; Stone Soup ``UpdateTimeStepsDeleter(3)``). What counts as a miss
  in JPDA: fusetrack -- the track's measurement probabilities sum to less than 1/2; Stone Soup
  -- no measurement is more probable than the miss.
* ``phd`` -- the GM-PHD filter (Vo & Ma 2006): ``p_S = 0.99``, ``P_D = 0.9``, the clutter
  intensity above, one birth component per scan (weight 0.1, mean 0, standard deviations
  1000 m in position and 5 m/s in velocity), pruning at weight ``1e-5``, merging at squared
  Mahalanobis distance 4, at most 5000 components. fusetrack: ``GMPHDFilter``; Stone Soup:
  ``PointProcessMultiTargetTracker`` with ``PHDUpdater``, ``GaussianMixtureHypothesiser`` over
  a ``DistanceHypothesiser`` (Mahalanobis, ``missed_distance = 5``: component-detection pairs
  beyond 5 sigma are left out; their weight would be below ``exp(-12.5)``) and
  ``GaussianMixtureReducer``. Estimates on both sides: every component with weight > 0.5,
  ``round(w)`` times (Vo & Ma Table III; fusetrack's ``extract_states``, applied to Stone
  Soup's mixture the same way).

**Score**: GOSPA (``c = 20`` m, ``p = 2``, ``alpha = 2``; fusetrack's ``evaluation.gospa`` on
both sides' estimates) between the position estimates of the confirmed tracks (or the PHD's
extracted states) and the true positions, at every scan, averaged over the scans of a run; the
mean and standard error over ``--seeds`` runs.

**Timing**: ``time.process_time`` (CPU seconds of every thread of the process) around each
scan's call (fusetrack ``tracker.step`` / ``predict`` + ``update`` + ``extract_states``; Stone
Soup ``tracker.update_tracker`` (+ the extraction for the PHD)), summed over the scans and
divided by their number; the wall time (``time.perf_counter``) of the same calls beside it
(``wall_seconds_per_scan``, ``wall_speedup``); building measurement and detection objects is
outside the clock. Runs alternate between the libraries seed by seed. BLAS is limited to one
thread (``--threads T``: BLAS/OpenMP and Numba get T threads, ``_results.py``). A 3-scan warm-up
run of each (library, tracker) comes first, untimed (within the budget). ``--budget S``: a library's run stops
after the scan at which its CPU time passed ``S`` seconds (its ``scans`` in the output says how
many it measured), and every figure of the configuration (both libraries' times and GOSPAs) is
then over the first scans that every run measured. A scan that alone would pass the budget is
cut off by a CPU-time alarm (``SIGPROF``): ``cut_by_budget`` is then true for that library and
its time per scan is a lower bound (its GOSPA over the cut scan is NaN).

**Agreement**: the two libraries' mean GOSPAs over the seeds agree when they differ by at most 3
combined standard errors (the t quantile of the same level for few seeds: 3.4 for 10;
``_results.agree_monte_carlo``; ``gospa_paired`` gives the mean and
standard error of the per-seed differences beside it, for information). A configuration that
does not agree has ``"agree": false`` and no ``speedup``; one where a library was cut before
any scan was scored has ``"agree": null``.

``--json`` prints one object per (tracker, targets, clutter) on one line::

    {"tracker": "jpda", "targets": 50, "clutter": 10, "seeds": 10,
     "scans": 100,
     "seconds_per_scan": {"fusetrack": ..., "stonesoup": ...}, "speedup": ...,
     "wall_seconds_per_scan": {...}, "wall_speedup": ..., "agree": ...,
     "gospa": {...}, "gospa_se": {...}, "gospa_paired": {...}, "estimates_per_scan": {...},
     "seconds_per_scan_own": {...}, "scans_own": {...}, "load": ...}
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import signal
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

import _results

Array = NDArray[np.float64]

DT = 1.0
Q_PSD = 1.0  # m^2/s^3 per axis
SIGMA = 5.0  # m, position measurement noise
P_DETECT = 0.9
P_GATE = 0.99
P_SURVIVE = 0.99
HALF_SIDE = 1000.0  # the surveillance square is [-HALF_SIDE, HALF_SIDE]^2 m
START_HALF_SIDE = 900.0
SPEED_SIGMA = 3.0  # m/s, true initial velocities per axis
PRIOR_SPEED_SIGMA = 5.0  # m/s, the velocity prior of a new track / birth component
CONFIRM = 3  # M = N = 3: confirmed after 3 detections in the first 3 scans
MAX_MISSES = 3
BIRTH_WEIGHT = 0.1
BIRTH_POS_SIGMA = 1000.0
PRUNE, MERGE, MAX_COMPONENTS = 1e-5, 4.0, 5000
PHD_MISSED_DISTANCE = 5.0
EXTRACT = 0.5
GOSPA_C, GOSPA_P, GOSPA_ALPHA = 20.0, 2.0, 2.0
START = datetime.datetime(2026, 1, 1)


def cv_model() -> tuple[Array, Array, Array, Array]:
    """``F``, ``Q`` (state ``[x, vx, y, vy]``), ``H`` and ``R`` of the position sensor."""
    f1 = np.array([[1.0, DT], [0.0, 1.0]])
    q1 = Q_PSD * np.array([[DT**3 / 3, DT**2 / 2], [DT**2 / 2, DT]])
    z = np.zeros((2, 2))
    F = np.block([[f1, z], [z, f1]])
    Q = np.block([[q1, z], [z, q1]])
    H = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
    return F, Q, H, SIGMA**2 * np.eye(2)


def clutter_density(clutter: float) -> float:
    return clutter / (2.0 * HALF_SIDE) ** 2


@dataclass(frozen=True)
class Scenario:
    """``truth`` ``(scans, targets, 4)`` and per scan the measured positions ``(m_k, 2)``."""

    targets: int
    clutter: float
    truth: Array
    measurements: list[Array]

    @classmethod
    def simulate(cls, targets: int, clutter: float, scans: int, seed: int) -> Scenario:
        rng = np.random.default_rng(seed)
        F, Q, H, _ = cv_model()
        LQ = np.linalg.cholesky(Q)
        x = np.zeros((targets, 4))
        x[:, [0, 2]] = rng.uniform(-START_HALF_SIDE, START_HALF_SIDE, (targets, 2))
        x[:, [1, 3]] = rng.normal(0.0, SPEED_SIGMA, (targets, 2))
        truth = np.empty((scans, targets, 4))
        zs = []
        for k in range(scans):
            if k:
                x = x @ F.T + rng.standard_normal((targets, 4)) @ LQ.T
            truth[k] = x
            seen = rng.random(targets) < P_DETECT
            z = x[seen] @ H.T + SIGMA * rng.standard_normal((int(seen.sum()), 2))
            n_false = rng.poisson(clutter)
            false = rng.uniform(-HALF_SIDE, HALF_SIDE, (n_false, 2))
            both = np.concatenate([z, false])
            zs.append(both[rng.permutation(len(both))])
        return cls(targets, clutter, truth, zs)


Estimator = Callable[[int], Array]  # scan index -> position estimates (n, 2)


# --------------------------------------------------------------------------------------------
# fusetrack


class FusetrackRun:
    """One fusetrack tracker over a scenario: ``scan(k)`` processes scan ``k`` and returns the
    position estimates after it."""

    def __init__(self, kind: str, scn: Scenario, seed: int) -> None:
        from fusetrack.core import Gaussian, Measurement
        from fusetrack.filters import GMPHDFilter, KalmanFilter, PhdIntensity
        from fusetrack.motion import LinearGaussianMotion
        from fusetrack.sensors import LinearGaussianSensor

        F, Q, H, R = cv_model()
        motion = LinearGaussianMotion(F, Q)
        sensor = LinearGaussianSensor("pos", H, R)
        kappa = clutter_density(scn.clutter)
        self.kind = kind
        self.rng = np.random.default_rng(seed + 10_000)
        self.scans = [
            [Measurement(k * DT, "pos", z) for z in zk] for k, zk in enumerate(scn.measurements)
        ]
        if kind == "phd":
            birth = PhdIntensity(
                [BIRTH_WEIGHT],
                [np.zeros(4)],
                [np.diag([BIRTH_POS_SIGMA**2, PRIOR_SPEED_SIGMA**2] * 2)],
            )
            self.phd = GMPHDFilter(
                motion,
                [sensor],
                birth,
                survival_probability=P_SURVIVE,
                detection_probability=P_DETECT,
                clutter_intensity=kappa,
                truncation_threshold=PRUNE,
                merge_threshold=MERGE,
                max_components=MAX_COMPONENTS,
            )
            self.intensity = PhdIntensity.empty(4)
            return
        from fusetrack.association import (
            GlobalNearestNeighbour,
            JointProbabilisticDataAssociation,
        )
        from fusetrack.tracking import (
            InverseMeasurementPrior,
            MissedCountDeleter,
            MofNInitiator,
            MultiTargetTracker,
        )

        prior = InverseMeasurementPrior(
            [sensor], Gaussian(np.zeros(4), np.diag([0.0, PRIOR_SPEED_SIGMA**2] * 2))
        )
        associator = (
            GlobalNearestNeighbour() if kind == "gnn" else JointProbabilisticDataAssociation()
        )
        self.tracker = MultiTargetTracker(
            KalmanFilter(motion, [sensor]),
            [sensor],
            associator,
            initiator=MofNInitiator(CONFIRM, CONFIRM, prior),
            deleter=MissedCountDeleter(MAX_MISSES),
            p_detect=P_DETECT,
            clutter_density=kappa,
            gate_probability=P_GATE,
            survival_probability=P_SURVIVE,
        )
        self.state = self.tracker.initial_state()

    def scan(self, k: int) -> Array:
        if self.kind == "phd":
            from fusetrack.filters import extract_states

            v = self.phd.predict(self.intensity, DT, self.rng)
            self.intensity = v = self.phd.update(v, self.scans[k], self.rng)
            states = extract_states(v, EXTRACT)
            return np.array([m[[0, 2]] for _, m, _ in states]).reshape(-1, 2)
        self.state = self.tracker.step(self.state, k * DT, self.scans[k], self.rng)
        return np.array([tr.belief.mean[[0, 2]] for tr in self.state.confirmed]).reshape(-1, 2)


# --------------------------------------------------------------------------------------------
# Stone Soup


def _extract_mixture(components: object) -> Array:
    """Vo & Ma Table III on a Stone Soup mixture (the rule of fusetrack's ``extract_states``)."""
    out = []
    for c in components:  # type: ignore[attr-defined]
        w = float(c.weight)
        if w > EXTRACT:
            out += [np.asarray(c.state_vector, float).ravel()[[0, 2]]] * int(np.floor(w + 0.5))
    return np.array(out).reshape(-1, 2)


class StoneSoupRun:
    """The same tracker built from Stone Soup 1.9 components (module docstring)."""

    def __init__(self, kind: str, scn: Scenario, seed: int) -> None:
        from stonesoup.models.measurement.linear import LinearGaussian
        from stonesoup.models.transition.linear import (
            CombinedLinearGaussianTransitionModel,
            ConstantVelocity,
        )
        from stonesoup.predictor.kalman import KalmanPredictor
        from stonesoup.types.detection import Detection
        from stonesoup.updater.kalman import KalmanUpdater

        _, _, _, R = cv_model()
        transition = CombinedLinearGaussianTransitionModel(
            [ConstantVelocity(Q_PSD), ConstantVelocity(Q_PSD)]
        )
        mm = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=R)
        predictor, updater = KalmanPredictor(transition), KalmanUpdater(mm)
        kappa = clutter_density(scn.clutter)
        self.kind = kind
        self.times = [START + datetime.timedelta(seconds=k * DT) for k in range(len(scn.truth))]
        self.scans = [
            {Detection(z.reshape(2, 1), timestamp=t, measurement_model=mm) for z in zk}
            for t, zk in zip(self.times, scn.measurements, strict=True)
        ]
        if kind == "phd":
            self.tracker = self._phd(predictor, updater, kappa)
        else:
            self.tracker = self._tracker(kind, predictor, updater, mm, kappa)

    @staticmethod
    def _tracker(kind: str, predictor: object, updater: object, mm: object, kappa: float) -> object:
        from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
        from stonesoup.dataassociator.probability import JPDAwithEHM
        from stonesoup.deleter.time import UpdateTimeStepsDeleter
        from stonesoup.hypothesiser.probability import PDAHypothesiser
        from stonesoup.initiator.simple import MultiMeasurementInitiator
        from stonesoup.tracker.simple import MultiTargetMixtureTracker, MultiTargetTracker
        from stonesoup.types.state import GaussianState

        hyp = PDAHypothesiser(
            predictor=predictor,
            updater=updater,
            clutter_spatial_density=kappa,
            prob_detect=P_DETECT,
            prob_gate=P_GATE,
        )
        initiator = MultiMeasurementInitiator(
            prior_state=GaussianState(np.zeros((4, 1)), np.diag([0.0, PRIOR_SPEED_SIGMA**2] * 2)),
            measurement_model=mm,
            deleter=UpdateTimeStepsDeleter(1),
            data_associator=GNNWith2DAssignment(hyp),
            updater=updater,
            min_points=CONFIRM,
        )
        cls = MultiTargetTracker if kind == "gnn" else MultiTargetMixtureTracker
        assoc = GNNWith2DAssignment(hyp) if kind == "gnn" else JPDAwithEHM(hyp)
        return cls(
            initiator=initiator,
            deleter=UpdateTimeStepsDeleter(MAX_MISSES),
            detector=None,
            data_associator=assoc,
            updater=updater,
        )

    @staticmethod
    def _phd(predictor: object, updater: object, kappa: float) -> object:
        from stonesoup.hypothesiser.distance import DistanceHypothesiser
        from stonesoup.hypothesiser.gaussianmixture import GaussianMixtureHypothesiser
        from stonesoup.measures import Mahalanobis
        from stonesoup.mixturereducer.gaussianmixture import GaussianMixtureReducer
        from stonesoup.tracker.pointprocess import PointProcessMultiTargetTracker
        from stonesoup.types.state import TaggedWeightedGaussianState
        from stonesoup.updater.pointprocess import PHDUpdater

        base = DistanceHypothesiser(
            predictor, updater, Mahalanobis(), missed_distance=PHD_MISSED_DISTANCE
        )
        birth = TaggedWeightedGaussianState(
            np.zeros((4, 1)),
            np.diag([BIRTH_POS_SIGMA**2, PRIOR_SPEED_SIGMA**2] * 2),
            weight=BIRTH_WEIGHT,
            tag=TaggedWeightedGaussianState.BIRTH,
            timestamp=START,
        )
        return PointProcessMultiTargetTracker(
            detector=None,
            updater=PHDUpdater(
                updater,
                clutter_spatial_density=kappa,
                prob_detection=P_DETECT,
                prob_survival=P_SURVIVE,
            ),
            hypothesiser=GaussianMixtureHypothesiser(base, order_by_detection=True),
            reducer=GaussianMixtureReducer(
                prune_threshold=PRUNE,
                pruning=True,
                merge_threshold=MERGE,
                merging=True,
                max_number_components=MAX_COMPONENTS,
            ),
            extraction_threshold=EXTRACT,
            birth_component=birth,
        )

    def scan(self, k: int) -> Array:
        _, tracks = self.tracker.update_tracker(self.times[k], self.scans[k])  # type: ignore[attr-defined]
        if self.kind == "phd":
            return _extract_mixture(self.tracker.gaussian_mixture)  # type: ignore[attr-defined]
        return np.array(
            [np.asarray(t.state_vector, float).ravel()[[0, 2]] for t in tracks]
        ).reshape(-1, 2)


RUNNERS: dict[str, Callable[[str, Scenario, int], FusetrackRun | StoneSoupRun]] = {
    "fusetrack": FusetrackRun,
    "stonesoup": StoneSoupRun,
}


# --------------------------------------------------------------------------------------------
# measuring


class _OverBudget(Exception):
    """Raised by the CPU-time alarm (``SIGPROF``) when a run passes its budget inside a scan."""


def _raise_over_budget(signum: int, frame: object) -> None:
    raise _OverBudget


def run_once(
    lib: str, kind: str, scn: Scenario, seed: int, scans: int, budget: float
) -> tuple[Array, bool]:
    """``(4, n)``: per scan the CPU seconds, the GOSPA, the number of estimates and the wall
    seconds, for the ``n`` scans run (all, or up to the one at which the CPU time passed ``budget``); and
    whether the last scan was cut off by the budget (its time is then a lower bound and its
    GOSPA NaN)."""
    from fusetrack.evaluation import gospa

    runner = RUNNERS[lib](kind, scn, seed)
    rows: list[tuple[float, float, float, float]] = []
    cpu, cut = 0.0, False
    old = signal.signal(signal.SIGPROF, _raise_over_budget)
    try:
        for k in range(scans):
            if np.isfinite(budget):  # a CPU-time alarm for what is left of the budget
                signal.setitimer(signal.ITIMER_PROF, max(budget - cpu, 1e-3))
            c0, w0 = time.process_time(), time.perf_counter()
            try:
                est = runner.scan(k)
            except _OverBudget:
                rows.append((time.process_time() - c0, np.nan, np.nan, time.perf_counter() - w0))
                cut = True
                break
            finally:
                signal.setitimer(signal.ITIMER_PROF, 0.0)
            dt, wall = time.process_time() - c0, time.perf_counter() - w0
            cpu += dt
            truth = scn.truth[k][:, [0, 2]]
            g = gospa(est, truth, c=GOSPA_C, p=GOSPA_P, alpha=GOSPA_ALPHA).distance
            rows.append((dt, g, len(est), wall))
            if cpu > budget:
                break
    finally:
        signal.signal(signal.SIGPROF, old)
    return np.array(rows, dtype=float).T, cut


def measure(kind: str, targets: int, clutter: float, args: argparse.Namespace) -> dict[str, object]:
    """One configuration over ``args.seeds`` seeds. Every figure is over the first ``n`` scans
    of each run, ``n`` the fewest any run of any library measured (all of them without
    ``--budget``), so both libraries are timed and scored on the same scans;
    ``seconds_per_scan_own`` is each library's time over all the scans it ran."""
    warm = Scenario.simulate(targets, clutter, 3, 12345)
    for lib in args.libs:
        run_once(lib, kind, warm, 12345, 3, args.budget)
    per: dict[str, list[Array]] = {lib: [] for lib in args.libs}
    cut: dict[str, bool] = dict.fromkeys(args.libs, False)
    for seed in range(args.seeds):
        scn = Scenario.simulate(targets, clutter, args.scans, seed)
        for lib in args.libs:
            rows, was_cut = run_once(lib, kind, scn, seed, args.scans, args.budget)
            per[lib].append(rows)
            cut[lib] |= was_cut
    n = min(r.shape[1] for rs in per.values() for r in rs)
    sec = {lib: float(np.mean([r[0, :n].mean() for r in rs])) for lib, rs in per.items()}
    wall = {lib: float(np.mean([r[3, :n].mean() for r in rs])) for lib, rs in per.items()}
    g = {lib: np.array([r[1, :n].mean() for r in rs]) for lib, rs in per.items()}
    se = {
        lib: float(v.std(ddof=1) / np.sqrt(len(v))) if len(v) > 1 else float("nan")
        for lib, v in g.items()
    }
    out: dict[str, object] = {
        "tracker": kind,
        "targets": targets,
        "clutter": clutter,
        "seeds": args.seeds,
        "scans": n,
        "seconds_per_scan": sec,
        "wall_seconds_per_scan": wall,
        "gospa": {lib: float(v.mean()) for lib, v in g.items()},
        "gospa_se": se,
        "estimates_per_scan": {
            lib: float(np.mean([r[2, :n].mean() for r in rs])) for lib, rs in per.items()
        },
        "seconds_per_scan_own": {
            lib: float(np.mean([r[0].mean() for r in rs])) for lib, rs in per.items()
        },
        "scans_own": {lib: [int(r.shape[1]) for r in rs] for lib, rs in per.items()},
        "cut_by_budget": cut,
        "load": os.getloadavg()[0],
    }
    if "fusetrack" in sec and "stonesoup" in sec:
        out.update(gospa_agreement(g["fusetrack"], g["stonesoup"]))
        ok = out["agree"] is not False
        out["speedup"] = sec["stonesoup"] / sec["fusetrack"] if ok else None
        out["wall_speedup"] = wall["stonesoup"] / wall["fusetrack"] if ok else None
    return out


def gospa_agreement(a: Array, b: Array) -> dict[str, object]:
    """``agree`` (``_results.agree_monte_carlo`` on the means and standard errors over seeds),
    and the paired per-seed difference ``a - b`` (mean, standard error) for information."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        return {"agree": None, "gospa_paired": None}
    ma, sa = _results.mean_se(a.tolist())
    mb, sb = _results.mean_se(b.tolist())
    check = _results.agree_monte_carlo(ma, sa, mb, sb, len(a), len(b))
    md, sd = _results.mean_se((a - b).tolist())
    return {"agree": check["agree"], "gospa_paired": {"difference": md, "se": sd}}


def _row(res: dict) -> str:
    sec, g, se = res["seconds_per_scan"], res["gospa"], res["gospa_se"]
    parts = [
        f"{res['tracker']:>4} {res['targets']:>4} targets {res['clutter']:>5g} clutter "
        f"({res['scans']} scans):"
    ]
    for lib in sec:
        parts.append(
            f"{lib} {sec[lib] * 1e3:8.2f} ms/scan, "
            f"GOSPA {g[lib]:6.2f} +- {se[lib]:.2f}, {res['estimates_per_scan'][lib]:.1f} est;"
        )
    if res.get("agree") is False:
        parts.append("GOSPA DISAGREES (> 3 SE): no speed-up")
    elif res.get("speedup") is not None:
        parts.append(f"speed-up {res['speedup']:.1f}x cpu, {res['wall_speedup']:.1f}x wall")
    return " ".join(parts)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--trackers", nargs="+", default=["gnn", "jpda", "phd"], choices=["gnn", "jpda", "phd"]
    )
    ap.add_argument("--targets", nargs="+", type=int, default=[10, 50])
    ap.add_argument("--clutter", nargs="+", type=float, default=[10.0])
    ap.add_argument("--scans", type=int, default=100)
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--libs", nargs="+", default=["fusetrack", "stonesoup"], choices=list(RUNNERS))
    ap.add_argument("--budget", type=float, default=np.inf, help="CPU seconds per library run")
    ap.add_argument("--json", action="store_true", help="one JSON object per configuration")
    _results.add_arguments(ap)
    args = ap.parse_args(argv)
    if min(args.targets) < 1 or args.scans < 1 or args.seeds < 1 or min(args.clutter) <= 0:
        ap.error("--targets, --scans and --seeds must be >= 1, --clutter > 0")
    if not args.json:
        print(
            f"{args.scans} scans, {args.seeds} seeds, CPU time per scan (process_time), BLAS 1 "
            f"thread; load average {os.getloadavg()[0]:.2f}",
            flush=True,
        )
    if args.threads is not None and args.threads < 1:
        ap.error("--threads must be >= 1")
    run, rows = _results.Run(argv, __file__), []
    with _results.limit_threads(args.threads) as threads:
        run.threads = threads
        for kind in args.trackers:
            for targets in args.targets:
                for clutter in args.clutter:
                    res = measure(kind, targets, clutter, args)
                    rows.append(res)
                    print(json.dumps(res) if args.json else _row(res), flush=True)
    run.save(_results.out_path(args, __file__), rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
