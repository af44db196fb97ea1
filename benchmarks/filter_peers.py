"""Particle-filter variants against the peer libraries' own implementations of the same variant,
on the same model, with the same particles and proposal (issue 21, item 2; ``filters.py`` times
every variant against fusetrack's bootstrap).

    python benchmarks/filter_peers.py [--N 1000 10000 100000] [--steps 10] [--repeats 5]
        [--variants bootstrap UPF MM-bootstrap] [--max-seconds 150] [--threads T]
        [--json] [--save | --out PATH]

Model: Zhai 2007's E2/E13 set-up of ``zhai2007_speed.py`` (2-D CV target, one bearing sensor at
the origin, sigma 0.05 rad), ``--steps`` steps of one simulated run; every library filters the
same bearings from the same Gaussian prior and reports the mean of its particles after each step.
Peers found in Stone Soup 1.9.1 and ``particles`` 0.3 (``PEERS``):

* ``bootstrap``: Stone Soup ``ParticlePredictor`` + ``ParticleUpdater(SystematicResampler())``;
  ``particles`` ``SMC(Bootstrap, resampling="systematic", ESSrmin=1)``.
* ``UPF`` (unscented proposal): Stone Soup ``KalmanProposal(KalmanPredictor,
  UnscentedKalmanUpdater(alpha=1, beta=2, kappa=3-d))`` -- per particle, a Kalman predict of the
  point mass ``N(x_i, 0)`` and an unscented update with the step's bearing give the proposal
  ``N(m_i, S_i)``, weight ``p(z|x) p(x|x_i) / q(x)``. fusetrack's ``UPF`` of ``filters.py``
  starts each particle's UKF from the particle set's covariance instead; here it runs in Stone
  Soup's form (:class:`PointMassUnscentedProposal`: the same ``UnscentedProposal`` with a zero
  covariance carried), so both draw from the same proposal.
* ``MM-bootstrap`` (Zhai 2007 Alg. 3, the four regimes and ``PI4`` of ``zhai2007_speed.py``):
  Stone Soup ``MultiModelPredictor`` + ``MultiModelParticleUpdater``, the two turns given to it as
  a Stone Soup transition model calling fusetrack's ``ManeuverTurn.mean`` (Stone Soup has no
  turn at a fixed manoeuvre acceleration). Not the same algorithm: Stone Soup moves a particle
  with its *previous* regime's model, then draws the new regime, and multiplies the weight by
  ``PI4[r_prev, r_new]`` although the regime was drawn from that row; fusetrack draws the regime
  first (Eq. 47) and weights by the likelihood only. The agreement check below says whether the
  two estimate the track equally well.

Every other variant of ``filters.py`` has no peer (``NO_PEER``, with the reason); the results
file lists them.

Timing: each library runs ``--repeats`` times (seeds 0, 1, ...) round-robin after one untimed
run of 2 steps (compilation, caches; it also estimates the time per step); each run is a whole
run (prior draw, ``steps`` predict + update + resample + mean) built outside the clock, divided
by ``steps``; wall and CPU (``_results.Clock``), the median over the runs. A library whose
estimated ``repeats`` runs would take over ``--max-seconds`` is skipped at that N (and at every
larger N, estimated from the last N measured, linearly). BLAS on one thread unless ``--threads``.
Operations per particle: fusetrack's count of the variant (``filters.OPS``); ``ns_per_op`` =
CPU per particle over it, for each library.

Agreement (``_results.agree_monte_carlo``): position RMSE against the simulated truth, mean over
the timed runs; a peer agrees when the means differ by at most the t quantile (3-sigma level) of
the combined standard error. A peer that disagrees gets no speed-up.
"""

from __future__ import annotations

import argparse
import gc
import json
import statistics
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results
import filters
import zhai2007_speed
from _scenario import Array, position_rmse
from fusetrack.filters.unscented_proposal import UnscentedProposal

