"""Batched Monte Carlo: R independent particle-filter runs as one ``(R, N, d)`` array.

The filter is ``pf_bearing.py``'s (fusetrack ``BootstrapFilter``, 2-D constant velocity, three
bearing sensors, systematic resampling every step); each of the ``--runs`` runs has its own
simulated truth and bearings (``_scenario.py``'s model, one seed per run) and its own
``numpy.random.Generator``. Two ways to do the study:

``separate``
    ``R`` ordinary runs one after another: ``initialize(prior, rng_r)``, then per step
    ``predict``, ``update`` (values ``(1,)``), ``mean``;
``batched``
    one filter call per step for all runs: ``initialize(prior, [rng_1..rng_R], (R,))``, measurement
    values ``(R, 1)``, ``mean`` ``(R, 4)``. Passing the list of generators makes run ``r`` draw
    exactly what the separate run ``r`` draws, so the estimates must be bit-identical (checked:
    ``bit_identical`` compares every run's estimate at every step and its final particles).

    python benchmarks/batched_runs.py [--runs 200] [--N 1000] [--steps 20] [--repeats 3]
        [--threads T] [--json] [--save | --out PATH]

Timing: ``time.perf_counter`` (and ``time.process_time``) around the whole study, divided by
``steps``; median over ``--repeats``, round-robin (separate, batched, separate, ...). BLAS is
limited to one thread (``--threads T``: BLAS/OpenMP and Numba's threaded loops get T threads,
``_results.py``); Numba compile time is excluded by a warm-up. The two ways agree when they are
bit-identical (``"agree"``); otherwise no speed-up is reported.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results
from _scenario import (
    DT,
    PRIOR_STD,
    Q_PSD,
    SENSOR_IDS,
    SENSORS,
    SIGMA_BEARING,
    X0_TRUE,
    Array,
    cv_matrices,
    wrap,
)


def simulate(runs: int, steps: int, seed: int = 2024) -> tuple[Array, Array, Array]:
    """Truth ``(R, steps, 4)``, bearings ``(R, steps, 3)``, prior means ``(R, 4)``."""
    F, Q = cv_matrices(DT, Q_PSD)
    LQ = np.linalg.cholesky(Q)
    truth = np.empty((runs, steps, 4))
    z = np.empty((runs, steps, len(SENSORS)))
    prior = np.empty((runs, 4))
    for r in range(runs):
        rng = np.random.default_rng([seed, r])
        x = X0_TRUE.copy()
        prior[r] = X0_TRUE + PRIOR_STD * rng.standard_normal(4)
        for k in range(steps):
            x = F @ x + LQ @ rng.standard_normal(4)
            truth[r, k] = x
            d = x[None, :2] - SENSORS
            z[r, k] = wrap(
                np.arctan2(d[:, 1], d[:, 0]) + SIGMA_BEARING * rng.standard_normal(len(SENSORS))
            )
    return truth, z, prior


class Study:
    def __init__(self, runs: int, n: int, steps: int) -> None:
        from fusetrack.core import Gaussian, Measurement
        from fusetrack.filters import BootstrapFilter
        from fusetrack.motion import ConstantVelocity
        from fusetrack.sensors import Bearing

        self.runs, self.n, self.steps = runs, n, steps
        self.truth, z, prior = simulate(runs, steps)
        sensors = [
            Bearing(sensor_id=sid, position=pos, sigma=SIGMA_BEARING)
            for sid, pos in zip(SENSOR_IDS, SENSORS)
        ]
        self.filt = BootstrapFilter(
            ConstantVelocity(ndim=2, q=Q_PSD), sensors, n_particles=n, resampler="systematic"
        )
        cov = np.diag(PRIOR_STD**2)
        self.priors = [Gaussian(prior[r], cov) for r in range(runs)]
        self.batch_prior = Gaussian(prior, np.broadcast_to(cov, (runs, 4, 4)))
        self.separate_meas = [
            [
                [
                    Measurement((k + 1) * DT, sid, z[r, k, i : i + 1])
                    for i, sid in enumerate(SENSOR_IDS)
                ]
                for k in range(steps)
            ]
            for r in range(runs)
        ]
        self.batch_meas = [
            [Measurement((k + 1) * DT, sid, z[:, k, i : i + 1]) for i, sid in enumerate(SENSOR_IDS)]
            for k in range(steps)
        ]

    def separate(self, seed: int, runs: int | None = None) -> tuple[Array, Array]:
        filt, steps = self.filt, self.steps
        runs = self.runs if runs is None else runs
        est = np.empty((runs, steps, 4))
        final = np.empty((runs, self.n, 4))
        for r in range(runs):
            rng = np.random.default_rng([seed, r])
            p = filt.initialize(self.priors[r], rng)
            for k in range(steps):
                p = filt.update(filt.predict(p, DT, rng), self.separate_meas[r][k], rng)
                est[r, k] = filt.mean(p)
            final[r] = p.states
        return est, final

    def batched(self, seed: int) -> tuple[Array, Array]:
        filt, steps = self.filt, self.steps
        gens = [np.random.default_rng([seed, r]) for r in range(self.runs)]
        p = filt.initialize(self.batch_prior, gens, batch_shape=(self.runs,))
        est = np.empty((self.runs, steps, 4))
        for k in range(steps):
            p = filt.update(filt.predict(p, DT, gens), self.batch_meas[k], gens)
            est[:, k] = filt.mean(p)
        return est, p.states


def measure(study: Study, repeats: int, seed: int = 1) -> dict[str, object]:
    study.separate(seed + 999, runs=min(2, study.runs))  # warm-up: Numba dispatch, caches
    study.batched(seed + 999)
    wall: dict[str, list[float]] = {"separate": [], "batched": []}
    cpu: dict[str, list[float]] = {"separate": [], "batched": []}
    identical = True
    for rep in range(repeats):
        outs = {}
        for name in ("separate", "batched"):
            gc.collect()
            t0, c0 = time.perf_counter(), time.process_time()
            outs[name] = getattr(study, name)(seed + rep)
            wall[name].append((time.perf_counter() - t0) / study.steps)
            cpu[name].append((time.process_time() - c0) / study.steps)
        (e1, f1), (e2, f2) = outs["separate"], outs["batched"]
        identical &= bool(np.array_equal(e1, e2) and np.array_equal(f1, f2))
    sec = {k: statistics.median(v) for k, v in wall.items()}
    csec = {k: statistics.median(v) for k, v in cpu.items()}
    est = outs["batched"][0]
    rmse = float(np.sqrt(np.mean(np.sum((est[..., :2] - study.truth[..., :2]) ** 2, -1))))
    return {
        "runs": study.runs,
        "N": study.n,
        "seconds_per_step": sec,
        "cpu_seconds_per_step": csec,
        "speedup": sec["separate"] / sec["batched"] if identical else None,
        "cpu_speedup": csec["separate"] / csec["batched"] if identical else None,
        "bit_identical": identical,
        "agree": identical,
        "rmse": rmse,
        "load": os.getloadavg()[0],
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, nargs="+", default=[200])
    ap.add_argument("--N", type=int, default=1000)
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json", action="store_true", help="one JSON object per --runs value")
    _results.add_arguments(ap)
    args = ap.parse_args(argv)
    if args.N < 1 or args.steps < 1 or args.repeats < 1 or min(args.runs) < 1:
        ap.error("--runs, --N, --steps and --repeats must be >= 1")
    if args.threads is not None and args.threads < 1:
        ap.error("--threads must be >= 1")
    run, rows = _results.Run(argv, __file__), []
    with _results.limit_threads(args.threads) as threads:
        run.threads = threads
        for runs in args.runs:
            res = measure(Study(runs, args.N, args.steps), args.repeats)
            rows.append(res)
            if args.json:
                print(json.dumps(res), flush=True)
                continue
            s, c = res["seconds_per_step"], res["cpu_seconds_per_step"]
            ratio = (
                f"speed-up {res['speedup']:.1f}x wall, {res['cpu_speedup']:.1f}x cpu"
                if res["agree"]
                else "NOT bit-identical: no speed-up"
            )
            print(
                f"{runs} runs x {args.N} particles, {args.steps} steps: separate "
                f"{s['separate'] * 1e3:.1f} ms/step (cpu {c['separate'] * 1e3:.1f}), batched "  # type: ignore[index]
                f"{s['batched'] * 1e3:.1f} ms/step (cpu {c['batched'] * 1e3:.1f}); {ratio}; "  # type: ignore[index]
                f"bit-identical {res['bit_identical']}; RMSE {res['rmse']:.2f} m; "
                f"load {res['load']:.2f}",
                flush=True,
            )
    run.save(_results.out_path(args, __file__), rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
