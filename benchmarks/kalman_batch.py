"""Speed of 1000 independent EKF / UKF tracks: fusetrack as one batch vs 1000 FilterPy filters.

The problem (the same for both): 2-D constant velocity ``[x, y, vx, vy]`` (continuous white-noise
acceleration, PSD ``q``), one range-bearing radar at the origin, ``dt = 1`` s. Each of the
``--tracks`` targets has its own truth, prior and measurements (simulated once with NumPy from
one seed; bearings cross the +-pi branch cut for some tracks). fusetrack steps all tracks as one
batched :class:`~fusetrack.core.Gaussian` (means ``(T, 4)``, covariances ``(T, 4, 4)``); FilterPy
steps one ``ExtendedKalmanFilter`` / ``UnscentedKalmanFilter`` object per track with plain NumPy
model functions (``hx``, Jacobian, wrapped residual, circular mean of the sigma-point bearings),
so FilterPy is not slowed down by fusetrack's models. The EKF of both uses the Joseph-form
covariance update; the UKF of both uses Van der Merwe's scaled sigma points
(``alpha = 1, beta = 2, kappa = 3 - d``).

Equality: the first timed run of each library keeps every step's posterior; the benchmark reports
the largest absolute difference of the means and covariances over all tracks and steps, and
``"agree": false`` (no speed-up) when either is above 1e-9 (``_results.agree_exact``).

    python benchmarks/kalman_batch.py [--tracks 1000 [100 ...]] [--steps 20] [--repeats 3]
        [--filters ekf ukf] [--threads T] [--json] [--save | --out PATH]

Timing: ``time.perf_counter`` (and ``time.process_time``, reported beside it) around a whole run (``steps`` predict + update), divided by
``steps``; the median over ``--repeats`` runs, taken round-robin (FilterPy, fusetrack, FilterPy,
...) so that a change of load hits both alike. BLAS is limited to one thread (``--threads T``:
BLAS/OpenMP and Numba get T threads, ``_results.py``). Building the
measurement objects, the prior and FilterPy's filter objects (one per track, state set from the
prior) happens before the clock starts, for every repeat.

fusetrack's batch of 1000 EKF tracks takes :mod:`fusetrack.filters.kalman_kernels`' Numba
Joseph-form update (batches of 16 beliefs or more); the UKF takes the NumPy path.
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

import numpy as np
from numpy.typing import NDArray

import _results
from _scenario import cv_matrices, wrap

Array = NDArray[np.float64]

DT = 1.0
Q_PSD = 0.05
SIGMA_RANGE = 0.5  # m
SIGMA_BEARING = 0.01  # rad


class Problem:
    """Truth, priors and measurements of ``tracks`` independent targets."""

    def __init__(self, tracks: int, steps: int, seed: int = 7) -> None:
        rng = np.random.default_rng(seed)
        F, Q = cv_matrices(DT, Q_PSD)
        LQ = np.linalg.cholesky(Q)
        angle = rng.uniform(-np.pi, np.pi, tracks)
        dist = rng.uniform(50.0, 300.0, tracks)
        x = np.stack(
            [
                dist * np.cos(angle),
                dist * np.sin(angle),
                rng.normal(0, 2, tracks),
                rng.normal(0, 2, tracks),
            ],
            axis=-1,
        )
        z = np.empty((steps, tracks, 2))
        truth = np.empty((steps, tracks, 4))
        for k in range(steps):
            x = x @ F.T + rng.standard_normal((tracks, 4)) @ LQ.T
            truth[k] = x
            z[k, :, 0] = np.hypot(x[:, 0], x[:, 1]) + SIGMA_RANGE * rng.standard_normal(tracks)
            z[k, :, 1] = wrap(
                np.arctan2(x[:, 1], x[:, 0]) + SIGMA_BEARING * rng.standard_normal(tracks)
            )
        self.tracks, self.steps = tracks, steps
        self.truth, self.z = truth, z
        self.p0 = np.diag([25.0, 25.0, 4.0, 4.0])
        start = rng.standard_normal((tracks, 4)) * np.sqrt(np.diag(self.p0))
        # prior at time 0: the truth one step back, perturbed (an honest prior)
        self.x0 = truth[0] @ np.linalg.inv(F).T + start
        self.R = np.diag([SIGMA_RANGE**2, SIGMA_BEARING**2])


# --------------------------------------------------------------------------------------------
# fusetrack: one batch


class FusetrackBatch:
    def __init__(self, prob: Problem, kind: str) -> None:
        from fusetrack.core import Gaussian, Measurement
        from fusetrack.filters import ExtendedKalmanFilter, UnscentedKalmanFilter
        from fusetrack.motion import ConstantVelocity
        from fusetrack.sensors import RangeBearing

        radar = RangeBearing(
            "radar", position=[0.0, 0.0], sigma_range=SIGMA_RANGE, sigma_bearing=SIGMA_BEARING
        )
        motion = ConstantVelocity(ndim=2, q=Q_PSD)
        cls = ExtendedKalmanFilter if kind == "ekf" else UnscentedKalmanFilter
        self.filt = cls(motion, [radar])
        self.prior = Gaussian(prob.x0, np.broadcast_to(prob.p0, (prob.tracks, 4, 4)).copy())
        self.meas = [Measurement((k + 1) * DT, "radar", prob.z[k]) for k in range(prob.steps)]

    def fresh(self) -> object:
        """The prior (built outside the clock; beliefs are immutable, so nothing to copy)."""
        return self.prior

    def run(self, prior: object, steps: int, keep: bool) -> tuple[Array, Array] | None:
        filt, b = self.filt, prior
        means = np.empty((steps, *b.mean.shape)) if keep else None
        covs = np.empty((steps, *b.cov.shape)) if keep else None
        for k in range(steps):
            b = filt.update(filt.predict(b, DT), [self.meas[k]])
            if keep:
                means[k], covs[k] = b.mean, b.cov  # type: ignore[index]
        return (means, covs) if keep else None  # type: ignore[return-value]


# --------------------------------------------------------------------------------------------
# FilterPy: one object per track, plain NumPy model functions


def _hx(x: Array) -> Array:
    return np.array([np.hypot(x[0], x[1]), np.arctan2(x[1], x[0])])


def _h_jacobian(x: Array) -> Array:
    r2 = x[0] ** 2 + x[1] ** 2
    r = np.sqrt(r2)
    return np.array([[x[0] / r, x[1] / r, 0.0, 0.0], [-x[1] / r2, x[0] / r2, 0.0, 0.0]])


def _residual(a: Array, b: Array) -> Array:
    y = np.subtract(a, b)
    y[1] = wrap(y[1])
    return y


def _z_mean(sigmas: Array, wm: Array) -> Array:
    z = wm @ sigmas
    z[1] = np.arctan2(wm @ np.sin(sigmas[:, 1]), wm @ np.cos(sigmas[:, 1]))
    return z


class FilterpyLoop:
    def __init__(self, prob: Problem, kind: str) -> None:
        from filterpy.kalman import ExtendedKalmanFilter as FpEKF
        from filterpy.kalman import MerweScaledSigmaPoints
        from filterpy.kalman import UnscentedKalmanFilter as FpUKF

        self.kind, self.prob = kind, prob
        F, Q = cv_matrices(DT, Q_PSD)
        self.F, self.Q = F, Q

        def make() -> object:
            if kind == "ekf":
                f = FpEKF(dim_x=4, dim_z=2)
                f.F = F.copy()
            else:
                pts = MerweScaledSigmaPoints(4, alpha=1.0, beta=2.0, kappa=3.0 - 4.0)
                f = FpUKF(
                    dim_x=4,
                    dim_z=2,
                    dt=DT,
                    hx=_hx,
                    fx=lambda x, dt: F @ x,
                    points=pts,
                    z_mean_fn=_z_mean,
                    residual_z=_residual,
                )
            f.Q, f.R = Q.copy(), prob.R.copy()
            return f

        self.make = make

    def fresh(self) -> object:
        """One new filter per track, state set from the prior (built outside the clock)."""
        prob, filters = self.prob, []
        for t in range(prob.tracks):
            f = self.make()
            f.x, f.P = prob.x0[t].copy(), prob.p0.copy()  # type: ignore[attr-defined]
            filters.append(f)
        return filters

    def run(self, filters: object, steps: int, keep: bool) -> tuple[Array, Array] | None:
        prob = self.prob
        means = np.empty((steps, prob.tracks, 4)) if keep else None
        covs = np.empty((steps, prob.tracks, 4, 4)) if keep else None
        ekf = self.kind == "ekf"
        for k in range(steps):
            zk = prob.z[k]
            for t, f in enumerate(filters):
                if ekf:
                    f.predict()  # type: ignore[attr-defined]
                    f.update(zk[t], _h_jacobian, _hx, residual=_residual)  # type: ignore[attr-defined]
                else:
                    f.predict()  # type: ignore[attr-defined]
                    f.update(zk[t])  # type: ignore[attr-defined]
                if keep:
                    means[k, t], covs[k, t] = f.x, f.P  # type: ignore[attr-defined,index]
        return (means, covs) if keep else None  # type: ignore[return-value]


RUNNERS: dict[str, Callable[[Problem, str], object]] = {
    "filterpy": FilterpyLoop,
    "fusetrack": FusetrackBatch,
}


def measure(prob: Problem, kind: str, args: argparse.Namespace) -> dict[str, object]:
    runners = {lib: RUNNERS[lib](prob, kind) for lib in RUNNERS}
    for r in runners.values():  # warm-up (imports, caches)
        r.run(r.fresh(), min(2, args.steps), False)  # type: ignore[attr-defined]
    times: dict[str, list[float]] = {lib: [] for lib in runners}
    cpu: dict[str, list[float]] = {lib: [] for lib in runners}
    kept: dict[str, tuple[Array, Array]] = {}
    for rep in range(args.repeats):
        for lib, runner in runners.items():
            start = runner.fresh()  # type: ignore[attr-defined]
            gc.collect()
            t0, c0 = time.perf_counter(), time.process_time()
            out = runner.run(start, args.steps, rep == 0)  # type: ignore[attr-defined]
            times[lib].append((time.perf_counter() - t0) / args.steps)
            cpu[lib].append((time.process_time() - c0) / args.steps)
            if rep == 0:
                kept[lib] = out
    (m_a, c_a), (m_b, c_b) = kept["fusetrack"], kept["filterpy"]
    diff_mean = float(np.max(np.abs(m_a - m_b)))
    diff_cov = float(np.max(np.abs(c_a - 0.5 * (c_b + np.swapaxes(c_b, -1, -2)))))
    sec = {lib: statistics.median(t) for lib, t in times.items()}
    csec = {lib: statistics.median(t) for lib, t in cpu.items()}
    agree = _results.agree_exact(max(diff_mean, diff_cov))
    rmse = {
        lib: float(
            np.sqrt(
                np.mean(np.sum((kept[lib][0][..., :2] - prob.truth[: args.steps, :, :2]) ** 2, -1))
            )
        )
        for lib in kept
    }
    return {
        "N": prob.tracks,
        "filter": kind,
        "seconds_per_step": sec,
        "rmse": rmse,
        "max_abs_diff": {"mean": diff_mean, "cov": diff_cov},
        "cpu_seconds_per_step": csec,
        "agree": agree,  # equal to 1e-9, else no speed-up
        "speedup": sec["filterpy"] / sec["fusetrack"] if agree else None,
        "cpu_speedup": csec["filterpy"] / csec["fusetrack"] if agree else None,
        "load": os.getloadavg()[0],
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tracks", type=int, nargs="+", default=[1000])
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--filters", nargs="+", default=["ekf", "ukf"], choices=["ekf", "ukf"])
    ap.add_argument("--json", action="store_true", help="one JSON object per filter")
    _results.add_arguments(ap)
    args = ap.parse_args(argv)
    if min(args.tracks) < 1 or args.steps < 1 or args.repeats < 1:
        ap.error("--tracks, --steps and --repeats must be >= 1")
    if args.threads is not None and args.threads < 1:
        ap.error("--threads must be >= 1")
    run, rows = _results.Run(argv, __file__), []
    with _results.limit_threads(args.threads) as threads:
        run.threads = threads
        for tracks in args.tracks:
            prob = Problem(tracks, args.steps)
            if not args.json:
                print(
                    f"{tracks} tracks, 4-D CV, range-bearing radar, {args.steps} steps, median "
                    f"of {args.repeats} round-robin runs, threads {args.threads or 'BLAS 1'}; "
                    f"load average {os.getloadavg()[0]:.2f}"
                )
            for kind in args.filters:
                res = measure(prob, kind, args)
                rows.append(res)
                if args.json:
                    print(json.dumps(res), flush=True)
                    continue
                _print(kind, res)
    run.save(_results.out_path(args, __file__), rows)
    return 0


def _print(kind: str, res: dict) -> None:
    sec, csec, d = res["seconds_per_step"], res["cpu_seconds_per_step"], res["max_abs_diff"]
    ratio = (
        f"speed-up {res['speedup']:.1f}x (cpu {res['cpu_speedup']:.1f}x)"
        if res["agree"]
        else "DISAGREE (> 1e-9): no speed-up"
    )
    print(
        f"\n{kind.upper()}: fusetrack {sec['fusetrack'] * 1e3:.2f} ms/step "
        f"(cpu {csec['fusetrack'] * 1e3:.2f}), FilterPy {sec['filterpy'] * 1e3:.1f} ms/step "
        f"(cpu {csec['filterpy'] * 1e3:.1f}), {ratio}; max |diff| mean {d['mean']:.2e}, "
        f"cov {d['cov']:.2e}; RMSE {res['rmse']}; load {res['load']:.2f}",
        flush=True,
    )


if __name__ == "__main__":
    sys.exit(main())
