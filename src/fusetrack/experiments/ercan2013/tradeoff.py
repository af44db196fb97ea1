"""E3 (Ercan et al. 2013, Sec. 6.1, Fig. 8): cameras against prior accuracy at RMSE_tr = 3.

Square room without the static occluder, M = 40. For each number of cameras k (first k of the
fixed list) the occluder-prior noise is swept; the RMSE_occ at which the mean RMSE_tr reaches the
target 3 units is read off the piecewise-linear curve. If even no priors reach the target, the
tolerated RMSE_occ is RMSE_max ("no prior information needed"); if even perfect priors miss it, the
target is out of reach with k cameras.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from ...evaluation.report import Claim, Outcome, RunContext
from .common import fmt, interpolate_crossing, md, mean_std, sizes
from .prior_accuracy import _prior
from .simulation import run_tracking

TARGET = 3.0


def tolerated(grp: pd.DataFrame, rmse_max: float) -> float:
    """RMSE_occ at which the mean RMSE_tr of one camera count reaches TARGET (see the module)."""
    g = grp.sort_values("rmse_occ")
    if g["mean"].iloc[-1] <= TARGET:
        return rmse_max
    if g["mean"].iloc[0] > TARGET:
        return float("nan")
    return interpolate_crossing(g["rmse_occ"].to_numpy(), g["mean"].to_numpy(), TARGET)


def run(ctx: RunContext) -> Outcome:
    size = sizes(ctx)
    runs = ctx.n_runs(full=5, quick=2)
    ks = [3, 8] if ctx.quick else list(range(2, 9))
    sweep = (0.0, 8.0, math.inf) if ctx.quick else (0.0, 2.0, 4.0, 8.0, 16.0, 32.0, math.inf)
    configs = [
        {
            "scene": "square-open",
            "n_occluders": 40,
            "prior": _prior(s),
            "sigma_psi": s if math.isfinite(s) else 0.0,
            "k": k,
            "method": "fixed",
            "label": "inf" if math.isinf(s) else f"{s:g}",
            **size,
        }
        for k in ks
        for s in sweep
    ]
    df = ctx.monte_carlo(run_tracking, configs, runs, desc="E3 trade-off")
    table = mean_std(df, ["k", "label"])
    occ = df.groupby(["k", "label"])["rmse_occ"].mean()
    table["rmse_occ"] = [occ[(k, lab)] for k, lab in zip(table["k"], table["label"])]
    rmse_max = float(df["rmse_max"].mean())
    curve = pd.DataFrame(
        [{"k": k, "tolerated_rmse_occ": tolerated(g, rmse_max)} for k, g in table.groupby("k")]
    )
    vals = curve["tolerated_rmse_occ"].fillna(-1.0).to_numpy()
    steps_ok = np.diff(vals) >= -0.1 * rmse_max
    share = float(steps_ok.mean()) if len(steps_ok) else float("nan")
    top = float(vals[-1])
    claims = [
        Claim(
            "C5_monotone",
            "the prior RMSE tolerated at RMSE_tr = 3 does not fall as cameras are added (share of steps in k)",
            "non-decreasing",
            share,
            ">= 0.75 (dips under 10% of RMSE_max allowed)",
            share >= 0.75,
        ),
        Claim(
            "C5_no_prior_needed",
            "with enough cameras no prior information is needed (tolerated RMSE_occ at the largest k / RMSE_max)",
            1.0,
            top / rmse_max,
            ">= 0.99",
            top / rmse_max >= 0.99,
        ),
    ]
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.0, 4.2))
    ok = curve.dropna()
    ax.plot(ok["tolerated_rmse_occ"], ok["k"], "o-")
    ax.axvline(rmse_max, ls=":", color="k", lw=1)
    ax.annotate("RMSE_max (no priors)", (rmse_max, ks[0]), fontsize=8, ha="right")
    ax.set_xlabel("RMSE_occ tolerated (units)")
    ax.set_ylabel("number of cameras")
    ax.set_title(f"Fig. 8: cameras vs prior accuracy for mean RMSE_tr = {TARGET:g} ({runs} runs)")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(ctx.figure_path("fig8_tradeoff"), dpi=110)
    plt.close(fig)
    grid = table.pivot(index="k", columns="label", values="mean")
    grid = grid[
        [c for c in ["0", "2", "4", "8", "16", "32", "inf"] if c in grid.columns]
    ].reset_index()
    report = f"""
## Setup

Square room without the static occluder, M = 40, first k of the fixed camera list, sigma_psi swept
({", ".join("inf" if math.isinf(s) else f"{s:g}" for s in sweep)}; 0 = perfect, inf = no priors), {runs} runs x
{size["steps"]} steps, L = {size["particles"]}. The paper plots only the curve (no numbers).

## Tolerated prior accuracy (Fig. 8)

{md(curve.assign(**{"tolerated / RMSE_max": curve["tolerated_rmse_occ"] / rmse_max}))}

NaN: even perfect priors miss RMSE_tr = {TARGET:g} with that many cameras. RMSE_max = {fmt(rmse_max)}.

Mean RMSE_tr per camera count (rows) and sigma_psi (columns):

{md(grid)}

![Fig. 8](fig8_tradeoff.png)

## Differences and their causes

* The paper's curve comes from an unstated grid; the reading here is linear interpolation on the sweep above, so
  its resolution is that of the sweep. With 5 runs the mean curves are noisy and the read-off can dip.
* Where the tracker already beats the target with no priors the tolerated accuracy is RMSE_max by definition.
"""
    return Outcome(df, claims, report, runs=runs)