WARMUP_STEPS = 2
SEED_DATA = 7  # the simulated run of zhai2007_speed.scenario

NO_PEER: dict[str, str] = {
    "PF-SP-PEKF": "no library has the EKF-bank (Gaussian-sum) proposal of Zhai 2007 Alg. 1",
    "CPF-SP": "no library has Zhai 2007 Alg. 2 (weighted multi-sensor EKF banks)",
    "MMPF-SP": "no library has the per-regime EKF-bank proposal (Zhai 2007 Alg. 4)",
    "Galerkin PF": "no library has a grid (Galerkin) proposal",
    "discretisation PF": "no library has the partitioned-space (cell) proposal",
    "discretisation MMPF": "no library has the partitioned-space proposal",
    "PF + MH-prior move": "no library has a Metropolis move from the transition prior",
    "PF + RWM move": (
        "Stone Soup's MCMCRegulariser is a different move (kernel h_opt chol(posterior cov), "
        "acceptance with the posterior covariance as the transition's): not the same algorithm"
    ),
    "PF + MIS move": "no library has an independence-sampler move",
    "ASIR, position fix": "the waypoint-regime room model of Ercan 2013 exists only in fusetrack",
    "ASIR, occlusion-aware": (
        "no library has the occlusion-aware camera likelihood (Ercan 2013 Eqs. 6-9); "
        "particles' AuxiliaryPF framework would need the model and likelihood written for it"
    ),
    "bootstrap, 9 Gaussian bearings": "the kushwaha2010 baseline: peers timed on bootstrap above",
    "detection-function PF": "no library has Kushwaha 2010's beam / mixture detection functions",
}
PARTICLES_NOTE = (
    "particles 0.3 offers GuidedPF / AuxiliaryPF as frameworks (the user writes the proposal) but "
    "no unscented or multiple-model proposal, and its MvNormal takes one covariance for all "
    "particles: a UPF there would be our code, not the library's, so it is not timed"
)


# --------------------------------------------------------------------------------------------
# the model


@dataclass(frozen=True)
class Model:
    """The E2/E13 run: fusetrack's motion, sensor and prior, bearings ``zs`` and ``truth``."""

    motion: Any
    sensor: Any
    prior: Any
    zs: list[list[Array]]
    truth: Array  # (steps, 4)

    @property
    def F(self) -> Array:
        return np.asarray(self.motion.transition_matrix(1.0), float)

    @property
    def Q(self) -> Array:
        return np.asarray(self.motion.noise_cov(1.0), float)


def make_model(steps: int) -> Model:
    return Model(*zhai2007_speed.simulate(steps, SEED_DATA))


@dataclass
class PointMassUnscentedProposal(UnscentedProposal):
    """The unscented proposal with each particle a point mass ``N(x_i, 0)`` before its UKF
    predict (Stone Soup's ``KalmanProposal``): no covariance carried between steps."""

    def initialize(self, prior: Any, particles: Array, rng: np.random.Generator) -> Array:
        d = particles.shape[-1]
        return np.zeros((*particles.shape[:-2], d, d))

    def feedback(self, state: Array, particles: Array, estimate: Array, filt: Any) -> Array:
        return np.zeros_like(state)


# --------------------------------------------------------------------------------------------
# the runners: built outside the clock; run(seed) -> (steps, 2) position estimates


class FusetrackRunner:
    """``zhai2007_speed.builders`` (bootstrap, MM-bootstrap) or the point-mass UPF."""

    def __init__(self, variant: str, model: Model, n: int) -> None:
        from fusetrack.filters.sis import ProposalParticleFilter

        self.model = model
        if variant == "UPF":
            self.filt: Any = ProposalParticleFilter(
                model.motion, [model.sensor], PointMassUnscentedProposal(), n
            )
        else:
            self.filt = zhai2007_speed.builders(n)[variant]()

    def run(self, seed: int, steps: int) -> Array:
        from fusetrack.experiments.zhai2007.common import run_steps

        est = run_steps(self.filt, self.model.prior, self.model.zs[:steps], 1.0,
                        np.random.default_rng(seed))  # fmt: skip
        return np.array([np.asarray(e, float)[:2] for e in est])


