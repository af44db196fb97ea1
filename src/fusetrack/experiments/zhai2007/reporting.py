"""Report pieces shared by the Zhai 2007 experiments: claims of a common shape, RMSE curves over
Monte Carlo runs, and the figure boilerplate (RMSE against time, one run's tracks)."""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ...evaluation import (
    Claim,
    ClaimKinds,
    RunContext,
    interval_values,
    paired_interval,
    plots,
    shown_positive,
)
from .common import fmt_order, ordering_holds


def rmse_by_step(df: pd.DataFrame, column: str) -> pd.DataFrame:
    """``sqrt(mean(df[column]))`` per method and step: one column per method, indexed by step."""
    return df.groupby(["method", "step"])[column].mean().pow(0.5).unstack("method")


def rmse_by_method(df: pd.DataFrame, column: str) -> pd.Series:
    """``sqrt(mean(df[column]))`` per method, over every step and run of ``df``."""
    return df.groupby("method")[column].mean().pow(0.5)


def order_claim(
    kinds: ClaimKinds,
    claim_id: str,
    statement: str,
    paper: Any,
    values: pd.Series,
    order: Sequence[str],
    tolerance: str = "strict",
) -> Claim:
    """``values[order[0]] < values[order[1]] < ...``, reported by :func:`fmt_order`; the kind
    from the experiment's ``kinds``."""
    return kinds.claim(
        claim_id,
        statement,
        paper,
        fmt_order(values, order),
        tolerance,
        ordering_holds(values, order),
    )


def paired_order_claim(
    kinds: ClaimKinds,
    claim_id: str,
    statement: str,
    paper: Any,
    per_run: pd.DataFrame,
    order: Sequence[str],
) -> Claim:
    """``order[0] < order[1] < ...`` in the mean over runs of ``per_run`` (index run, one column
    per method), judged per adjacent pair by the 95 % t-interval of the paired difference over
    runs (the runs share their data): each must lie above 0. Filters that converged to the same
    posterior (bootstrap 1000 vs 2000) differ by noise, which a bare ``<`` would judge."""
    gaps = {
        f"{b} - {a}": paired_interval(per_run[b], per_run[a]) for a, b in itertools.pairwise(order)
    }
    ours = {
        "means": fmt_order(per_run.mean(), order),
        **{f"{k} (paired mean, 95% half-width)": interval_values(v) for k, v in gaps.items()},
    }
    held = all(shown_positive(v) for v in gaps.values())
    return kinds.claim(claim_id, statement, paper, ours, "each gap's 95% t-interval above 0", held)


def relative_claim(
    kinds: ClaimKinds, claim_id: str, statement: str, paper: float, ours: float, rel: float
) -> Claim:
    """``ours`` within ``rel`` (a fraction) of the paper's ``paper``; the kind from ``kinds``."""
    return kinds.claim(
        claim_id, statement, paper, ours, f"relative ±{rel:.0%}", abs(ours - paper) <= rel * paper
    )


def plot_rmse(
    ctx: RunContext,
    name: str,
    rmse: pd.DataFrame,
    methods: Iterable[str],
    title: str,
    xlabel: str = "t",
    ylabel: str = "position RMSE",
) -> Path:
    """RMSE(t) of ``methods`` (columns of :func:`rmse_by_step`), log scale, saved as ``name``."""
    return plots.plot_series(
        ctx.figure_path(name),
        rmse.index.to_numpy(),
        {m: rmse[m].to_numpy() for m in methods},
        xlabel=xlabel,
        ylabel=ylabel,
        title=title,
        logy=True,
    )


def plot_run_tracks(
    ctx: RunContext,
    name: str,
    run: pd.DataFrame,
    truth_method: str,
    methods: Iterable[str],
    sensors: Sequence[tuple[str, Any]],
    title: str,
    area: tuple[float, float, float, float] | None = None,
) -> Path:
    """One run's estimated tracks (rows with ``x``, ``y``) beside the truth (``true_x``,
    ``true_y`` of ``truth_method``'s rows), with the sensors marked."""
    return plots.plot_trajectories(
        ctx.figure_path(name),
        run[run["method"] == truth_method][["true_x", "true_y"]].to_numpy(),
        {m: run[run["method"] == m][["x", "y"]].to_numpy() for m in methods},
        sensors=sensors,
        area=area,
        title=title,
    )


def origin_sensor(label: str = "sensor") -> list[tuple[str, np.ndarray]]:
    """The one sensor at the origin, as :func:`plot_run_tracks` marks it."""
    return [(label, np.zeros(2))]
