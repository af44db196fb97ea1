"""E2 (Ercan et al. 2013, Sec. 6.1, Fig. 7): tracker RMSE against occluder-prior RMSE.

N = 4 cameras (first 4 of the fixed list), M = 40, no static occluder. The occluder-prior noise
sigma_psi is swept from 0 (perfect priors) through Gaussian priors to infinity (no priors); the
x-axis is the measured RMSE_occ. The paper quotes: RMSE_tr(no priors) / RMSE_tr(perfect) ~ 2.34;
RMSE_tr = RMSE_occ at RMSE_occ ~ 3.72; RMSE_tr(no priors) / 3.72 ~ 1.94; std improves ~3.4x.
"""

from __future__ import annotations

import math

import numpy as np

from ...evaluation.report import Claim, Outcome, RunContext
from .common import curve_plot, fmt, interpolate_crossing, md, mean_std, sizes
from .simulation import run_tracking

SIGMA_PSI_FULL = (0.0, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, math.inf)
SIGMA_PSI_QUICK = (0.0, 2.0, 8.0, math.inf)
PRINTED = "0, printed likelihood"
"""Label of the variant run with the likelihood exactly as printed (hard zeros, full rectangles)."""


def _prior(sigma_psi: float) -> str:
    return "perfect" if sigma_psi == 0 else ("none" if math.isinf(sigma_psi) else "gaussian")


