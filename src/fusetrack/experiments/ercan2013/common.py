"""What the Ercan et al. 2013 experiments share: run sizes, summaries, plots of rooms and curves."""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from pydantic import Field

from ...core import ConfigError, invalid
from ...evaluation import ExperimentOptions, RunContext, plots
from .scenes import Scene

PAPER = "Ercan, El Gamal, Guibas 2013, ACM TOSN 9(2) 16"


def smoke() -> bool:
    """Tiny sizes for the end-to-end tests (environment variable ``FUSETRACK_SMOKE=1``): the same
    code paths and output files in seconds; the numbers mean nothing."""
    return os.environ.get("FUSETRACK_SMOKE", "") not in ("", "0")


def sizes(ctx: RunContext, *, steps: int = 4000, particles: int = 1000) -> dict[str, int]:
    """Steps, particles and burn-in: the paper's (no burn-in) or a quick run's."""
    if smoke():
        return {"steps": 10, "particles": 50, "burn_in": 2}
    if ctx.quick:
        return {"steps": 150, "particles": 600, "burn_in": 15}
    return {"steps": steps, "particles": particles, "burn_in": 0}


class SizeOptions(ExperimentOptions):
    """``--set steps=N`` / ``particles=L`` / ``burn_in=B``: a full-size run that must fit a time
    budget (fewer steps per run, the paper's number of runs); unset: the run's own sizes."""

    steps: int | None = Field(None, ge=1, description="time steps per run (default: the run's)")
    particles: int | None = Field(
        None, ge=1, description="particles of the tracker (default: the run's)"
    )
    burn_in: int | None = Field(
        None, ge=0, description="steps left out of RMSE_tr, < steps (default: the run's)"
    )


PRINTED_PREFIX = "printed "
"""Label prefix of a series run with the likelihood exactly as printed (hard zeros, full rectangles)."""


def prior_level(sigma_psi: float) -> str:
    """The occluder-prior level of a sweep point: 0 is perfect, infinity none, else Gaussian."""
    return "perfect" if sigma_psi == 0 else ("none" if math.isinf(sigma_psi) else "gaussian")


def sweep_config(sigma_psi: float, k: int, size: dict[str, int]) -> dict[str, Any]:
    """One point of a sigma_psi sweep in the open square room (M = 40, first ``k`` fixed cameras),
    labelled by its sigma_psi ("inf": no priors)."""
    return {
        "scene": "square-open",
        "n_occluders": 40,
        "prior": prior_level(sigma_psi),
        "sigma_psi": sigma_psi if math.isfinite(sigma_psi) else 0.0,
        "k": k,
        "method": "fixed",
        "label": "inf" if math.isinf(sigma_psi) else f"{sigma_psi:g}",
        **size,
    }


def printed_config(config: dict[str, Any]) -> dict[str, Any]:
    """``config`` with the likelihood exactly as printed (floor 0, full Eq. 7 rectangles)."""
    return {
        **config,
        "floor": 0.0,
        "exclusion": 0.0,
        "label": f"{PRINTED_PREFIX}{config['label']}",
    }


def printed_runs(results: pd.DataFrame, no_prior: pd.DataFrame) -> pd.DataFrame:
    """The printed-likelihood runs of ``results`` under their sweep labels, with the shared
    no-prior runs ``no_prior`` (neither correction enters the no-prior likelihood)."""
    is_printed = results["label"].str.startswith(PRINTED_PREFIX)
    return pd.concat(
        [
            results[is_printed].assign(label=lambda d: d["label"].str[len(PRINTED_PREFIX) :]),
            no_prior,
        ]
    )


def size_options(ctx: RunContext, size: dict[str, int]) -> dict[str, int]:
    """``size`` with the :class:`SizeOptions` the user set applied."""
    opts = SizeOptions.of(ctx).model_dump()
    out = {k: v if opts[k] is None else opts[k] for k, v in size.items()}
    if out["burn_in"] >= out["steps"]:
        raise ConfigError(invalid("--set burn_in", out["burn_in"], f"< steps = {out['steps']}"))
    return out


@dataclass(frozen=True)
class Timed:
    """A Monte Carlo table with the wall time and load averages around it."""

    results: pd.DataFrame
    wall: float
    load_start: tuple[float, float, float]
    load_end: tuple[float, float, float]


def timed_monte_carlo(
    ctx: RunContext,
    fn: Callable[..., Any],
    configs: Sequence[Mapping[str, Any]],
    runs: int,
    desc: str,
) -> Timed:
    """``ctx.monte_carlo(fn, configs, runs)`` timed: wall seconds, load average before and after."""
    load_start = os.getloadavg()
    t0 = time.perf_counter()
    results = ctx.monte_carlo(fn, configs, runs, desc=desc)
    wall = time.perf_counter() - t0
    return Timed(results, wall, load_start, os.getloadavg())


