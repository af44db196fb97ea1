"""Helpers shared by the Zhai 2007 experiments: timing a filter run, tables, claims."""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Mapping, Sequence
from contextlib import nullcontext
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from ...core import Gaussian, Measurement, filter_step, systematic

Array = NDArray[np.float64]

# compile the resampling kernel once per process, so that no filter's timing includes it
systematic(np.full((1, 2), 0.5), np.random.default_rng(0))

Steps = Sequence[Sequence[Array | None]]
"""One sensor-aligned list per step: a value or None for each of the filter's sensors."""


def run_steps(
    filt: Any,
    prior: Gaussian,
    zs: Steps,
    dt: float,
    rng: np.random.Generator | None,
    *,
    keep: Callable[[Any], Any] = lambda belief: belief.estimate,
    side: Mapping[str, Sequence[Array | None]] | None = None,
    batch_shape: tuple[int, ...] = (),
    sensor_ids: Sequence[str] | None = None,
) -> list[Any]:
    """Run any filter from ``prior`` over ``zs``, step ``k`` at time ``(k + 1) dt``, one
    :func:`~fusetrack.core.filter_step` per step, and return ``keep(belief)`` after each.

    With ``rng`` (the particle filters: :class:`~fusetrack.filters.ProposalParticleFilter`,
    :class:`~fusetrack.filters.MultipleModelParticleFilter`) the belief starts as
    ``filt.initialize(prior, rng, batch_shape)``; without (Gaussian filters) it is ``prior``, or
    ``filt.initialize(prior)`` for an IMM, and overflow inside the filter is silenced (a
    diverging EKF is scored, not reported). ``sensor_ids`` name ``zs``'s columns (default: the
    filter's sensors); ``side`` adds per-step side inputs by id (e.g. CPF-SP's sensor weights;
    a None entry is left out)."""
    if rng is not None:
        belief = filt.initialize(prior, rng, batch_shape)
    else:
        init = getattr(filt, "initialize", None)
        belief = init(prior) if init is not None else prior
    ids = list(sensor_ids) if sensor_ids is not None else [s.sensor_id for s in filt.sensors]
    out = []
    for k, step in enumerate(zs):
        t = (k + 1) * dt
        ms = [Measurement(t, i, np.asarray(z, float)) for i, z in zip(ids, step) if z is not None]
        for sid, values in (side or {}).items():
            if values[k] is not None:
                ms.append(Measurement(t, sid, np.asarray(values[k], dtype=float)))
        quiet = np.errstate(over="ignore", invalid="ignore") if rng is None else nullcontext()
        with quiet:
            belief = filter_step(filt, belief, dt, ms, rng)
        out.append(keep(belief))
    return out


def timed_sis(
    filt: Any,
    prior: Gaussian,
    zs: Steps,
    dt: float,
    rng: np.random.Generator,
    keep: Callable[[Any], Any] | None = None,
    side: Mapping[str, Sequence[Array | None]] | None = None,
) -> tuple[Array, float, list[Any]]:
    """Estimates ``(T, d)``, seconds, and ``keep(belief)`` per step (:func:`run_steps`)."""
    t0 = time.perf_counter()
    kept = run_steps(
        filt, prior, zs, dt, rng, side=side, keep=lambda b: (b.estimate, keep(b) if keep else None)
    )
    secs = time.perf_counter() - t0
    return np.array([e for e, _ in kept]), secs, [k for _, k in kept] if keep else []


def timed_gaussian(
    filt: Any,
    prior: Gaussian,
    zs: Steps,
    sensor_ids: Sequence[str],
    dt: float,
    probs: list[Array] | None = None,
) -> tuple[Array, float]:
    """Run a fusetrack Gaussian filter (EKF/UKF, or an IMM: started with ``filt.initialize``)
    with :func:`run_steps`; NaN/None measurements skipped. An IMM's regime probabilities per
    step are appended to ``probs`` when it is given."""
    finite = [[z if z is not None and np.all(np.isfinite(z)) else None for z in s] for s in zs]
    t0 = time.perf_counter()
    kept = run_steps(
        filt,
        prior,
        finite,
        dt,
        None,
        sensor_ids=sensor_ids,
        keep=lambda b: (np.asarray(b.mean, float), None if probs is None else b.probs),
    )
    secs = time.perf_counter() - t0
    if probs is not None:
        probs.extend(np.asarray(p, float) for _, p in kept)
    return np.array([m for m, _ in kept]), secs


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


def join_with_relations(values: Sequence[float], texts: Sequence[str]) -> str:
    """``texts`` joined by the true relation of consecutive ``values`` (``<``, ``=`` or ``>``), so
    that a printed ordering never claims one the numbers do not have."""
    out = [texts[0]]
    for a, b, text in zip(values[:-1], values[1:], texts[1:]):
        out.append(f"{'<' if a < b else '>' if a > b else '='} {text}")
    return " ".join(out)


def fmt_order(values: pd.Series, order: Sequence[str]) -> str:
    """``"A 1.23 < B 4.56 > C 2.1"``: ``values`` in ``order``, with their true relations."""
    v = [float(values[k]) for k in order]
    return join_with_relations(v, [f"{k} {x:.3g}" for k, x in zip(order, v)])


def timed_mm(
    filt: Any,
    prior: Gaussian,
    zs: Steps,
    dt: float,
    rng: np.random.Generator,
) -> tuple[Array, Array, float]:
    """A multiple-model particle filter run (:func:`run_steps`): estimates ``(T, d)``, model
    probabilities ``(T, M)`` and seconds."""
    t0 = time.perf_counter()
    kept = run_steps(filt, prior, zs, dt, rng, keep=lambda b: (b.estimate, b.proposal.model_probs))
    secs = time.perf_counter() - t0
    return np.array([e for e, _ in kept]), np.array([p for _, p in kept]), secs