def _stonesoup_transition(model: Any) -> Any:
    """A Stone Soup transition model computing fusetrack's ``model.mean`` and ``noise_cov``
    (layout ``[x, y, vx, vy]``)."""
    from stonesoup.models.base import TimeVariantModel
    from stonesoup.models.transition.nonlinear import GaussianTransitionModel
    from stonesoup.types.array import CovarianceMatrix, StateVectors

    class FusetrackTransition(GaussianTransitionModel, TimeVariantModel):
        @property
        def ndim_state(self) -> int:
            return 4

        def function(self, state: Any, noise: Any = False, **kwargs: Any) -> Any:
            dt = kwargs["time_interval"].total_seconds()
            x = np.asarray(model.mean(np.asarray(state.state_vector, float).T, dt), float).T
            if noise is True:
                noise = self.rvs(num_samples=x.shape[1], **kwargs)
            return StateVectors(x) + (0 if noise is False or noise is None else noise)

        def covar(self, time_interval: Any, **kwargs: Any) -> Any:
            return CovarianceMatrix(model.noise_cov(time_interval.total_seconds()))

    return FusetrackTransition()


class StoneSoupRunner:
    """Stone Soup's particle predictor / updater for ``variant``, state ``[x, y, vx, vy]``."""

    def __init__(self, variant: str, model: Model, n: int) -> None:
        from datetime import datetime, timedelta

        from stonesoup.models.measurement.nonlinear import Cartesian2DToBearing
        from stonesoup.models.transition.linear import LinearGaussianTimeInvariantTransitionModel
        from stonesoup.predictor.kalman import KalmanPredictor
        from stonesoup.predictor.particle import MultiModelPredictor, ParticlePredictor
        from stonesoup.proposal.simple import KalmanProposal
        from stonesoup.resampler.particle import SystematicResampler
        from stonesoup.types.angle import Bearing
        from stonesoup.types.array import StateVector
        from stonesoup.types.detection import Detection
        from stonesoup.updater.kalman import UnscentedKalmanUpdater
        from stonesoup.updater.particle import MultiModelParticleUpdater, ParticleUpdater

        self.variant, self.model, self.n = variant, model, n
        cv = LinearGaussianTimeInvariantTransitionModel(model.F, model.Q)
        bearing = Cartesian2DToBearing(
            ndim_state=4, mapping=(0, 1), noise_covar=np.array([[model.sensor.sigma**2]])
        )
        resampler = SystematicResampler()
        self.predictor: Any
        if variant == "bootstrap":
            self.predictor = ParticlePredictor(cv)
            self.updater: Any = ParticleUpdater(bearing, resampler=resampler)
        elif variant == "UPF":
            d = model.F.shape[0]
            proposal = KalmanProposal(
                KalmanPredictor(cv),
                UnscentedKalmanUpdater(bearing, alpha=1.0, beta=2.0, kappa=3.0 - d),
            )
            self.predictor = ParticlePredictor(cv, proposal=proposal)
            self.updater = ParticleUpdater(bearing, resampler=resampler)
        else:  # MM-bootstrap
            regimes = [
                _stonesoup_transition(m) if type(m).__name__ == "ManeuverTurn" else
                LinearGaussianTimeInvariantTransitionModel(
                    np.asarray(m.transition_matrix(1.0), float), np.asarray(m.noise_cov(1.0)))
                for m in zhai2007_speed.mm_models()
            ]  # fmt: skip
            self.predictor = MultiModelPredictor(
                transition_models=regimes,
                transition_matrix=zhai2007_speed.PI4,
                model_mappings=[(0, 1, 2, 3)] * len(regimes),
            )
            self.updater = MultiModelParticleUpdater(
                bearing, predictor=self.predictor, resampler=resampler
            )
        self.start = datetime(2024, 1, 1)
        self.detections = [
            Detection(StateVector([[Bearing(float(np.ravel(z[0])[0]))]]),
                      timestamp=self.start + timedelta(seconds=k + 1), measurement_model=bearing)
            for k, z in enumerate(model.zs)
        ]  # fmt: skip

    def _prior(self) -> Any:
        from scipy.stats import multivariate_normal
        from stonesoup.types.state import MultiModelParticleState, ParticleState, StateVectors

        x = multivariate_normal.rvs(self.model.prior.mean, self.model.prior.cov, size=self.n)
        kw = {"log_weight": np.full(self.n, -np.log(self.n)), "timestamp": self.start}
        if self.variant == "MM-bootstrap":
            return MultiModelParticleState(
                StateVectors(x.T), dynamic_model=np.zeros(self.n, dtype=int), **kw
            )
        return ParticleState(StateVectors(x.T), **kw)

    def run(self, seed: int, steps: int) -> Array:
        from stonesoup.types.hypothesis import SingleHypothesis

        np.random.seed(seed)  # noqa: NPY002 - Stone Soup draws from NumPy's global generator
        state = self._prior()
        est = np.empty((steps, 2))
        for k, det in enumerate(self.detections[:steps]):
            if self.variant == "UPF":
                state = self.predictor.predict(state, timestamp=det.timestamp, measurement=det)
            else:
                state = self.predictor.predict(state, timestamp=det.timestamp)
            state = self.updater.update(SingleHypothesis(state, det))
            est[k] = np.asarray(state.mean, float)[:2, 0]
        return est

    def cleanup(self) -> None:
        """Empty the predictors' LRU caches of whole particle sets (outside the clock)."""
        fns = [type(self.predictor).predict, getattr(self.updater, "predict_measurement", None)]
        for f in [*fns, *(getattr(fn, "__wrapped__", None) for fn in fns)]:
            clear = getattr(f, "cache_clear", None)
            if clear is not None:
                clear()


