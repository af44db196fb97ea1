"""E3 (Ercan et al. 2013, Sec. 6.1, Fig. 8): cameras against prior accuracy at RMSE_tr = 3.

Square room without the static occluder, M = 40. For each number of cameras k (first k of the
fixed list) the occluder-prior noise is swept; the RMSE_occ at which the mean RMSE_tr reaches the
target 3 units is read off the piecewise-linear curve. If even no priors reach the target, the
tolerated RMSE_occ is RMSE_max ("no prior information needed"); if even perfect priors miss it, the
target is out of reach with k cameras.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from ...evaluation import (
    Claim,
    ClaimKinds,
    Outcome,
    RunContext,
    mean_with_se,
    plots,
    possible_claim,
)
from . import best_possible as bp
from .common import (
    PRINTED_PREFIX,
    fmt,
    interpolate_crossing,
    md,
    mean_std,
    printed_config,
    printed_runs,
    sizes,
    sweep_config,
)
from .simulation import DEFAULTS, run_tracking

TARGET = 3.0
SWEEP_FULL = (0.0, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, math.inf)
"""sigma_psi of the full run (the spec's sweep, as E2's): perfect, six Gaussian accuracies, none;
the measured RMSE_occ is in the report. With every k = 1..8 (:data:`KS_FULL`) the grid is 64
configurations (71 with the printed series, 77 with the best possible's, 385 runs); a run costs
2-62 CPU s (more cameras and wider priors cost more; ~80% of it in the occlusion-aware
likelihood). Each run's CPU seconds are in the committed report's ``results.parquet``;
``benchmarks/reproduction_budget.py`` splits them against the 30-minute budget."""
KS_FULL = tuple(range(1, 9))
KS_QUICK = (3, 8)
SWEEP_QUICK = (0.0, 8.0, math.inf)
PAPER_PERFECT_K4 = 3.1
"""The paper's RMSE_tr with perfect priors at N = 4, M = 40 (implied by Sec. 6.1: 7.2 / 2.34)."""
PRINTED_KS_FULL = (8,)
PRINTED_KS_QUICK = (8,)
"""Camera counts also run with the likelihood as printed (floor 0, full Eq. 7 rectangles)."""
BEST_KS = (2, 4, 8)
"""Camera counts whose perfect- and no-prior points are rerun with 2L particles (the best
possible; the quick run has k = 8 only): 4-12 CPU s per run at 2L, ~300 CPU s in all."""
BEST_FACTORS = {"full": (1, 2), "quick": (1, 2)}
"""The best possible's particle counts as multiples of L: the paper's L (the grid's own runs), 2L."""


def tolerated(grp: pd.DataFrame, rmse_max: float, target: float = TARGET) -> float:
    """RMSE_occ at which the mean RMSE_tr of one camera count reaches ``target`` (see the module)."""
    g = grp.sort_values("rmse_occ")
    if g["mean"].iloc[-1] <= target:
        return rmse_max
    if g["mean"].iloc[0] > target:
        return float("nan")
    return interpolate_crossing(g["rmse_occ"].to_numpy(), g["mean"].to_numpy(), target)


def _grid(df: pd.DataFrame) -> pd.DataFrame:
    """Mean and std of RMSE_tr per (k, sigma_psi label), with the measured RMSE_occ."""
    table = mean_std(df, ["k", "label"])
    occ = df.groupby(["k", "label"])["rmse_occ"].mean()
    table["rmse_occ"] = [occ[(k, lab)] for k, lab in zip(table["k"], table["label"])]
    return table


def _gaussian_vs_none(table: pd.DataFrame) -> pd.DataFrame:
    """Per k: how many Gaussian sigma_psi beat no priors (mean RMSE_tr <= none's), and which."""
    rows = []
    for k, g in table.groupby("k"):
        none = g[g["label"] == "inf"]["mean"]
        gauss = g[~g["label"].isin(["0", "inf"])].sort_values("rmse_occ")
        if none.empty or gauss.empty:
            continue
        ok = gauss[gauss["mean"] <= float(none.iloc[0])]["label"].tolist()
        rows.append(
            {
                "k": k,
                "none": float(none.iloc[0]),
                "best Gaussian": float(gauss["mean"].min()),
                "worst Gaussian": float(gauss["mean"].max()),
                "beat none": f"{len(ok)} of {len(gauss)}",
                "sigma_psi that beat none": ", ".join(ok) or "-",
            }
        )
    return pd.DataFrame(rows)


def _grid_figure(ctx: RunContext, table: pd.DataFrame, targets: list[float], runs: int) -> str:
    """Mean RMSE_tr over (RMSE_occ, k) as a colour map with the iso-lines at ``targets``."""
    mean = table.pivot(index="k", columns="label", values="mean")
    occ = table.groupby("label")["rmse_occ"].mean()
    labels = sorted(mean.columns, key=lambda lab: occ[lab])
    mean = mean[labels]
    x = occ[labels].to_numpy()
    y = mean.index.to_numpy()
    z = mean.to_numpy()
    fig, ax = plots.panel(size=(6.6, 4.4))
    plots.colour_map(ax, z, x=x, y=y, label="mean RMSE_tr (units)", log=True, filled_levels=14)
    if len(y) > 1 and len(x) > 1:
        plots.contour_lines(ax, x, y, z, sorted(set(targets)), ["r", "w"][: len(set(targets))])
    gx, gy = np.meshgrid(x, y)
    ax.scatter(gx.ravel(), gy.ravel(), s=6, c="k", alpha=0.5, label="grid points run")
    plots.label_axes(ax, "RMSE_occ (units; left = perfect priors, right = none)",
                     "number of cameras k", f"RMSE_tr over the grid ({runs} runs each)")  # fmt: skip
    plots.legend(ax, loc="upper right")
    plots.save(fig, ctx.figure_path("rmse_grid"))
    return "rmse_grid.png"


@dataclass(frozen=True)
class _Tradeoff:
    """E3's results: the RMSE_tr grids (corrected and printed likelihood) and the tolerated
    RMSE_occ per camera count read off them."""

    df_all: pd.DataFrame
    df: pd.DataFrame
    table: pd.DataFrame
    hard_table: pd.DataFrame
    curve: pd.DataFrame
    hard_curve: dict[Any, float]
    rmse_max: float
    perfect_k4: pd.Series
    scaled: float
    best: bp.BestPossible
    gaussian: dict[int, tuple[float, float]]
    gaussian_label: str


def _configs(ctx: RunContext, size: dict[str, int]) -> list[dict[str, Any]]:
    """Scenario: the (k, sigma_psi) grid, at a few k the printed-likelihood series, and the best
    possible (the extremes at :data:`BEST_KS` with more particles)."""
    ks = list(KS_QUICK if ctx.quick else KS_FULL)
    sweep = SWEEP_QUICK if ctx.quick else SWEEP_FULL
    configs = [sweep_config(s, k, size) for k in ks for s in sweep]
    printed_ks = PRINTED_KS_QUICK if ctx.quick else PRINTED_KS_FULL
    printed = [  # neither correction enters the no-prior likelihood: those runs are shared
        printed_config(c) for c in configs if c["k"] in printed_ks and c["prior"] != "none"
    ]
    extremes = [c for c in configs if c["prior"] in bp.EXTREMES and c["k"] in BEST_KS]
    best = bp.best_configs(extremes, _best_counts(ctx, size), size["particles"])
    return [*configs, *printed, *best]


def _best_counts(ctx: RunContext, size: dict[str, int]) -> tuple[int, int]:
    """The best possible's two particle counts (BEST_FACTORS times L)."""
    return bp.particle_counts(ctx.quick, size["particles"], BEST_FACTORS)


def _estimate(ctx: RunContext, size: dict[str, int], runs: int) -> _Tradeoff:
    """Estimation: run the grid, tabulate it and read the tolerated RMSE_occ per k."""
    printed_ks = PRINTED_KS_QUICK if ctx.quick else PRINTED_KS_FULL
    df_all = ctx.monte_carlo(run_tracking, _configs(ctx, size), runs, desc="E3 trade-off")
    is_printed = df_all["label"].str.startswith(PRINTED_PREFIX)
    df = df_all[~is_printed & ~bp.is_best(df_all)]
    rmse_max = float(df["rmse_max"].mean())
    table = _grid(df)
    hard_table = _grid(printed_runs(df_all, df[(df["label"] == "inf") & df["k"].isin(printed_ks)]))
    curve = pd.DataFrame(
        [{"k": k, "tolerated_rmse_occ": tolerated(g, rmse_max)} for k, g in table.groupby("k")]
    )
    hard_curve = {k: tolerated(g, rmse_max) for k, g in hard_table.groupby("k")}
    # Our tracker is more accurate than the paper's; the same trade-off at a target scaled by the
    # ratio of the perfect-prior RMSEs at k = 4 (ours / the paper's implied 3.1)
    perfect_k4 = table[(table["k"] == 4) & (table["label"] == "0")]["mean"]
    scaled = TARGET * float(perfect_k4.iloc[0]) / PAPER_PERFECT_K4 if len(perfect_k4) else TARGET
    curve[f"tolerated at scaled target {scaled:.2f}"] = [
        tolerated(g, rmse_max, scaled) for _, g in table.groupby("k")
    ]
    curve["tolerated (printed likelihood)"] = curve["k"].map(hard_curve)
    counts = _best_counts(ctx, size)
    best = bp.estimate(df, df_all[bp.is_best(df_all)], counts, size["particles"], ["prior", "k"])
    finest = min(float(v) for v in df.loc[df["prior"] == "gaussian", "label"])  # most accurate
    finest_runs = df[(df["prior"] == "gaussian") & (df["label"].astype(float) == finest)]
    gaussian = {
        k: mean_with_se(finest_runs.loc[finest_runs["k"] == k, "rmse_tr"]) for k in bp.grid_ks(best)
    }
    return _Tradeoff(
        df_all, df, table, hard_table, curve, hard_curve, rmse_max, perfect_k4, scaled,
        best, gaussian, f"{finest:g}",
    )  # fmt: skip


# Each claim's kind (fusetrack.evaluation.KINDS), by id or fnmatch pattern, first match.
CLAIM_KINDS = ClaimKinds(
    {
        "C5_monotone_scaled_target": "diagnostic",  # readings of C5
        "C5_no_prior_needed_printed": "diagnostic",
        "C5_monotone": "paper",
        "C5_no_prior_needed": "paper",
        "BP_*": "diagnostic",  # the best possible on the printed model (issue 19 item 3)
    }
)


def _claims(t: _Tradeoff, ks: list[int]) -> list[Claim]:
    """C5: the tolerated RMSE_occ does not fall with cameras; enough cameras need no priors."""
    curve, rmse_max, scaled, hard_curve = t.curve, t.rmse_max, t.scaled, t.hard_curve
    vals = curve["tolerated_rmse_occ"].fillna(-1.0).to_numpy()
    steps_ok = np.diff(vals) >= -0.1 * rmse_max
    share = float(steps_ok.mean()) if len(steps_ok) else float("nan")
    top = float(vals[-1])
    claims = [
        CLAIM_KINDS.claim(
            "C5_monotone",
            "the prior RMSE tolerated at RMSE_tr = 3 does not fall as cameras are added (share of steps in k)",
            "non-decreasing",
            share,
            ">= 0.75 (dips under 10% of RMSE_max allowed)",
            share >= 0.75,
        ),
        CLAIM_KINDS.claim(
            "C5_no_prior_needed",
            "with enough cameras no prior information is needed (tolerated RMSE_occ at the largest k / RMSE_max)",
            1.0,
            top / rmse_max,
            ">= 0.99",
            top / rmse_max >= 0.99,
        ),
    ]
    scaled_vals = curve[f"tolerated at scaled target {scaled:.2f}"].fillna(-1.0).to_numpy()
    scaled_ok = np.diff(scaled_vals) >= -0.1 * rmse_max
    claims.append(
        CLAIM_KINDS.claim(
            "C5_monotone_scaled_target",
            f"as C5_monotone, at the target scaled to our tracker ({scaled:.2f})",
            "non-decreasing",
            float(scaled_ok.mean()) if len(scaled_ok) else float("nan"),
            ">= 0.75 (dips under 10% of RMSE_max allowed)",
            bool(len(scaled_ok) and scaled_ok.mean() >= 0.75),
        )
    )
    hard_top = float(hard_curve.get(ks[-1], float("nan")))
    claims.append(
        CLAIM_KINDS.claim(
            "C5_no_prior_needed_printed",
            "as C5_no_prior_needed, with the likelihood as printed (hard zeros, full rectangles)",
            1.0,
            hard_top / rmse_max,
            ">= 0.99",
            bool(np.isfinite(hard_top) and hard_top / rmse_max >= 0.99),
        )
    )
    return claims


def _best_claims(t: _Tradeoff) -> list[Claim]:
    """Against the best possible: the grid's ordering (which E3's read-off assumes), our most
    accurate Gaussian priors against the no-prior best possible, convergence, and the paper's
    implied perfect-prior RMSE_tr at k = 4 (when k = 4 is rerun)."""
    claims = bp.grid_claims(
        CLAIM_KINDS, t.best, t.gaussian, "E3's read-off (RMSE_tr rising with RMSE_occ)", bp.EXTREMES,
        f"the sweep's most accurate Gaussian priors at sigma_psi = {t.gaussian_label}",
    )  # fmt: skip
    if 4 in bp.grid_ks(t.best):
        claims.append(
            possible_claim(
                CLAIM_KINDS,
                "BP_perfect_k4_possible",
                f"RMSE_tr with perfect priors and k = 4 ({PAPER_PERFECT_K4:g}, implied by Sec. 6.1)",
                PAPER_PERFECT_K4,
                t.best.best(("perfect", 4)),
            )
        )
    return claims


def _report_best(t: _Tradeoff, runs: int) -> str:
    """Report text: the best possible beside the grid."""
    n1, n2 = t.best.counts
    return f"""
{bp.intro(t.best, runs)} Only perfect and no occluder priors are rerun, at k in
{bp.grid_ks(t.best)}; the "gaussian" column is our tracker with the sweep's most accurate Gaussian
priors (sigma_psi = {t.gaussian_label}), whose large-L limit is no best possible (the random-walk
Kalman priors are overconfident). Mean over runs of the per-run RMSE_tr ± its standard error;
"–": not run.

{md(bp.grid_rows(t.best, t.gaussian, bp.EXTREMES))}

Reading a tolerated RMSE_occ off the grid assumes that RMSE_tr rises with RMSE_occ; on the
printed model the minimum mean-square errors do (exact occluder positions are more information
than noisy ones, which are more than none), so the extremes' posterior means must be in order
(`BP_ordering_possible`), and a Gaussian-prior tracker above the no-prior best possible has priors
worse than no information (`BP_gaussian_not_above_no_prior_best`). The paper prints one number the
best possible can judge, RMSE_tr = {PAPER_PERFECT_K4:g} with perfect priors at k = 4 (implied by
Sec. 6.1; `BP_perfect_k4_possible`). `BP_converged_*` check that L = {n1} and L = {n2} agree.

"""


def _tradeoff_figure(ctx: RunContext, t: _Tradeoff, ks: list[int], runs: int) -> None:
    """Fig. 8: cameras against the tolerated RMSE_occ (corrected, printed, scaled target)."""
    curve, rmse_max, scaled = t.curve, t.rmse_max, t.scaled
    fig, ax = plots.panel(size=(6.0, 4.2))
    ok = curve.dropna()
    plots.curve(ax, ok["tolerated_rmse_occ"], ok["k"], index=0, label="corrected likelihood")
    hard_ok = curve.dropna(subset=["tolerated (printed likelihood)"])
    ax.plot(hard_ok["tolerated (printed likelihood)"], hard_ok["k"], "s", color="C1", mfc="none",
            label="likelihood as printed")  # fmt: skip
    col = f"tolerated at scaled target {scaled:.2f}"
    sc = curve.dropna(subset=[col])
    plots.curve(ax, sc[col], sc["k"], index=2, label=f"corrected, scaled target {scaled:.2f}")
    plots.reference_line(ax, rmse_max, "RMSE_max (no priors)", axis="x")
    plots.label_axes(ax, "RMSE_occ tolerated (units)", "number of cameras",
                     f"Fig. 8: cameras vs prior accuracy for mean RMSE_tr = {TARGET:g} ({runs} runs)")  # fmt: skip
    plots.legend(ax)
    plots.save(fig, ctx.figure_path("fig8_tradeoff"))


def _report_tables(ctx: RunContext, t: _Tradeoff, size: dict[str, int], runs: int) -> str:
    """Report text: setup, the tolerated accuracy, the scaled target, the RMSE_tr grids."""
    curve, rmse_max, perfect_k4, scaled, df = t.curve, t.rmse_max, t.perfect_k4, t.scaled, t.df
    sweep = SWEEP_QUICK if ctx.quick else SWEEP_FULL
    printed_ks = PRINTED_KS_QUICK if ctx.quick else PRINTED_KS_FULL
    order = sorted(set(t.table["label"]), key=float)
    grid = t.table.pivot(index="k", columns="label", values="mean")[order].reset_index()
    hard_grid = t.hard_table.pivot(index="k", columns="label", values="mean")[order].reset_index()
    return f"""
## Setup

Square room without the static occluder, M = 40, first k of the fixed camera list, sigma_psi swept
({", ".join("inf" if math.isinf(s) else f"{s:g}" for s in sweep)}; 0 = perfect, inf = no priors), {runs} runs x
{size["steps"]} steps, L = {size["particles"]}. The paper plots only the curve (no numbers).

## Tolerated prior accuracy (Fig. 8)

{md(curve.assign(**{"tolerated / RMSE_max": curve["tolerated_rmse_occ"] / rmse_max}))}

Scaled target: our tracker is more accurate than the paper's (perfect priors, k = 4: ours
{fmt(float(perfect_k4.iloc[0])) if len(perfect_k4) else "n/a"} against the paper's implied {PAPER_PERFECT_K4:g}), so
RMSE_tr = {TARGET:g} may be reached without priors at every camera count; the scaled target {TARGET:g} x ours / {PAPER_PERFECT_K4:g} =
{scaled:.2f} asks the same of our tracker as the paper's 3 asked of its own.

NaN: even perfect priors miss RMSE_tr = {TARGET:g} with that many cameras. RMSE_max = {fmt(rmse_max)}.
"printed likelihood": the same sweep at k in {list(printed_ks)} with p(eta | u) not floored and Eq. 7 rectangles up
to the particle (the paper as printed); the other columns use the floor {DEFAULTS["floor"]:g} and rectangles ending
{DEFAULTS["exclusion"]:g} D before the particle.

Calibration of the Gaussian priors (squared error / the variance they claim, per coordinate; 1 = calibrated),
per sigma_psi: {", ".join(f"{lab}: {v:.2f}" for lab, v in df[df["prior"] == "gaussian"].groupby("label")["prior_nees"].mean().items())}.
Overconfident priors (> 1) overstate the occlusion evidence.

Mean RMSE_tr per camera count (rows) and sigma_psi (columns):

{md(grid)}

The same with the likelihood as printed:

{md(hard_grid)}

"""


def _report_figures(grid_png: str, beats: pd.DataFrame) -> str:
    """Report text: Fig. 8, the whole grid, Gaussian priors against none, differences."""
    return f"""![Fig. 8](fig8_tradeoff.png)

The whole grid (mean RMSE_tr, log colour scale) with the iso-RMSE lines the curves above are read from:

![RMSE_tr over cameras and prior accuracy]({grid_png})

Gaussian priors against none, per camera count: the sigma_psi whose mean RMSE_tr is at most that of no
priors (the paper's Figs. 6-7 have every Gaussian curve between the perfect and the no-prior one):

{md(beats)}

## Differences and their causes

* The paper's curve comes from an unstated grid; the reading here is linear interpolation on the sweep above, so
  its resolution is that of the sweep. With 5 runs the mean curves are noisy and the read-off can dip.
* Where the tracker already beats the target with no priors the tolerated accuracy is RMSE_max by definition.
"""


def run(ctx: RunContext) -> Outcome:
    """E3: scenario, estimation, claims, Fig. 8 and the grid, report text."""
    size = sizes(ctx)
    runs = ctx.n_runs(full=5, quick=2)
    ks = list(KS_QUICK if ctx.quick else KS_FULL)
    t = _estimate(ctx, size, runs)
    claims = _claims(t, ks) + _best_claims(t)
    _tradeoff_figure(ctx, t, ks, runs)
    grid_png = _grid_figure(ctx, t.table, [TARGET, t.scaled], runs)
    beats = _gaussian_vs_none(t.table)
    report = (
        _report_tables(ctx, t, size, runs)
        + _report_best(t, runs)
        + _report_figures(grid_png, beats)
    )
    return Outcome(t.df_all, claims, report, runs=runs)