def cost_text(ctx: RunContext, timed: Timed) -> str:
    """The Monte Carlo's wall time, worker processes and load averages (the machine is shared)."""
    wall, start, end = timed.wall, timed.load_start, timed.load_end
    return f"""Tracking wall time {wall:.0f} s ({wall / 60:.1f} min) with {ctx.workers or os.cpu_count()} worker processes, load average
{start[0]:.2f} / {start[1]:.2f} / {start[2]:.2f} at the start and {end[0]:.2f} / {end[1]:.2f} /
{end[2]:.2f} at the end (1 / 5 / 15 min; the machine has {os.cpu_count()} cores and is shared)."""


def mean_std(df: pd.DataFrame, by: Sequence[str], value: str = "rmse_tr") -> pd.DataFrame:
    """Mean, standard deviation (ddof 1; 0 for one run) and count of ``value`` per group."""
    g = df.groupby(list(by))[value]
    out = pd.DataFrame({"mean": g.mean(), "std": g.std(ddof=1).fillna(0.0), "runs": g.count()})
    return out.reset_index()


def curve_plot(
    path: Path,
    table: pd.DataFrame,
    x: str,
    series: str,
    *,
    xlabel: str,
    ylabel: str,
    title: str,
    hlines: Mapping[str, float] | None = None,
    diagonal: bool = False,
    labels: Mapping[Any, str] | None = None,
) -> Path:
    """Mean +- one standard deviation of each series against ``x`` (the paper's error-bar plots),
    bars shifted sideways so that they do not hide one another; ``hlines`` are labelled
    reference values."""
    fig, ax = plots.panel(size=(6.4, 4.4))
    groups = list(table.groupby(series, sort=False))
    span = float(table[x].max() - table[x].min()) or 1.0
    for i, (key, grp) in enumerate(groups):
        grp = grp.sort_values(x)
        off = (i - (len(groups) - 1) / 2) * 0.012 * span  # small shifts keep error bars apart
        label = (labels or {}).get(key, str(key))
        plots.curve(ax, grp[x] + off, grp["mean"], index=i, label=label, yerr=grp["std"])
    dashes = (":", "--", "-.", (0, (6, 2)))
    for k, (name, y) in enumerate((hlines or {}).items()):
        plots.reference_line(ax, y, name, linestyle=dashes[k % 4])
    if diagonal:
        lim = max(table[x].max(), table["mean"].max())
        ax.plot([0, lim], [0, lim], "k:", lw=1, label="y = x")
    plots.label_axes(ax, xlabel, ylabel, title)
    plots.legend(ax)
    return plots.save(fig, path)


def room_plot(
    path: Path,
    scene: Scene,
    *,
    title: str,
    occluders: np.ndarray | None = None,
    obj: np.ndarray | None = None,
    truth: np.ndarray | None = None,
    estimate: np.ndarray | None = None,
    fov_length: float | None = None,
) -> Path:
    """The room, its cameras with numbered field-of-view wedges, occluders, object and track."""
    fig, axes = plots.figure(1, 1, size=(6.0, 6.0))
    ax = axes[0, 0]
    discs = [(p, scene.diameter / 2) for p in occluders] if occluders is not None else []
    plots.draw_scene(ax, scene.room, occluders=discs, cameras=scene.cameras, fov_length=fov_length)
    if truth is not None:
        ax.plot(truth[:, 0], truth[:, 1], "-", color="tab:green", lw=1.2, label="object path")
    if estimate is not None:
        ax.plot(estimate[:, 0], estimate[:, 1], "--", color="tab:red", lw=0.8, label="estimate")
    if obj is not None:
        ax.plot(*obj, "*", color="tab:red", ms=12, label="object")
    plots.label_axes(ax, title=title)
    ax.legend(fontsize=8, loc="upper right")
    return plots.save(fig, path)


def md(df: pd.DataFrame, floatfmt: str = ".3g") -> str:
    return str(df.to_markdown(index=False, floatfmt=floatfmt))


def fmt(v: float, digits: int = 3) -> str:
    return f"{v:.{digits}g}" if np.isfinite(v) else "n/a"


def interpolate_crossing(x: np.ndarray, y: np.ndarray, target: float) -> float:
    """First ``x`` where the piecewise-linear ``y(x)`` reaches ``target`` (NaN if it never does)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    for i in range(len(x) - 1):
        lo, hi = y[i] - target, y[i + 1] - target
        if lo == 0:
            return float(x[i])
        if lo * hi < 0:
            return float(x[i] + (x[i + 1] - x[i]) * lo / (lo - hi))
    return float(x[-1]) if len(x) and y[-1] == target else float("nan")
