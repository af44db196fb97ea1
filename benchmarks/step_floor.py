"""The floor of one step of ``pf_bearing.py``'s filter on this machine: each phase alone.

Issue 3 asks fusetrack to be 30x faster than Stone Soup at N = 1e5 (Stone Soup about 107 ms per
step on an idle machine, so 3.6 ms per step, 36 ns per particle). This script measures, at that
N, what each unavoidable phase of a bootstrap step costs when it is written as one tight Numba
loop and run alone (no Python between phases, no other phase's memory traffic), serial and on
two threads:

``normals``
    the 4 process-noise normals per particle from NumPy's generator (Numba's ziggurat on the
    bit generator's C functions, the same numbers as ``Generator.standard_normal``); serial: one
    generator; threaded: 4 child generators, each filling its part (as fusetrack);
``propagate``
    ``x' = F x + G eps`` (4-D constant velocity; ``eps`` given);
``bearings``
    3 bearing residuals and their Gaussian log-likelihoods summed per particle, on contiguous
    position columns (``fused._add_bearing``: the branch-free ``atan`` of ``fused._abs_angle``);
``normalise``
    the maximum, ``exp`` (NumPy's SIMD ``exp``; Numba's libm ``exp`` shown beside), the sum,
    the normalised weights and the weighted mean;
``resample``
    systematic ancestors (``resampling.systematic_row``) and the gather ``x[a]``.

Each figure is the minimum over ``--repeats`` timed calls (the least disturbed by other
processes), in wall and CPU seconds; the sum of the phases is the floor of a step built from
separate passes. ``--stonesoup`` adds whole runs of Stone Soup (``pf_bearing.py``'s runner)
beside fusetrack's and the limit reference's (minimum of a few runs of ``--steps`` steps, the
prior draw included). BLAS runs on one thread for everyone. ``--threads T``: the threaded
column and the threaded whole runs use T Numba threads instead of 2, and BLAS (Stone Soup) gets
T threads too (``_results.py``). ``--json`` prints one object; ``--save`` / ``--out`` write it
with the run's metadata. The whole runs are ``pf_bearing.py``'s filters, whose RMSE agreement
that script checks; this one only times them.

    python benchmarks/step_floor.py [--N 100000] [--repeats 30] [--stonesoup-ms 107]
        [--threads T] [--json] [--save | --out PATH]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results
from _scenario import DT, Q_PSD, SENSORS, SIGMA_BEARING, cv_matrices
from fusetrack.core.resampling import systematic_row
from fusetrack.filters import fused, rng_handles
from fusetrack.filters.fused import _add_bearing
from fusetrack.filters.rng_handles import _bitgen, random_standard_normal

BLOCK = 4096


def _normals_py(handles, out):  # pragma: no cover - jit
    """Part ``s`` of the particles (rows of ``out`` ``(N, 4)``) from generator ``s``."""
    n = out.shape[0]
    parts = handles.shape[0]
    per = (n + parts - 1) // parts
    for s in numba.prange(parts):
        bg = _bitgen(handles[s])
        for i in range(s * per, min(n, (s + 1) * per)):
            for k in range(4):
                out[i, k] = random_standard_normal(bg)


def _propagate_py(x, F, G, eps, out):  # pragma: no cover - jit
    n = x.shape[0]
    for b in numba.prange((n + BLOCK - 1) // BLOCK):
        for i in range(b * BLOCK, min(n, (b + 1) * BLOCK)):
            for a in range(4):
                m = 0.0
                for c in range(4):
                    m += F[a, c] * x[i, c] + G[a, c] * eps[i, c]
                out[i, a] = m


def _bearings_py(px, py, sensors, cz, sz, half_iv, logw):  # pragma: no cover - jit
    n = px.shape[0]
    for b in numba.prange((n + BLOCK - 1) // BLOCK):
        lo = b * BLOCK
        hi = min(n, lo + BLOCK)
        for i in range(lo, hi):
            logw[i] = 0.0
        for s in range(sensors.shape[0]):
            _add_bearing(
                px[lo:hi],
                py[lo:hi],
                sensors[s, 0],
                sensors[s, 1],
                cz[s],
                sz[s],
                half_iv,
                0.0,
                logw[lo:hi],
            )


def _normalise_py(e, x, mean):  # pragma: no cover - jit
    """Given ``e = exp(logw - max)``: the sum, ``e /= sum`` and the weighted mean (block sums)."""
    n = e.shape[0]
    nb = (n + BLOCK - 1) // BLOCK
    parts = np.zeros((nb, 3))
    for b in numba.prange(nb):
        s = 0.0
        mx = 0.0
        my = 0.0
        for i in range(b * BLOCK, min(n, (b + 1) * BLOCK)):
            s += e[i]
            mx += e[i] * x[i, 0]
            my += e[i] * x[i, 1]
        parts[b, 0] = s
        parts[b, 1] = mx
        parts[b, 2] = my
    tot = parts.sum(axis=0)
    inv = 1.0 / tot[0]
    for b in numba.prange(nb):
        for i in range(b * BLOCK, min(n, (b + 1) * BLOCK)):
            e[i] *= inv
    mean[0] = tot[1] * inv
    mean[1] = tot[2] * inv


def _max_py(v):  # pragma: no cover - jit
    m = -np.inf
    for i in range(v.shape[0]):
        m = max(m, v[i])
    return m


def _libm_exp_py(v, m, out):  # pragma: no cover - jit
    n = v.shape[0]
    for b in numba.prange((n + BLOCK - 1) // BLOCK):
        for i in range(b * BLOCK, min(n, (b + 1) * BLOCK)):
            out[i] = math.exp(v[i] - m)


def _resample_py(w, u0, x, anc, counts, out):  # pragma: no cover - jit
    systematic_row(w, u0, anc, counts)
    n = x.shape[0]
    for b in numba.prange((n + BLOCK - 1) // BLOCK):
        for i in range(b * BLOCK, min(n, (b + 1) * BLOCK)):
            j = anc[i]
            for k in range(4):
                out[i, k] = x[j, k]


_KERNELS = {
    name: fused._twins(py)
    for name, py in {
        "normals": _normals_py,
        "propagate": _propagate_py,
        "bearings": _bearings_py,
        "normalise": _normalise_py,
        "libm_exp": _libm_exp_py,
        "resample": _resample_py,
    }.items()
}
_max = numba.njit(cache=True)(_max_py)


def _best(fn: Callable[[], object], repeats: int) -> tuple[float, float]:
    """Minimum wall and minimum CPU seconds of ``repeats`` calls (after one warm-up call)."""
    fn()
    wall, cpu = math.inf, math.inf
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall = min(wall, time.perf_counter() - t0)
        cpu = min(cpu, time.process_time() - c0)
    return wall, cpu


def measure(n: int, repeats: int, threaded: int = 2) -> dict[str, dict[str, float]]:
    """ns per particle of each phase: ``{phase: {"serial": .., "threads": .., "cpu_threads": ..}}``."""
    fused.passive_threads()
    rng = np.random.default_rng(1)
    F, Q = cv_matrices(DT, Q_PSD)
    G = np.linalg.cholesky(Q)
    x = rng.normal(0, 50, (n, 4)) + np.array([200.0, 150.0, 1.0, 1.0])
    eps = rng.standard_normal((n, 4))
    out = np.empty((n, 4))
    px, py = np.ascontiguousarray(x[:, 0]), np.ascontiguousarray(x[:, 1])
    phi = rng.uniform(-np.pi, np.pi, len(SENSORS))
    cz, sz = np.cos(phi), np.sin(phi)
    half_iv = 0.5 / SIGMA_BEARING**2
    logw = np.empty(n)
    w = rng.uniform(0, 1, n) ** 8
    w /= w.sum()
    anc = np.empty(n, dtype=np.intp)
    counts = np.empty(n + 1, dtype=np.intp)
    mean = np.empty(2)
    sensors = np.ascontiguousarray(SENSORS, dtype=float)
    gens1 = [np.random.default_rng(7)]
    gens4 = list(np.random.default_rng(7).spawn(fused.NOISE_STREAMS))
    h1, h4 = rng_handles.generator_handles(gens1), rng_handles.generator_handles(gens4)
    _bearings_serial = _KERNELS["bearings"][0]
    _bearings_serial(px, py, sensors, cz, sz, half_iv, logw)
    m = _max(logw)
    e = np.empty(n)

    def numpy_exp() -> None:
        np.subtract(logw, m, out=e)
        np.exp(e, out=e)

    res: dict[str, dict[str, float]] = {}
    for key, threads in (("serial", 1), ("threads", threaded)):
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
        par = key == "threads"  # the threaded kernels and 4 child generators, on `threads`
        kern = {name: pair[1 if par else 0] for name, pair in _KERNELS.items()}
        h = h4 if par else h1
        calls: dict[str, Callable[[], object]] = {
            "normals": partial(kern["normals"], h, out),
            "propagate": partial(kern["propagate"], x, F, G, eps, out),
            "bearings": partial(kern["bearings"], px, py, sensors, cz, sz, half_iv, logw),
            "max + NumPy exp": lambda: (_max(logw), numpy_exp()),
            "sum, weights, mean": lambda k=kern: k["normalise"](e.copy(), x, mean),
            "resample + gather": partial(kern["resample"], w, 0.5, x, anc, counts, out),
            "(libm exp, not in the sum)": partial(kern["libm_exp"], logw, m, e),
        }
        for name, fn in calls.items():
            wall, cpu = _best(fn, repeats)
            row = res.setdefault(name, {})
            row[key] = wall / n * 1e9
            row["cpu_" + key] = cpu / n * 1e9
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    # the copy inside "sum, weights, mean" is not part of the phase: subtract its own cost
    copy_wall, copy_cpu = _best(lambda: e.copy(), repeats)
    for key in ("serial", "threads"):
        res["sum, weights, mean"][key] -= copy_wall / n * 1e9
        res["sum, weights, mean"]["cpu_" + key] -= copy_cpu / n * 1e9
    return res


def whole_steps(
    n: int, repeats: int, steps: int, libs: list[str], threaded: int = 2
) -> dict[str, dict[str, float]]:
    """ms per step of whole filter runs (``pf_bearing.py``'s runners, ``steps`` steps, the
    prior draw included), the minimum over ``repeats`` runs, on 1 and ``threaded`` threads."""
    from _limit_reference import LimitReferencePF
    from _scenario import make_scenario
    from pf_bearing import FusetrackPF, StoneSoupPF

    scn = make_scenario()
    runners = {"fusetrack": FusetrackPF, "limit_reference": LimitReferencePF}
    runners.update({"stonesoup": StoneSoupPF} if "stonesoup" in libs else {})
    out: dict[str, dict[str, float]] = {}
    for name, cls in runners.items():
        runner = cls(scn, n)  # type: ignore[abstract]

        def one_run(r: object = runner) -> None:
            r.run(1, steps)  # type: ignore[attr-defined]
            if hasattr(r, "cleanup"):
                r.cleanup()  # Stone Soup's predictor cache, as pf_bearing.py clears it

        for threads in sorted({1, threaded}) if name != "stonesoup" else (1,):
            numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
            wall, cpu = _best(one_run, repeats)
            out.setdefault(name, {})[f"{threads}_thread_ms"] = wall / steps * 1e3
            out[name][f"{threads}_thread_cpu_ms"] = cpu / steps * 1e3
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--N", type=int, default=100_000)
    ap.add_argument("--repeats", type=int, default=30)
    ap.add_argument(
        "--stonesoup-ms",
        type=float,
        default=107.0,
        help="Stone Soup ms per step for the bar when --stonesoup is not given",
    )
    ap.add_argument("--steps", type=int, default=20, help="steps of the whole-run timings")
    ap.add_argument("--stonesoup", action="store_true", help="also time Stone Soup's whole run")
    ap.add_argument("--json", action="store_true")
    _results.add_arguments(ap)
    args = ap.parse_args(argv)
    if args.threads is not None and args.threads < 1:
        ap.error("--threads must be >= 1")
    load0 = os.getloadavg()[0]
    run = _results.Run(argv, __file__)
    threaded = args.threads or 2
    with _results.limit_threads(args.threads) as threads:  # default: BLAS on one thread
        run.threads = threads
        res = measure(args.N, args.repeats, threaded)
        libs = ["stonesoup"] if args.stonesoup else []
        runs = whole_steps(args.N, max(3, args.repeats // 6), args.steps, libs, threaded)
    phases = [p for p in res if not p.startswith("(")]
    total = {k: sum(res[p][k] for p in phases) for k in ("serial", "threads", "cpu_threads")}
    ss_ms = runs["stonesoup"]["1_thread_ms"] if "stonesoup" in runs else args.stonesoup_ms
    budget_ns = ss_ms / 30.0 * 1e6 / args.N
    summary = {
        "N": args.N,
        "ns_per_particle": res,
        "floor_ns_per_particle": total,
        "floor_ms_per_step": {k: v * args.N / 1e6 for k, v in total.items()},
        "stonesoup_ms_per_step": ss_ms,
        "bar_ms_per_step": ss_ms / 30.0,
        "bar_ns_per_particle": budget_ns,
        "whole_steps": runs,
        "load": [load0, os.getloadavg()[0]],
        "threaded": threaded,
    }
    run.save(_results.out_path(args, __file__), [summary])
    if args.json:
        print(json.dumps(summary))
        return 0
    print(
        f"N = {args.N}, min of {args.repeats} calls, load {load0:.2f} -> {os.getloadavg()[0]:.2f}"
    )
    print(
        f"{'phase':28s} {'serial ns':>10s} {f'{threaded} thr. ns':>10s} {f'{threaded} thr. cpu':>10s}"
    )
    for p, row in res.items():
        print(f"{p:28s} {row['serial']:10.2f} {row['threads']:10.2f} {row['cpu_threads']:10.2f}")
    print(
        f"{'sum (floor)':28s} {total['serial']:10.2f} {total['threads']:10.2f} {total['cpu_threads']:10.2f}"
    )
    print(
        f"floor per step: {total['serial'] * args.N / 1e6:.2f} ms serial, "
        f"{total['threads'] * args.N / 1e6:.2f} ms on {threaded} threads; 30x Stone Soup "
        f"({ss_ms:.4g} ms{', measured here' if 'stonesoup' in runs else ''}) needs "
        f"{ss_ms / 30:.2f} ms ({budget_ns:.1f} ns/particle)"
    )
    for name, row in runs.items():
        cells = ", ".join(f"{k.replace('_', ' ')} {v:.2f}" for k, v in row.items())
        print(f"whole step, {name}: {cells}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