class ParticlesRunner:
    """``particles``: ``SMC(fk=Bootstrap(...), resampling="systematic", ESSrmin=1.0)``; its
    ``X_0`` is the state at time 1 (the prior pushed through the motion model)."""

    def __init__(self, variant: str, model: Model, n: int) -> None:
        import particles.distributions as dists
        from particles import state_space_models as ssm

        F, Q, m0, P0 = model.F, model.Q, model.prior.mean, model.prior.cov
        pos, sigma = np.asarray(model.sensor.position, float), float(model.sensor.sigma)

        class Bearing(dists.ProbDist):
            dim = 1

            def __init__(self, x: Array) -> None:
                self.x = x

            def logpdf(self, y: Array) -> Array:
                b = np.arctan2(self.x[:, 1] - pos[1], self.x[:, 0] - pos[0])
                r = ((np.ravel(y)[0] - b + np.pi) % (2 * np.pi) - np.pi) / sigma
                return -0.5 * r * r - np.log(sigma) - 0.5 * np.log(2 * np.pi)

        class BearingCV(ssm.StateSpaceModel):
            def PX0(self) -> Any:
                return dists.MvNormal(loc=F @ m0, cov=F @ P0 @ F.T + Q)

            def PX(self, t: int, xp: Array) -> Any:
                return dists.MvNormal(loc=xp @ F.T, cov=Q)

            def PY(self, t: int, xp: Array, x: Array) -> Any:
                return Bearing(x)

        self.ssm, self.n = BearingCV(), n
        self.data = [np.ravel(z[0]) for z in model.zs]

    def run(self, seed: int, steps: int) -> Array:
        import particles
        from particles import collectors
        from particles import state_space_models as ssm

        np.random.seed(seed)  # noqa: NPY002 - particles draws from NumPy's global generator
        alg = particles.SMC(
            fk=ssm.Bootstrap(ssm=self.ssm, data=self.data[:steps]), N=self.n,
            resampling="systematic", ESSrmin=1.0, collect=[collectors.Moments()], verbose=False,
        )  # fmt: skip
        alg.run()
        return np.array([m["mean"][:2] for m in alg.summaries.moments])


