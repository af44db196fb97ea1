"""Speed of one bootstrap particle filter in fusetrack, Stone Soup, ``particles`` and plain NumPy,
beside a hand-fused Numba *limit reference* of the same filter (``_limit_reference.py``).

The filter (the same in all four): 2-D constant velocity ``[x, y, vx, vy]`` with continuous
white-noise acceleration (PSD ``q``), three bearing sensors at fixed known positions, Gaussian
prior, bootstrap proposal, systematic resampling after every step, 100 steps. All four filter
the same simulated truth and measurements (``_scenario.py``, one fixed seed) and report the
weighted particle mean of the position, so their RMSEs must agree within Monte Carlo error.

    python benchmarks/pf_bearing.py [--N 1000 10000 100000 1000000]
        [--libs fusetrack stonesoup particles numpy limit_reference] [--repeats K] [--steps S]
        [--sensors S1 S2 ...] [--threads T] [--json] [--save | --out PATH]

``limit_reference`` is not a library: it is this one filter written as two fused Numba loops
(propagate + all likelihoods; weights + estimate + systematic resampling) with the noise from
NumPy's generator, i.e. about as fast as this filter can be written by hand. It draws exactly what
fusetrack draws, so its RMSE equals fusetrack's to rounding. BLAS is limited to one thread for
every library (a threaded (N, 4) @ (4, 4) product is pathologically slow on a loaded machine);
``--threads T`` gives every library T threads instead (BLAS/OpenMP via threadpoolctl, Numba via
``numba.set_num_threads``: fusetrack's and the limit reference's threaded loops; ``_results.py``).

Timing: ``time.perf_counter`` and ``time.process_time`` (CPU seconds of all the process's
threads) around a whole run (prior draw, then ``steps`` predict + update + resample + mean),
divided by ``steps``; the median over ``--repeats`` runs, taken round-robin over the libraries.
``--clock`` chooses which of the two is ``seconds_per_step`` (and the budget's estimate); both
are in the JSON (``wall_seconds_per_step``, ``cpu_seconds_per_step``) with the ratios both
ways. Each library is first warmed up with a 3-step run (Numba JIT compile time is excluded);
that run, or the previous N scaled linearly, estimates the time per step, and a library whose
estimate exceeds ``--budget`` seconds per step is skipped ("skipped (est. Xs)", JSON ``null``).

Agreement: every timed run (seed ``--seed + r``) scores its RMSE; a library agrees with
fusetrack when their mean RMSEs over the runs differ by at most 3 combined standard errors
(with few runs the t quantile of the same level instead of 3, ``_results.agree_monte_carlo``;
with one run a library borrows the other's spread). A library
that does not agree gets ``"agree": false`` and no speed-up (the table prints "disagrees").

``--sensors S1 S2 ...``: the sensors sweep instead of the three fixed sensors: the same truth
seen by S bearing sensors on a circle (``_scenario.with_sensors``), one row per (S, N).

Building models and measurement objects happens before the clock starts, for every library.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _results
from _limit_reference import LimitReferencePF
from _scenario import (
    Array,
    Scenario,
    cv_matrices,
    make_scenario,
    position_rmse,
    with_sensors,
    wrap,
)

LIBS = ("fusetrack", "stonesoup", "particles", "numpy", "limit_reference")
WARMUP_STEPS = 3


# --------------------------------------------------------------------------------------------
# (1) fusetrack


class FusetrackPF:
    """``filters.BootstrapFilter`` with ``motion.ConstantVelocity`` and ``sensors.Bearing``."""

    def __init__(self, scn: Scenario, n: int) -> None:
        from fusetrack.core import Gaussian, Measurement
        from fusetrack.filters import BootstrapFilter
        from fusetrack.motion import ConstantVelocity
        from fusetrack.sensors import Bearing

        sensors = [
            Bearing(sensor_id=sid, position=pos, sigma=scn.sigma)
            for sid, pos in zip(scn.sensor_ids, scn.sensors)
        ]
        self.filt = BootstrapFilter(
            ConstantVelocity(ndim=2, q=scn.q, noise="continuous"),
            sensors,
            n_particles=n,
            resampler="systematic",
            ess_threshold=1.0,
            engine="numba",
        )
        self.prior = Gaussian(scn.prior_mean, scn.prior_cov)
        self.dt = scn.dt
        self.measurements = [
            [
                Measurement((k + 1) * scn.dt, sid, [scn.z[k, i]])
                for i, sid in enumerate(scn.sensor_ids)
            ]
            for k in range(scn.steps)
        ]

    def run(self, seed: int, steps: int) -> Array:
        rng = np.random.default_rng(seed)
        filt = self.filt
        p = filt.initialize(self.prior, rng)
        est = np.empty((steps, 2))
        for k in range(steps):
            p = filt.predict(p, self.dt, rng)
            p = filt.update(p, self.measurements[k], rng)
            est[k] = filt.mean(p)[:2]  # weighted mean (cached weights, one pass)
        return est


# --------------------------------------------------------------------------------------------
# (2) Stone Soup: state layout [x, vx, y, vy]; three detections per step, each with its own
# Cartesian2DToBearing model, applied in sequence; only the last update of a step resamples.


class StoneSoupPF:
    """``ParticlePredictor``, ``ParticleUpdater`` and ``SystematicResampler`` (the tutorial way)."""

    def __init__(self, scn: Scenario, n: int) -> None:
        from datetime import datetime, timedelta

        from stonesoup.models.measurement.nonlinear import Cartesian2DToBearing
        from stonesoup.models.transition.linear import (
            CombinedLinearGaussianTransitionModel,
            ConstantVelocity,
        )
        from stonesoup.predictor.particle import ParticlePredictor
        from stonesoup.resampler.particle import SystematicResampler
        from stonesoup.types.angle import Bearing
        from stonesoup.types.array import StateVector
        from stonesoup.types.detection import Detection
        from stonesoup.types.hypothesis import SingleHypothesis
        from stonesoup.types.state import ParticleState, StateVectors
        from stonesoup.updater.particle import ParticleUpdater

        self._ParticleState, self._StateVectors, self._Hypothesis = (
            ParticleState,
            StateVectors,
            SingleHypothesis,
        )
        self._ParticlePredictor = ParticlePredictor
        self.n = n
        transition = CombinedLinearGaussianTransitionModel(
            [ConstantVelocity(scn.q), ConstantVelocity(scn.q)]
        )
        models = [
            Cartesian2DToBearing(
                ndim_state=4,
                mapping=(0, 2),
                noise_covar=np.array([[scn.sigma**2]]),
                translation_offset=StateVector([[pos[0]], [pos[1]]]),
            )
            for pos in scn.sensors
        ]
        self.predictor = ParticlePredictor(transition)
        self.updater = ParticleUpdater(measurement_model=models[0])
        self.updater_resample = ParticleUpdater(
            measurement_model=models[0], resampler=SystematicResampler()
        )
        self.start = datetime(2024, 1, 1)
        self.detections = [
            [
                Detection(
                    StateVector([[Bearing(scn.z[k, i])]]),
                    timestamp=self.start + timedelta(seconds=(k + 1) * scn.dt),
                    measurement_model=models[i],
                )
                for i in range(len(models))
            ]
            for k in range(scn.steps)
        ]
        perm = [0, 2, 1, 3]  # [x, y, vx, vy] -> [x, vx, y, vy]
        self.prior_mean = scn.prior_mean[perm]
        self.prior_cov = scn.prior_cov[np.ix_(perm, perm)]

    def run(self, seed: int, steps: int) -> Array:
        from scipy.stats import multivariate_normal

        np.random.seed(seed)  # noqa: NPY002 - Stone Soup draws from NumPy's global generator
        samples = multivariate_normal.rvs(self.prior_mean, self.prior_cov, size=self.n)
        state = self._ParticleState(
            self._StateVectors(samples.T),
            log_weight=np.full(self.n, -np.log(self.n)),
            timestamp=self.start,
        )
        est = np.empty((steps, 2))
        for k in range(steps):
            dets = self.detections[k]
            state = self.predictor.predict(state, timestamp=dets[0].timestamp)
            for i, det in enumerate(dets):
                upd = self.updater_resample if i == len(dets) - 1 else self.updater
                state = upd.update(self._Hypothesis(state, det))
            est[k] = np.asarray(state.mean, float)[[0, 2], 0]
        return est

    def cleanup(self) -> None:
        # ParticlePredictor.predict keeps an LRU cache (128 entries) of whole particle sets;
        # release it between runs so N = 1e6 does not hold gigabytes (done outside the clock).
        self._ParticlePredictor.predict.__wrapped__.cache_clear()


# --------------------------------------------------------------------------------------------
# (3) particles (N. Chopin): X_0 of the state-space model is the state at time 1 (the prior
# pushed through the motion model), so Y_t is the measurement at time t + 1.


def _particles_model(scn: Scenario) -> object:
    import particles.distributions as dists
    from particles import state_space_models as ssm

    F, Q = cv_matrices(scn.dt, scn.q)
    sensors, sigma = scn.sensors, scn.sigma

    class WrappedBearings(dists.ProbDist):
        """Independent Gaussian bearings (one per sensor), the residual wrapped to [-pi, pi)."""

        dim = len(sensors)

        def __init__(self, x: Array) -> None:
            self.x = x

        def _pred(self) -> Array:
            d = self.x[..., None, :2] - sensors
            return np.arctan2(d[..., 1], d[..., 0])

        def logpdf(self, y: Array) -> Array:
            r = wrap(y - self._pred()) / sigma
            norm = len(sensors) * (np.log(sigma) + 0.5 * np.log(2 * np.pi))
            return -0.5 * np.sum(r * r, axis=-1) - norm

        def rvs(self, size: int | None = None) -> Array:
            return wrap(self._pred() + sigma * np.random.standard_normal(self._pred().shape))  # noqa: NPY002

    class BearingsOnlyCV(ssm.StateSpaceModel):
        def PX0(self):
            return dists.MvNormal(loc=F @ scn.prior_mean, cov=F @ scn.prior_cov @ F.T + Q)

        def PX(self, t, xp):
            return dists.MvNormal(loc=xp @ F.T, cov=Q)

        def PY(self, t, xp, x):
            return WrappedBearings(x)

    return BearingsOnlyCV()


class ParticlesPF:
    """``SMC(fk=Bootstrap(...), resampling='systematic', ESSrmin=1.0)`` with ``Moments``."""

    def __init__(self, scn: Scenario, n: int) -> None:
        self.model = _particles_model(scn)
        self.data = [scn.z[k] for k in range(scn.steps)]
        self.n = n

    def run(self, seed: int, steps: int) -> Array:
        import particles
        from particles import collectors
        from particles import state_space_models as ssm

        np.random.seed(seed)  # noqa: NPY002 - particles draws from NumPy's global generator
        fk = ssm.Bootstrap(ssm=self.model, data=self.data[:steps])
        alg = particles.SMC(
            fk=fk,
            N=self.n,
            resampling="systematic",
            ESSrmin=1.0,
            collect=[collectors.Moments()],
            verbose=False,
        )
        alg.run()
        return np.array([m["mean"][:2] for m in alg.summaries.moments])


# --------------------------------------------------------------------------------------------
# (4) plain NumPy: what a user writes in twenty lines.


class NumpyPF:
    """A vectorised bootstrap filter written directly in NumPy."""

    def __init__(self, scn: Scenario, n: int) -> None:
        self.scn, self.n = scn, n
        self.F, Q = cv_matrices(scn.dt, scn.q)
        self.LQ = np.linalg.cholesky(Q)
        self.L0 = np.linalg.cholesky(scn.prior_cov)

    def run(self, seed: int, steps: int) -> Array:
        rng = np.random.default_rng(seed)
        scn, n = self.scn, self.n
        x = scn.prior_mean + rng.standard_normal((n, 4)) @ self.L0.T
        est = np.empty((steps, 2))
        for k in range(steps):
            x = x @ self.F.T + rng.standard_normal((n, 4)) @ self.LQ.T
            logw = np.zeros(n)
            for i, (sx, sy) in enumerate(scn.sensors):
                r = wrap(scn.z[k, i] - np.arctan2(x[:, 1] - sy, x[:, 0] - sx)) / scn.sigma
                logw -= 0.5 * r * r
            w = np.exp(logw - logw.max())
            w /= w.sum()
            est[k] = w @ x[:, :2]
            u = (rng.random() + np.arange(n)) / n
            idx = np.minimum(np.searchsorted(np.cumsum(w), u), n - 1)
            x = x[idx]
        return est


RUNNERS: dict[str, Callable[[Scenario, int], object]] = {
    "fusetrack": FusetrackPF,
    "stonesoup": StoneSoupPF,
    "particles": ParticlesPF,
    "numpy": NumpyPF,
    "limit_reference": LimitReferencePF,
}


# --------------------------------------------------------------------------------------------


CLOCKS = {"wall": time.perf_counter, "cpu": time.process_time}
_clock_name = "wall"


def _timed_run(runner: object, seed: int, steps: int) -> tuple[float, Array, float, float]:
    """Seconds of the ``--clock`` clock, the estimates, wall and CPU seconds of one run."""
    gc.collect()
    with _results.Clock() as c:
        est = runner.run(seed, steps)  # type: ignore[attr-defined]
    if hasattr(runner, "cleanup"):
        runner.cleanup()  # type: ignore[attr-defined]
    return (c.cpu if _clock_name == "cpu" else c.wall), est, c.wall, c.cpu


def measure(
    scn: Scenario,
    n: int,
    args: argparse.Namespace,
    last: dict[str, tuple[int, float]],
) -> dict[str, dict[str, float | None]]:
    """Time every library of ``args.libs`` at ``n`` particles.

    Per library: median seconds per step (``None`` when skipped), the RMSE of its first timed
    run, the estimated seconds per step and the number of timed runs. ``last`` maps a library
    to ``(N, seconds per step)`` of its previous N and is updated. The timed runs go round-robin
    over the libraries (run 1 of each, then run 2 of each, ...), so that a change of load on
    the machine during the measurement hits every library alike.
    """
    res: dict[str, dict[str, float | None]] = {}
    runners: dict[str, object] = {}
    runs: dict[str, int] = {}
    warm_steps = min(WARMUP_STEPS, args.steps)
    for lib in args.libs:
        prev = last.get(lib)
        est_step = prev[1] * n / prev[0] if prev is not None else None
        if est_step is None or est_step <= args.budget:
            runner = RUNNERS[lib](scn, n)
            # Warm-up: JIT compilation, caches, page faults. A library's first warm-up may
            # include compile time, so when it looks over budget it gets a second one.
            t_warm = _timed_run(runner, args.seed + 10_000, warm_steps)[0]
            if prev is None and t_warm / warm_steps > args.budget:
                t_warm = _timed_run(runner, args.seed + 10_001, warm_steps)[0]
            est_step = t_warm / warm_steps
            if est_step <= args.budget:
                runners[lib] = runner
                # Fewer timed runs when they would take longer than --max-seconds together.
                runs[lib] = max(
                    1, min(args.repeats, int(args.max_seconds // (est_step * args.steps)))
                )
            else:
                del runner
        res[lib] = {
            "seconds_per_step": None,
            "rmse": None,
            "estimate": est_step,
            "runs": 0,
            "wall": None,
            "cpu": None,
            "rmse_runs": [],
        }
        last[lib] = (n, float(est_step))  # a skipped library stays skipped at larger N
    times: dict[str, list[tuple[float, float, float]]] = {lib: [] for lib in runners}
    for r in range(max(runs.values(), default=0)):
        for lib, runner in runners.items():
            if r >= runs[lib]:
                continue
            elapsed, est, wall, cpu = _timed_run(runner, args.seed + r, args.steps)
            times[lib].append((elapsed / args.steps, wall / args.steps, cpu / args.steps))
            rmse = position_rmse(est, scn.truth[1 : args.steps + 1, :2])
            res[lib]["rmse_runs"].append(rmse)  # type: ignore[union-attr]
            if r == 0:
                res[lib]["rmse"] = rmse
    for lib in runners:
        t, wall, cpu = (statistics.median(col) for col in zip(*times[lib]))
        res[lib].update(seconds_per_step=t, runs=runs[lib], wall=wall, cpu=cpu)
        last[lib] = (n, t)
    runners.clear()
    gc.collect()
    return res


def agreement(res: dict[str, dict], reference: str = "fusetrack") -> dict[str, dict]:
    """Per library: its mean RMSE over the timed runs against ``reference``'s
    (``_results.agree_monte_carlo``); the reference itself and skipped libraries are left out."""
    ref = res.get(reference)
    if ref is None or not ref["rmse_runs"]:
        return {}
    m_ref, se_ref = _results.mean_se(ref["rmse_runs"])
    n_ref = len(ref["rmse_runs"])
    out = {}
    for lib, r in res.items():
        if lib != reference and r["rmse_runs"]:
            m, se = _results.mean_se(r["rmse_runs"])
            n = len(r["rmse_runs"])
            out[lib] = _results.agree_monte_carlo(m, se, m_ref, se_ref, n, n_ref)
    return out


def result_row(n: int, sensors: int, libs: list[str], res: dict[str, dict]) -> dict:
    """One JSON row: the ``--json`` line (N, seconds_per_step, rmse) and the rest (both clocks,
    RMSE of every run, agreement with fusetrack, speed-ups wall and cpu where they agree)."""
    agree = agreement(res)
    ft = res.get("fusetrack", {})
    speedup = {
        lib: None
        if agree.get(lib, {}).get("agree") is False
        else {
            "wall": _results.ratio(res[lib]["wall"], ft.get("wall")),
            "cpu": _results.ratio(res[lib]["cpu"], ft.get("cpu")),
        }
        for lib in libs
        if lib != "fusetrack" and "fusetrack" in res
    }
    return {
        "N": n,
        "seconds_per_step": {lib: res[lib]["seconds_per_step"] for lib in libs},
        "rmse": {lib: res[lib]["rmse"] for lib in libs},
        "sensors": sensors,
        "clock": _clock_name,
        "wall_seconds_per_step": {lib: res[lib]["wall"] for lib in libs},
        "cpu_seconds_per_step": {lib: res[lib]["cpu"] for lib in libs},
        "runs": {lib: res[lib]["runs"] for lib in libs},
        "rmse_runs": {lib: res[lib]["rmse_runs"] for lib in libs},
        "agreement": agree,
        "agree": _results.all_agree([a["agree"] for a in agree.values()]),
        "speedup_over": speedup,
        "load": os.getloadavg()[0],
    }


def _fmt_time(t: float | None, est: float | None) -> str:
    if t is None:
        return f"skipped (est. {est:.3g}s)" if est is not None else "failed"
    return f"{t * 1e3:.3f} ms" if t < 1 else f"{t:.3f} s"


def _profile(lib: str, scn: Scenario, n: int, args: argparse.Namespace) -> None:
    import cProfile
    import pstats

    runner = RUNNERS[lib](scn, n)
    _timed_run(runner, args.seed + 10_000, min(WARMUP_STEPS, args.steps))
    prof = cProfile.Profile(time.process_time if args.clock == "cpu" else time.perf_counter)
    prof.enable()
    runner.run(args.seed, args.steps)  # type: ignore[attr-defined]
    prof.disable()
    print(f"\n{lib}, N = {n:,}, {args.steps} steps")
    pstats.Stats(prof, stream=sys.stdout).sort_stats("tottime").print_stats(25)


def _versions(libs: list[str]) -> str:
    import importlib.metadata as md

    names = {"fusetrack": "fusetrack", "stonesoup": "stonesoup", "particles": "particles"}
    parts = [f"python {sys.version.split()[0]}", f"numpy {np.__version__}"]
    for lib in ["numba", *libs]:
        dist = names.get(lib, lib if lib == "numba" else None)
        if dist is not None:
            try:
                parts.append(f"{dist} {md.version(dist)}")
            except md.PackageNotFoundError:
                parts.append(f"{dist} (not installed)")
    return ", ".join(parts)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawTextHelpFormatter
    )
    ap.add_argument(
        "--N",
        type=int,
        nargs="+",
        default=[1000, 10_000, 100_000, 1_000_000],
        help="particle counts",
    )
    ap.add_argument(
        "--libs", nargs="+", default=list(LIBS), choices=LIBS, help="implementations to time"
    )
    ap.add_argument(
        "--repeats", type=int, default=3, help="timed runs per (library, N); the median is reported"
    )
    ap.add_argument("--steps", type=int, default=100, help="time steps per run (default 100)")
    ap.add_argument(
        "--budget",
        type=float,
        default=1.0,
        help="skip a library whose estimated seconds per step exceed this (default 1.0)",
    )
    ap.add_argument(
        "--max-seconds",
        type=float,
        default=60.0,
        help="time the timed runs of one (library, N) may take together; fewer repeats\n"
        "(at least one) when they would take longer (default 60)",
    )
    ap.add_argument(
        "--seed",
        type=int,
        default=1,
        help="seed of the filters' random draws (the scenario is fixed)",
    )
    ap.add_argument("--json", action="store_true", help="one JSON object per N instead of a table")
    ap.add_argument(
        "--sensors",
        type=int,
        nargs="+",
        default=None,
        help="the sensors sweep: S bearing sensors on a circle instead of the three fixed ones",
    )
    _results.add_arguments(ap)
    ap.add_argument(
        "--clock",
        choices=sorted(CLOCKS),
        default="wall",
        help="wall: time.perf_counter (default); cpu: time.process_time, the CPU time of\n"
        "all threads of this process (less sensitive to other processes on a busy machine)",
    )
    ap.add_argument(
        "--profile",
        choices=LIBS,
        help="instead of timing: cProfile one run of this library at each N (after a warm-up)\n"
        "and print the 25 functions with the most internal time",
    )
    args = ap.parse_args(argv)
    if args.steps < 1 or args.repeats < 1:
        ap.error("--steps and --repeats must be >= 1")
    if any(n < 1 for n in args.N) or (args.sensors and min(args.sensors) < 1):
        ap.error("--N and --sensors values must be >= 1")
    if args.threads is not None and args.threads < 1:
        ap.error("--threads must be >= 1")
    global _clock_name
    _clock_name = args.clock
    run = _results.Run(argv, __file__)
    with _results.limit_threads(args.threads) as threads:
        run.threads = threads
        rows = _measure_all(args)
    if not args.json:
        print(f"\nload average at end {os.getloadavg()[0]:.2f}")
    if rows is not None:
        run.save(_results.out_path(args, __file__), rows)
    return 0


def _measure_all(args: argparse.Namespace) -> list[dict] | None:
    """Every (sensors, N) of the command line: table or JSON lines; the rows (``None`` after
    ``--profile``)."""
    # The first --steps steps of the standard 100-step scenario (the same truth for any --steps).
    base = make_scenario(steps=max(args.steps, 100))
    if not args.json:
        print(
            "bootstrap PF, 4-D CV, bearing sensors, systematic resampling every step, "
            f"{args.steps} steps; median of up to {args.repeats} runs; "
            f"budget {args.budget}s/step; {args.clock} clock\n{_versions(args.libs)}; {os.cpu_count()} cores; "
            f"threads {args.threads or 'default (BLAS 1)'}; "
            f"load average at start {os.getloadavg()[0]:.2f}"
        )
    counts = args.sensors or [None]
    if args.profile:
        for s_count in counts:
            scn = base if s_count is None else with_sensors(base, s_count)
            for n in args.N:
                _profile(args.profile, scn, n, args)
        return None
    rows = []
    for s_count in counts:
        scn = base if s_count is None else with_sensors(base, s_count)
        last: dict[str, tuple[int, float]] = {}  # lib -> (N, s per step) of the last measured N
        for n in args.N:
            res = measure(scn, n, args, last)
            rows.append(result_row(n, len(scn.sensors), args.libs, res))
            if args.json:
                print(json.dumps(rows[-1]), flush=True)
            else:
                if s_count is not None:
                    print(f"\n{s_count} sensors", end="")
                _print_table(n, args.libs, res, rows[-1]["agreement"])
    return rows


def _print_table(
    n: int, libs: list[str], res: dict[str, dict[str, float | None]], agree: dict[str, dict]
) -> None:
    ft = res.get("fusetrack", {})
    w = max(10, *(len(lib) for lib in libs))
    print(f"\nN = {n:,}")
    print(
        f"  {'library':<{w}} {'time / step':>24} {'cpu / step':>11} {'runs':>5} {'RMSE (m)':>10} "
        f"{'fusetrack speed-up':>19} {'(cpu)':>7}"
    )
    for lib in libs:
        r = res[lib]
        t, rmse, est = r["seconds_per_step"], r["rmse"], r["estimate"]
        ratio = cpu_ratio = ""
        if agree.get(lib, {}).get("agree") is False:
            ratio = "disagrees"
        elif lib != "fusetrack" and ft.get("seconds_per_step") and t is not None:
            ratio = f"{t / ft['seconds_per_step']:.1f}x"  # type: ignore[operator]
            cpu_ratio = f"{r['cpu'] / ft['cpu']:.1f}x" if ft.get("cpu") else ""  # type: ignore[operator]
        rm = "" if rmse is None else f"{rmse:.3f}"
        runs = "" if t is None else str(r["runs"])
        cpu = "" if r["cpu"] is None else f"{r['cpu'] * 1e3:.3f} ms"  # type: ignore[operator]
        print(
            f"  {lib:<{w}} {_fmt_time(t, est):>24} {cpu:>11} {runs:>5} {rm:>10} {ratio:>19} "
            f"{cpu_ratio:>7}",
            flush=True,
        )


if __name__ == "__main__":
    raise SystemExit(main())