def run(ctx: RunContext) -> Outcome:
    size = sizes(ctx)
    runs = ctx.n_runs(full=5, quick=2)
    sweep = SIGMA_PSI_QUICK if ctx.quick else SIGMA_PSI_FULL
    configs = [
        {
            "scene": "square-open",
            "n_occluders": 40,
            "prior": _prior(s),
            "sigma_psi": s if math.isfinite(s) else 0.0,
            "k": 4,
            "method": "fixed",
            "label": "inf" if math.isinf(s) else f"{s:g}",
            **size,
        }
        for s in sweep
    ]
    printed = {**configs[0], "floor": 0.0, "exclusion": 0.0, "label": PRINTED}
    df_all = ctx.monte_carlo(run_tracking, [*configs, printed], runs, desc="E2 prior accuracy")
    df = df_all[df_all["label"] != PRINTED]
    hard = df_all[df_all["label"] == PRINTED]
    table = mean_std(df, ["label"])
    occ = df.groupby("label")["rmse_occ"].mean()
    table["rmse_occ"] = table["label"].map(occ)
    table = table.sort_values("rmse_occ").reset_index(drop=True)
    table["series"] = "RMSE_tr"
    perfect = table.iloc[0]
    none = table.iloc[-1]
    ratio = float(none["mean"] / perfect["mean"])
    std_ratio = float(none["std"] / max(perfect["std"], 1e-12))
    rmse_max = float(df["rmse_max"].mean())
    hard_mean, hard_std = float(hard["rmse_tr"].mean()), float(hard["rmse_tr"].std(ddof=1))
    hard_ignored = float(hard["ignored_steps"].mean())
    hard_reinit = float(hard["reinitialisations"].mean())
    hard_ratio = float(none["mean"] / hard_mean)
    cross = interpolate_crossing(
        table["rmse_occ"].to_numpy(), (table["mean"] - table["rmse_occ"]).to_numpy(), 0.0
    )
    gain_real = float(none["mean"] / cross) if np.isfinite(cross) and cross > 0 else float("nan")
    tol = 0.5 if ctx.quick else 0.25
    claims = [
        Claim(
            "C4_gain_perfect",
            "mean RMSE_tr with no occluder information / with perfect information",
            2.34,
            ratio,
            f"+-{tol:.0%}",
            abs(ratio / 2.34 - 1) <= tol,
        ),
        Claim(
            "C4_crossing",
            "RMSE_occ where mean RMSE_tr = RMSE_occ (priors no better than the tracker)",
            3.72,
            cross,
            f"+-{tol:.0%}",
            bool(np.isfinite(cross) and abs(cross / 3.72 - 1) <= tol),
        ),
        Claim(
            "C4_gain_realistic",
            "mean RMSE_tr with no information / RMSE_tr at the crossing",
            1.94,
            gain_real,
            f"+-{tol:.0%}",
            bool(np.isfinite(gain_real) and abs(gain_real / 1.94 - 1) <= tol),
        ),
        Claim(
            "C4_std_gain",
            "std of RMSE_tr over runs, no information / perfect information",
            3.4,
            std_ratio,
            "> 1 (the paper's 3.4 is from 5 runs; a ratio of standard deviations of 5 runs is itself very noisy)",
            std_ratio > 1,
        ),
        Claim(
            "C4_ordering",
            "mean RMSE_tr does not fall as the priors get worse (Spearman rho of RMSE_occ vs RMSE_tr)",
            "increasing",
            float(table[["rmse_occ", "mean"]].corr(method="spearman").iloc[0, 1]),
            ">= 0.5",
            float(table[["rmse_occ", "mean"]].corr(method="spearman").iloc[0, 1]) >= 0.5,
        ),
        Claim(
            "C12_priors_worthwhile",
            "conclusion: at realistic prior accuracy the gain over no priors is modest (<= 2.34x)",
            "~1.94x",
            gain_real,
            "between 1 and 2.34",
            bool(np.isfinite(gain_real) and 1 <= gain_real <= 2.34 * (1 + tol)),
        ),
        Claim(
            "rmse_max_open",
            "RMSE_max without the static occluder",
            21.4,
            rmse_max,
            "+-15%",
            abs(rmse_max / 21.4 - 1) <= 0.15,
        ),
        Claim(
            "C4_gain_perfect_printed",
            "as C4_gain_perfect, with the perfect-prior likelihood exactly as printed (hard zeros)",
            2.34,
            hard_ratio,
            f"+-{tol:.0%}",
            abs(hard_ratio / 2.34 - 1) <= tol,
        ),
    ]
    curve_plot(
        ctx.figure_path("fig7_rmse_vs_prior_accuracy"),
        table,
        "rmse_occ",
        "series",
        xlabel="RMSE_occ (units)",
        ylabel="RMSE_tr (units)",
        title=f"Fig. 7: N = 4, M = 40, no static occluder, {runs} runs x {size['steps']} steps",
        diagonal=True,
    )
    show = table[["label", "rmse_occ", "mean", "std", "runs"]].rename(
        columns={"label": "sigma_psi", "mean": "RMSE_tr mean", "std": "RMSE_tr std"}
    )
    report = f"""
## Setup

Square room without the static occluder, cameras 1, 7, 5, 3 (first 4 of the fixed list), M = 40, D = 3.33,
L = {size["particles"]}, {size["steps"]} steps, {runs} runs. sigma_psi = 0 is the perfect-information likelihood,
sigma_psi = inf the no-information one (Sec. 6.1); in between, Gaussian priors from random-walk Kalman filters.

## The paper's numbers beside ours

| quantity | paper | ours |
|---|---|---|
| RMSE_tr(no info) / RMSE_tr(perfect) | 2.34 | {fmt(ratio)} |
| RMSE_occ where RMSE_tr = RMSE_occ | 3.72 | {fmt(cross)} |
| RMSE_tr(no info) / crossing | 1.94 | {fmt(gain_real)} |
| std ratio | 3.4 | {fmt(std_ratio)} |
| RMSE_tr(perfect) (implied) | ~3.1 | {fmt(float(perfect["mean"]))} |
| RMSE_tr(no info) (implied) | ~7.2 | {fmt(float(none["mean"]))} |
| RMSE_max | 21.4 | {fmt(rmse_max)} |

{md(show)}

Variant, the likelihood exactly as printed (hard zeros, rectangles to the particle), sigma_psi = 0:
RMSE_tr {fmt(hard_mean)} (std {fmt(hard_std)}) over {len(hard)} runs.

![Fig. 7](fig7_rmse_vs_prior_accuracy.png)

## Differences and their causes

* Absolute RMSEs depend on the reconstructed camera layout and on details the paper leaves open (tracker motion
  noise, initial particles, the Kalman filter of the priors); the ratios are the comparable quantities.
* The crossing is read off the piecewise-linear mean curve; with few sweep points (quick run: {len(sweep)}) it is coarse.
* The perfect-prior likelihood of Sec. 6.1 is all-or-nothing: a particle survives only if every camera's
  seen/not-seen report matches the known discs exactly. When the object is barely hidden the consistent region
  is a thin shadow; when the predicted cloud misses it, every weight is 0, the step's readings are lost and the
  cloud drifts (the Gaussian part of the likelihood, which would pull it back, is multiplied by 0). Run as
  printed (the variant above), the perfect-prior tracker had RMSE_tr {fmt(hard_mean)} (std {fmt(hard_std)}),
  {hard_ignored:.1f} steps per run with no consistent particle and {hard_reinit:.1f} re-initialisations per run;
  its gain over no priors is {fmt(hard_ratio)}x. Our runs floor p(eta | u) at the value in `simulation.DEFAULTS`
  (a report that contradicts the known occluders is improbable, not impossible) and stop the rectangles of
  Eq. 7 one D before the particle (all rectangles of a particle overlap there, Eq. 8's disjointness fails and
  the true position itself got p = 0).
* What still differs: both our trackers are better than the paper's implied ones (perfect ~3.1, none ~7.2), and
  the no-prior one by much more. The paper gives neither its camera layout nor tracker details beyond
  Algorithm 1; with our layout (cameras 1, 7, 5, 3 in the corners, each seeing the whole room) the object is
  rarely unobserved for long, and a not-seen report carries no information without priors, so the no-prior
  tracker rarely loses the object. The ratio 2.34 is therefore not reproduced; the ordering is.
* The Kalman priors' error persists over many steps while the tracker treats each step's occlusion evidence
  as new; at intermediate accuracy this repeated, correlated evidence can pull the cloud the same wrong way
  step after step, which is why intermediate priors may do no better than none here.
* The std ratio is a ratio of two standard deviations of {runs} runs each and varies a lot between seeds.
"""
    return Outcome(df_all, claims, report, runs=runs)