RUNNERS: dict[str, Callable[[str, Model, int], Any]] = {
    "fusetrack": FusetrackRunner,
    "stonesoup": StoneSoupRunner,
    "particles": ParticlesRunner,
}
# variant -> (the peers' implementations, what they are)
PEERS: dict[str, tuple[tuple[str, ...], str]] = {
    "bootstrap": (("stonesoup", "particles"),
                  "Stone Soup ParticlePredictor + ParticleUpdater(SystematicResampler); "
                  "particles SMC(Bootstrap, systematic, ESSrmin=1)"),
    "UPF": (("stonesoup",),
            "Stone Soup ParticlePredictor(proposal=KalmanProposal(KalmanPredictor, "
            "UnscentedKalmanUpdater)); fusetrack's UnscentedProposal with point-mass particles"),
    "MM-bootstrap": (("stonesoup",),
                     "Stone Soup MultiModelPredictor + MultiModelParticleUpdater (moves with the "
                     "previous regime, weights by PI4 again: not the same algorithm)"),
}  # fmt: skip


# --------------------------------------------------------------------------------------------
# timing


def _run(runner: Any, seed: int, steps: int, truth: Array) -> dict[str, float]:
    gc.collect()
    with _results.Clock() as c:
        est = runner.run(seed, steps)
    if hasattr(runner, "cleanup"):
        runner.cleanup()
    return {"wall": c.wall / steps, "cpu": c.cpu / steps, "rmse": position_rmse(est, truth)}


def measure_size(
    variant: str, n: int, libs: list[str], model: Model, args: argparse.Namespace,
    last: dict[str, tuple[int, float]],
) -> tuple[dict[str, Any], list[dict[str, Any]]]:  # fmt: skip
    """Time ``libs`` on ``variant`` at ``n`` (round-robin over ``--repeats`` seeds); ``last``
    (library -> (N, CPU seconds per step)) estimates the cost and is updated."""
    runners, skipped = {}, []
    truth = model.truth[: args.steps, :2]
    for lib in libs:
        est = last[lib][1] * n / last[lib][0] if lib in last else None
        if est is not None and est * args.steps * args.repeats > args.max_seconds:
            skipped.append({"variant": variant, "library": lib, "N": n,
                            "estimated_seconds": est * args.steps * args.repeats})  # fmt: skip
            continue
        runners[lib] = RUNNERS[lib](variant, model, n)
        warm = _run(runners[lib], 99, WARMUP_STEPS, truth[:WARMUP_STEPS])
        est = warm["cpu"]
        if lib != "fusetrack" and est * args.steps * args.repeats > args.max_seconds:
            skipped.append({"variant": variant, "library": lib, "N": n,
                            "estimated_seconds": est * args.steps * args.repeats})  # fmt: skip
            last[lib] = (n, est)
            del runners[lib]
    runs: dict[str, list[dict[str, float]]] = {lib: [] for lib in runners}
    for r in range(args.repeats):
        for lib, runner in runners.items():
            runs[lib].append(_run(runner, r, args.steps, truth))
    for lib in runners:
        last[lib] = (n, statistics.median(x["cpu"] for x in runs[lib]))
    return _row(variant, n, runs), skipped


