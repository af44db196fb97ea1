"""Speed of particle marginal Metropolis-Hastings in fusetrack, ``particles`` and a hand-written
whole-run Numba bootstrap filter (the limit reference), on the same model, data and proposal.

The model (all three): ``x_0 ~ N(0, q / (1 - rho^2))``, ``x_t = rho x_{t-1} + N(0, q)``,
``y_t = x_t + N(0, r)``, ``rho = 0.9`` known, ``T = 100`` observations simulated once
(seed 0, ``q = 1``, ``r = 0.5``); parameters ``theta = (log q, log r)`` with independent
``N(0, 2^2)`` priors; a bootstrap filter with ``N = 1000`` particles and systematic resampling
whenever ``ESS < N`` (every step in practice) estimates the likelihood; random-walk proposal
``theta' = theta + N(0, s^2 I)``, ``s = 0.15``, not adapted; start ``theta = (0, 0)``.

* ``fusetrack``: :func:`fusetrack.estimation.pmmh` with a ``model(theta)`` that builds a
  :class:`~fusetrack.filters.BootstrapFilter` (``LinearGaussianMotion``,
  ``LinearGaussianSensor``) per proposal: the whole-run kernel path;
* ``particles``: ``particles.mcmc.PMMH`` (``adaptive=False``, ``rw_cov = s^2 I``,
  ``resampling="systematic"``, ``ESSrmin=1``) on the same model as a ``StateSpaceModel``;
* ``limit_reference``: the filter hand-written for this one model as one Numba function (scalar
  state, NumPy's generator passed to Numba, systematic merge inline) in a minimal Python MH
  loop: about as fast as this PMMH can be written.

``particles`` 0.3 calls ``np.float`` (removed in NumPy 2) in its PMMH: the script restores the
alias (``np.float = float``) before importing it, and its ``compute_post`` stores a
1-element array into an array element, which NumPy 2 refuses: the script's subclass takes the
element (the same arithmetic).

    python benchmarks/pmmh.py [--iterations 1000] [--libs fusetrack particles limit_reference]
        [--threads N] [--save | --out PATH] [--json]

Reported per library: milliseconds per PMMH iteration (one likelihood estimate each) in wall
time (``time.perf_counter``) and CPU time of all threads (``time.process_time``), the ratio of
the CPU time to the limit reference's, the acceptance rate, and the posterior means of ``q`` and
``r`` after a 20 % burn-in with their Monte Carlo errors (batch means, 10 batches). Each
library's posterior means of ``log q`` and ``log r`` are checked against the limit reference's
(``_results.agree_monte_carlo``: within the t quantile of the combined errors;
``agreement_with_limit_reference``); fusetrack and the limit reference draw the same numbers in
the same order and give the same chain. Threads (``_results.py``): ``--threads N`` for every
library (BLAS and Numba), default BLAS on one thread; every implementation here runs its one
chain serially either way. JIT compilation is excluded (a 5-iteration warm-up run first).
``--save`` writes ``{metadata, results}`` to ``benchmarks/results/pmmh.json`` (date, machine,
load, versions, threads, command, git); ``--json`` prints one object per library.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, ClassVar

import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results

RHO, Q_TRUE, R_TRUE, T_STEPS, N_PARTICLES = 0.9, 1.0, 0.5, 100, 1000
PRIOR_SD, STEP, BURN_FRACTION, BATCHES = 2.0, 0.15, 0.2, 10
LIBS = ("fusetrack", "particles", "limit_reference")


def simulate(seed: int = 0) -> np.ndarray:
    """``y_1:T`` of the model at the true ``q``, ``r``."""
    rng = np.random.default_rng(seed)
    y = np.empty(T_STEPS)
    x = rng.normal() * math.sqrt(Q_TRUE / (1 - RHO**2))
    for t in range(T_STEPS):
        if t:
            x = RHO * x + math.sqrt(Q_TRUE) * rng.normal()
        y[t] = x + math.sqrt(R_TRUE) * rng.normal()
    return y


def log_prior(theta: np.ndarray) -> float:
    return float(-0.5 * np.sum((theta / PRIOR_SD) ** 2))


# --------------------------------------------------------------------------------------------
# (1) fusetrack


def run_fusetrack(y: np.ndarray, iterations: int, seed: int) -> dict[str, Any]:
    from fusetrack.core import Gaussian, Measurement
    from fusetrack.estimation import pmmh, prepare_series
    from fusetrack.filters import BootstrapFilter
    from fusetrack.motion import LinearGaussianMotion
    from fusetrack.sensors import LinearGaussianSensor

    series = prepare_series([Measurement(float(t), "y", [v]) for t, v in enumerate(y)])

    def model(theta: np.ndarray) -> tuple[Any, Any]:
        q, r = np.exp(theta)
        motion = LinearGaussianMotion(F=[[RHO]], Q=[[q]])
        sensor = LinearGaussianSensor("y", H=[[1.0]], R=[[r]])
        filt = BootstrapFilter(motion, [sensor], n_particles=N_PARTICLES)
        return filt, Gaussian(np.zeros(1), np.array([[q / (1 - RHO**2)]]))

    def run(n: int) -> tuple[np.ndarray, float]:
        out = pmmh(
            model, log_prior, [0.0, 0.0], series, n_iterations=n, scale=STEP,
            rng=np.random.default_rng(seed),
        )  # fmt: skip
        return out.chain[:, 0, :], float(out.accepted.mean())

    return _timed(run, iterations)


# --------------------------------------------------------------------------------------------
# (2) particles


def run_particles(y: np.ndarray, iterations: int, seed: int) -> dict[str, Any]:
    if not hasattr(np, "float"):  # particles 0.3 views theta with np.float, gone in NumPy 2
        setattr(np, "float", float)  # noqa: B010
    from particles import distributions as dists
    from particles import mcmc
    from particles import smc_samplers as ssp
    from particles import state_space_models as ssms

    class PMMH(mcmc.PMMH):  # type: ignore[misc]
        """``mcmc.PMMH`` with its ``compute_post`` taking the prior's one value as a scalar
        (NumPy 2 refuses to store a 1-element array into an element)."""

        def compute_post(self) -> None:
            self.prop.lpost[0] = self.prior.logpdf(self.prop.theta)[0]
            if np.isfinite(self.prop.lpost[0]):
                pf = self.alg_instance(ssp.rec_to_dict(self.prop.theta[0]))
                pf.run()
                self.prop.lpost[0] += pf.logLt

    class AR1(ssms.StateSpaceModel):  # type: ignore[misc]
        default_params: ClassVar[dict[str, float]] = {"logq": 0.0, "logr": 0.0}

        def PX0(self) -> Any:
            return dists.Normal(loc=0.0, scale=math.sqrt(math.exp(self.logq) / (1 - RHO**2)))

        def PX(self, t: int, xp: np.ndarray) -> Any:
            return dists.Normal(loc=RHO * xp, scale=math.sqrt(math.exp(self.logq)))

        def PY(self, t: int, xp: Any, x: np.ndarray) -> Any:
            return dists.Normal(loc=x, scale=math.sqrt(math.exp(self.logr)))

    prior = dists.StructDist(
        {"logq": dists.Normal(0.0, PRIOR_SD), "logr": dists.Normal(0.0, PRIOR_SD)}
    )
    theta0 = np.zeros(1, dtype=[("logq", float), ("logr", float)])

    def run(n: int) -> tuple[np.ndarray, float]:
        np.random.seed(seed)  # noqa: NPY002 - particles draws from NumPy's global generator
        alg = PMMH(
            ssm_cls=AR1, prior=prior, data=y, Nx=N_PARTICLES, niter=n + 1, theta0=theta0,
            adaptive=False, rw_cov=STEP**2 * np.eye(2),
            smc_options={"resampling": "systematic", "ESSrmin": 1.0},
        )  # fmt: skip
        alg.run()
        th = alg.chain.theta
        return np.stack([th["logq"], th["logr"]], axis=1), alg.nacc / n

    return _timed(run, iterations)


# --------------------------------------------------------------------------------------------
# (3) the limit reference


@numba.njit(cache=True, error_model="numpy")
def limit_log_likelihood(rng: Any, y: np.ndarray, q: float, r: float, n: int) -> float:
    """The bootstrap filter's log-likelihood estimate for this model, by hand (scalar state,
    systematic resampling every step by the inline merge, one pass per step for propagation
    and weights, one for the exponentials)."""
    x = np.empty(n)
    xn = np.empty(n)
    v = np.empty(n)
    w = np.empty(n)
    sq = math.sqrt(q)
    s0 = math.sqrt(q / (1 - RHO**2))
    half_inv_r = 0.5 / r
    const = -0.5 * math.log(2 * math.pi * r) - math.log(n)
    total = 0.0
    w_sum = 1.0
    for t in range(y.shape[0]):
        yt = y[t]
        top = -np.inf
        if t == 0:
            for i in range(n):
                xi = s0 * rng.standard_normal()
                x[i] = xi
                v[i] = -half_inv_r * (yt - xi) ** 2
                top = max(top, v[i])
        else:
            u = rng.random()
            scale = n / w_sum
            cum = 0.0
            k = 0
            for j in range(n):  # systematic merge: copies of j while (k + u) < cum * n / sum
                cum += w[j] * scale
                while k < n and k + u < cum:
                    xi = RHO * x[j] + sq * rng.standard_normal()
                    xn[k] = xi
                    vk = -half_inv_r * (yt - xi) ** 2
                    v[k] = vk
                    top = max(top, vk)
                    k += 1
            while k < n:  # rounding left the last slots: copies of the last particle
                xi = RHO * x[n - 1] + sq * rng.standard_normal()
                xn[k] = xi
                v[k] = -half_inv_r * (yt - xi) ** 2
                top = max(top, v[k])
                k += 1
            x, xn = xn, x
        w_sum = 0.0
        for i in range(n):
            wi = math.exp(v[i] - top)
            w[i] = wi
            w_sum += wi
        total += const + top + math.log(w_sum)
    return total


def run_limit_reference(y: np.ndarray, iterations: int, seed: int) -> dict[str, Any]:
    def run(n: int) -> tuple[np.ndarray, float]:
        rng = np.random.default_rng(seed)
        pf_rng = rng.spawn(1)[0]
        chain = np.empty((n + 1, 2))
        chain[0] = 0.0
        lpost = log_prior(chain[0]) + limit_log_likelihood(
            pf_rng, y, math.exp(chain[0, 0]), math.exp(chain[0, 1]), N_PARTICLES
        )
        acc = 0
        for it in range(n):
            prop = chain[it] + STEP * rng.standard_normal(2)
            lp = log_prior(prop) + limit_log_likelihood(
                pf_rng, y, math.exp(prop[0]), math.exp(prop[1]), N_PARTICLES
            )
            if math.log(rng.random()) < lp - lpost:
                chain[it + 1], lpost = prop, lp
                acc += 1
            else:
                chain[it + 1] = chain[it]
        return chain, acc / n

    return _timed(run, iterations)


# --------------------------------------------------------------------------------------------
# timing and report


def _timed(run: Callable[[int], tuple[np.ndarray, float]], iterations: int) -> dict[str, Any]:
    run(5)  # JIT compile, imports
    w0, c0 = time.perf_counter(), time.process_time()
    chain, acc = run(iterations)
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    kept = chain[1 + int(BURN_FRACTION * iterations) :]
    q, r = np.exp(kept).mean(axis=0)
    k = kept.shape[0] // BATCHES  # batch means: the Monte Carlo error of a correlated chain
    means = kept[: BATCHES * k].reshape(BATCHES, k, 2).mean(axis=1)
    se = means.std(axis=0, ddof=1) / math.sqrt(BATCHES)
    return {
        "ms_per_iteration_wall": 1e3 * wall / iterations,
        "ms_per_iteration_cpu": 1e3 * cpu / iterations,
        "acceptance_rate": acc,
        "posterior_mean_q": float(q),
        "posterior_mean_r": float(r),
        "posterior_mean_log_q": float(kept[:, 0].mean()),
        "posterior_mean_log_r": float(kept[:, 1].mean()),
        "mc_se_log_q": float(se[0]),
        "mc_se_log_r": float(se[1]),
    }


def agreement(a: dict[str, Any], b: dict[str, Any]) -> dict[str, Any]:
    """Posterior means of ``log q`` and ``log r`` against another library's, each by
    ``_results.agree_monte_carlo`` on the batch-means errors (10 batches each)."""
    out: dict[str, Any] = {}
    for p in ("q", "r"):
        out[f"log_{p}"] = _results.agree_monte_carlo(
            a[f"posterior_mean_log_{p}"], a[f"mc_se_log_{p}"],
            b[f"posterior_mean_log_{p}"], b[f"mc_se_log_{p}"], BATCHES, BATCHES,
        )  # fmt: skip
    out["agree"] = _results.all_agree([out["log_q"]["agree"], out["log_r"]["agree"]])
    return out


RUNNERS = {
    "fusetrack": run_fusetrack,
    "particles": run_particles,
    "limit_reference": run_limit_reference,
}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawTextHelpFormatter
    )
    ap.add_argument("--iterations", type=int, default=1000, help="PMMH iterations (default 1000)")
    ap.add_argument("--libs", nargs="+", choices=LIBS, default=list(LIBS))
    ap.add_argument("--seed", type=int, default=1, help="seed of the chains (data: seed 0)")
    ap.add_argument("--json", action="store_true", help="one JSON object per library")
    _results.add_arguments(ap)
    args = ap.parse_args(argv)
    run = _results.Run(argv, __file__)
    y = simulate(0)
    setup = {"T": T_STEPS, "N": N_PARTICLES, "iterations": args.iterations, "step": STEP}
    results: dict[str, dict[str, Any]] = {}
    with _results.limit_threads(args.threads) as threads:
        run.threads = threads
        for lib in args.libs:
            results[lib] = {"library": lib, **setup, **RUNNERS[lib](y, args.iterations, args.seed)}
    ref = results.get("limit_reference")
    for res in results.values():
        res["agreement_with_limit_reference"] = None if ref is None else agreement(res, ref)
        res["cpu_ratio_to_limit_reference"] = _results.ratio(
            res["ms_per_iteration_cpu"], None if ref is None else ref["ms_per_iteration_cpu"]
        )
    rows = list(results.values())
    run.save(_results.out_path(args, __file__), rows)
    if args.json:
        for res in rows:
            print(json.dumps(res))
        return 0
    print(f"PMMH, T={T_STEPS}, N={N_PARTICLES}, {args.iterations} iterations, load "
          f"{os.getloadavg()[0]:.1f}, threads {args.threads or 'BLAS 1'}")  # fmt: skip
    print(f"{'library':<16}{'ms/it wall':>11}{'ms/it cpu':>11}{'x ref cpu':>10}{'accept':>8}"
          f"{'E[q]':>8}{'E[r]':>8}  posterior agrees with the reference")  # fmt: skip
    for lib, res in results.items():
        ratio = res["cpu_ratio_to_limit_reference"] or math.nan
        agree = (res["agreement_with_limit_reference"] or {}).get("agree")
        print(
            f"{lib:<16}{res['ms_per_iteration_wall']:>11.3f}{res['ms_per_iteration_cpu']:>11.3f}"
            f"{ratio:>10.2f}{res['acceptance_rate']:>8.3f}{res['posterior_mean_q']:>8.3f}"
            f"{res['posterior_mean_r']:>8.3f}  {agree}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
