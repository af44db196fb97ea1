"""Helpers shared by the Zhai 2007 experiments: timing a filter run, tables, claims."""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import pandas as pd

from ...core import Gaussian, Measurement
from ...core.resampling import systematic
from ...filters.sis import Array, ProposalParticleFilter, run_sis

# compile the resampling kernel once per process, so that no filter's timing includes it
systematic(np.full((1, 2), 0.5), np.random.default_rng(0))


def timed_sis(
    filt: ProposalParticleFilter,
    prior: Gaussian,
    zs: Sequence[Sequence[Array | None]],
    dt: float,
    rng: np.random.Generator,
    keep: Callable[[Any], Any] | None = None,
) -> tuple[Array, float, list[Any]]:
    """Estimates ``(T, d)``, seconds, and ``keep(state)`` per step."""
    t0 = time.perf_counter()
    est, kept = run_sis(filt, prior, zs, dt, rng, keep=keep)
    return est, time.perf_counter() - t0, kept


def timed_gaussian(
    filt: Any,
    prior: Gaussian,
    zs: Sequence[Sequence[Array | None]],
    sensor_ids: Sequence[str],
    dt: float,
    probs: list[Array] | None = None,
) -> tuple[Array, float]:
    """Run a fusetrack Gaussian filter (EKF/UKF, or an IMM: started with ``filt.initialize``)
    step by step; NaN/None measurements skipped. An IMM's regime probabilities per step are
    appended to ``probs`` when it is given."""
    t0 = time.perf_counter()
    belief = filt.initialize(prior) if hasattr(filt, "initialize") else prior
    out = []
    for k, step in enumerate(zs):
        with np.errstate(over="ignore", invalid="ignore"):
            belief = filt.predict(belief, dt)
        ms = [
            Measurement(float(k + 1), sid, np.atleast_1d(np.asarray(z, float)))
            for sid, z in zip(sensor_ids, step)
            if z is not None and np.all(np.isfinite(z))
        ]
        if ms:
            with np.errstate(over="ignore", invalid="ignore"):
                belief = filt.update(belief, ms)
        out.append(np.asarray(belief.mean, float))
        if probs is not None:
            probs.append(np.asarray(belief.probs, float))
    return np.array(out), time.perf_counter() - t0


def track_rows(method: str, est: Array, truth: Array, **columns: Any) -> list[dict[str, Any]]:
    """One row per step: squared position error, estimate and truth positions; ``columns``
    values are constants or per-step sequences (``est``, ``truth`` ``(T, d)``, position first)."""
    rows = []
    for t in range(len(truth)):
        row: dict[str, Any] = {
            "method": method,
            "step": t + 1,
            "sq_pos_err": float(np.sum((est[t, :2] - truth[t, :2]) ** 2)),
            "x": float(est[t, 0]),
            "y": float(est[t, 1]),
            "true_x": float(truth[t, 0]),
            "true_y": float(truth[t, 1]),
        }
        for k, v in columns.items():
            row[k] = v[t] if isinstance(v, (list, tuple, np.ndarray)) else v
        rows.append(row)
    return rows


def ordering_holds(values: pd.Series, order: Sequence[str]) -> bool:
    """``values[order[0]] < values[order[1]] < ...``."""
    v = [float(values[k]) for k in order]
    return all(a < b for a, b in itertools.pairwise(v))


def fmt_order(values: pd.Series, order: Sequence[str]) -> str:
    return " < ".join(f"{k} {float(values[k]):.3g}" for k in order)


def timed_mm(
    filt: Any,
    prior: Gaussian,
    zs: Sequence[Sequence[Array | None]],
    dt: float,
    rng: np.random.Generator,
) -> tuple[Array, Array, float]:
    """A multiple-model particle filter run (:func:`~fusetrack.filters.multiple_model.run_mm`):
    estimates ``(T, d)``, model probabilities ``(T, M)`` and seconds."""
    from ...filters.multiple_model import run_mm

    t0 = time.perf_counter()
    est, probs = run_mm(filt, prior, zs, dt, rng)
    return est, probs, time.perf_counter() - t0