def _row(variant: str, n: int, runs: dict[str, list[dict[str, float]]]) -> dict[str, Any]:
    ops = filters.operations(variant, n)
    row: dict[str, Any] = {"variant": variant, "N": n, "peers": PEERS[variant][1],
                           "ops_per_particle": ops, "runs": {}, "rmse": {}, "rmse_se": {},
                           "wall_seconds_per_step": {}, "cpu_seconds_per_step": {},
                           "ns_per_op": {}, "agreement": {}, "speedup_over": {}}  # fmt: skip
    for lib, rs in runs.items():
        m, se = _results.mean_se([x["rmse"] for x in rs])
        row["runs"][lib], row["rmse"][lib], row["rmse_se"][lib] = len(rs), m, se
        for clock in ("wall", "cpu"):
            row[f"{clock}_seconds_per_step"][lib] = statistics.median(x[clock] for x in rs)
        row["ns_per_op"][lib] = 1e9 * row["cpu_seconds_per_step"][lib] / n / ops
    ft = "fusetrack"
    for lib in runs:
        if lib == ft or ft not in runs:
            continue
        a = _results.agree_monte_carlo(row["rmse"][lib], row["rmse_se"][lib], row["rmse"][ft],
                                       row["rmse_se"][ft], len(runs[lib]), len(runs[ft]))  # fmt: skip
        row["agreement"][lib] = a
        row["speedup_over"][lib] = None if a["agree"] is False else {
            clock: _results.ratio(row[f"{clock}_seconds_per_step"][lib],
                                  row[f"{clock}_seconds_per_step"][ft])
            for clock in ("wall", "cpu")
        }  # fmt: skip
    row["agree"] = _results.all_agree([a["agree"] for a in row["agreement"].values()])
    return row


def measure(args: argparse.Namespace) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    model = make_model(args.steps)
    rows, skipped = [], []
    for variant in args.variants:
        libs = ["fusetrack", *PEERS[variant][0]]
        last: dict[str, tuple[int, float]] = {}
        for n in sorted(args.N):
            row, skip = measure_size(variant, n, libs, model, args, last)
            rows.append(row)
            skipped += skip
            if not args.json:
                print(_line(row), *(f"  skipped {s}" for s in skip), sep="\n", flush=True)
    return rows, skipped


def _line(r: dict[str, Any]) -> str:
    cells = []
    for lib, t in r["cpu_seconds_per_step"].items():
        sp = r["speedup_over"].get(lib)
        extra = f" ({sp['cpu']:.1f}x cpu)" if sp and sp.get("cpu") else ""
        if r["agreement"].get(lib, {}).get("agree") is False:
            extra = " (RMSE disagrees)"
        cells.append(f"{lib} {t * 1e3:.3g} ms, RMSE {r['rmse'][lib]:.3f}{extra}")
    return f"{r['variant']:13s} N={r['N']:<7d} " + "; ".join(cells)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--N", type=int, nargs="+", default=[1000, 10000, 100000])
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--variants", nargs="+", default=list(PEERS), choices=list(PEERS))
    ap.add_argument("--max-seconds", type=float, default=150.0,
                    help="skip a peer whose timed runs at an N would take longer (CPU s)")  # fmt: skip
    ap.add_argument("--json", action="store_true")
    _results.add_arguments(ap)
    args = ap.parse_args(argv)
    if min(args.N) < 1 or args.steps < WARMUP_STEPS or args.repeats < 1:
        ap.error(f"--N and --repeats must be >= 1, --steps >= {WARMUP_STEPS}")
    if args.threads is not None and args.threads < 1:
        ap.error("--threads must be >= 1")
    run = _results.Run(argv, __file__)
    with _results.limit_threads(args.threads) as threads:
        run.threads = threads
        rows, skipped = measure(args)
    no_peer = {"no_peer": NO_PEER, "particles": PARTICLES_NOTE, "skipped": skipped,
               "steps": args.steps, "repeats": args.repeats, "max_seconds": args.max_seconds}  # fmt: skip
    doc = [*rows, no_peer]
    if args.json:
        print(json.dumps(doc, default=float))
    run.save(_results.out_path(args, __file__), doc)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
