"""E2 (Ercan et al. 2013, Sec. 6.1, Fig. 7): tracker RMSE against occluder-prior RMSE.

N = 4 cameras (first 4 of the fixed list), M = 40, no static occluder. The occluder-prior noise
sigma_psi is swept from 0 (perfect priors) through Gaussian priors to infinity (no priors); the
x-axis is the measured RMSE_occ. The paper quotes: RMSE_tr(no priors) / RMSE_tr(perfect) ~ 2.34;
RMSE_tr = RMSE_occ at RMSE_occ ~ 3.72; RMSE_tr(no priors) / 3.72 ~ 1.94; std improves ~3.4x.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
import pandas as pd

from ...evaluation import Claim, ClaimKinds, Outcome, RunContext, best_table, possible_claim
from . import best_possible as bp
from .common import (
    PRINTED_PREFIX,
    curve_plot,
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

SIGMA_PSI_FULL = (0.0, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, math.inf)
SIGMA_PSI_QUICK = (0.0, 2.0, 8.0, math.inf)
SIGMA_V_PREFIX = "sigma_v "
"""Label prefix of the extremes rerun with another tracker motion noise (the paper does not give it)."""
SIGMA_V_SWEPT = 2.0
"""Tracker sigma_v at which the whole sigma_psi sweep is rerun (the paper's 2.34x, 3.72 and 1.94x)."""
SIGMA_V_EXTREMES_FULL = (1.0,)
"""Further sigma_v at which only perfect and no priors are rerun."""
WITH = {"perfect": "with perfect occluder priors", "none": "with no occluder priors"}
"""Fig. 7's two extremes, whose best possible is shown (:mod:`.best_possible`)."""
PAPER_RMSE_TR = {"perfect": 3.1, "none": 7.2}
"""The paper's mean RMSE_tr at the two extremes (implied by Sec. 6.1's ratios, spec C4:
~7.2 / 2.34 ~ 3.1 and 1.94 x 3.72 ~ 7.2)."""
PAPER_CROSSING = 3.72
"""The paper's mean RMSE_tr where it equals RMSE_occ (Sec. 6.1), with Gaussian priors."""


class _Curve(NamedTuple):
    """Fig. 7's curve and the numbers the paper reads off it."""

    table: pd.DataFrame
    ratio: float
    std_ratio: float
    cross: float
    gain: float


def _curve(df: pd.DataFrame) -> _Curve:
    """Fig. 7's curve (mean, std of RMSE_tr per sigma_psi, sorted by RMSE_occ) and its numbers:
    no-info / perfect ratio, std ratio, the crossing RMSE_tr = RMSE_occ, no-info / crossing."""
    table = mean_std(df, ["label"])
    occ = df.groupby("label")["rmse_occ"].mean()
    table["rmse_occ"] = table["label"].map(occ)
    table = table.sort_values("rmse_occ").reset_index(drop=True)
    perfect, none = table.iloc[0], table.iloc[-1]
    ratio = float(none["mean"] / perfect["mean"])
    std_ratio = float(none["std"] / max(perfect["std"], 1e-12))
    cross = interpolate_crossing(
        table["rmse_occ"].to_numpy(), (table["mean"] - table["rmse_occ"]).to_numpy(), 0.0
    )
    gain_real = float(none["mean"] / cross) if np.isfinite(cross) and cross > 0 else float("nan")
    return _Curve(table, ratio, std_ratio, cross, gain_real)


def _sigma_v_table(noisier: pd.DataFrame, df_all: pd.DataFrame) -> pd.DataFrame:
    """Perfect and no-prior RMSE_tr and their ratio per tracker sigma_v (0.33: the main series)."""
    base = df_all[df_all["label"].isin(["0", "inf"])].assign(
        sigma_v=0.33, prior_label=lambda d: d["label"]
    )
    parts = noisier["label"].str[len(SIGMA_V_PREFIX) :].str.split("|", expand=True)
    more = noisier.assign(sigma_v=parts[0].astype(float), prior_label=parts[1])
    both = pd.concat([base, more])
    mean = both.groupby(["sigma_v", "prior_label"])["rmse_tr"].mean().unstack()
    std = both.groupby(["sigma_v", "prior_label"])["rmse_tr"].std(ddof=1).unstack()
    return pd.DataFrame(
        {
            "tracker sigma_v": mean.index,
            "RMSE_tr perfect": mean["0"].to_numpy(),
            "std perfect": std["0"].to_numpy(),
            "RMSE_tr none": mean["inf"].to_numpy(),
            "std none": std["inf"].to_numpy(),
            "none / perfect (paper 2.34)": (mean["inf"] / mean["0"]).to_numpy(),
        }
    )


@dataclass(frozen=True)
class _Sweep:
    """All series of one E2 run: the corrected sweep, the printed one, and the sigma_v reruns."""

    results: pd.DataFrame
    df: pd.DataFrame
    hard: pd.DataFrame
    main: _Curve
    printed: _Curve
    sv: _Curve
    sv_table: pd.DataFrame
    best: bp.BestPossible


def _configs(ctx: RunContext, size: dict[str, int]) -> list[dict[str, Any]]:
    """Scenario: the sigma_psi sweep, the printed-likelihood series, the sigma_v reruns and the
    posterior-mean series (the extremes with many more particles, last)."""
    sweep = SIGMA_PSI_QUICK if ctx.quick else SIGMA_PSI_FULL
    configs = [sweep_config(s, 4, size) for s in sweep]
    printed = [
        printed_config(c)
        for c in configs
        if c["prior"] != "none"  # neither correction enters the no-prior likelihood
    ]
    noisier = [  # a tracker that assumes more motion noise (Eq. 5's sigma_v, not given)
        {**c, "tracker_sigma_v": sv, "label": f"{SIGMA_V_PREFIX}{sv:g}|{c['label']}"}
        for sv in (SIGMA_V_SWEPT, *(() if ctx.quick else SIGMA_V_EXTREMES_FULL))
        for c in configs
        if sv == SIGMA_V_SWEPT or c["prior"] != "gaussian"
    ]
    counts = bp.particle_counts(ctx.quick, size["particles"])
    extremes = [c for c in configs if c["prior"] in WITH]
    return [*configs, *printed, *noisier, *bp.best_configs(extremes, counts, size["particles"])]


def _estimate(ctx: RunContext, size: dict[str, int], runs: int) -> _Sweep:
    """Estimation: run every series and read Fig. 7's curves off them."""
    every = ctx.monte_carlo(run_tracking, _configs(ctx, size), runs, desc="E2 prior accuracy")
    results = every[~bp.is_best(every)]
    is_noisier = results["label"].str.startswith(SIGMA_V_PREFIX)
    sv_table = _sigma_v_table(results[is_noisier], results)
    swept_prefix = f"{SIGMA_V_PREFIX}{SIGMA_V_SWEPT:g}|"
    swept = results[results["label"].str.startswith(swept_prefix)]
    sv = _curve(swept.assign(label=swept["label"].str[len(swept_prefix) :]))
    df_all = results[~is_noisier]
    is_printed = df_all["label"].str.startswith(PRINTED_PREFIX)
    df = df_all[~is_printed]
    hard = printed_runs(df_all, df[df["label"] == "inf"])  # shared no-prior runs at the end
    counts = bp.particle_counts(ctx.quick, size["particles"])
    best = bp.estimate(df, every[bp.is_best(every)], counts, size["particles"], "prior")
    return _Sweep(every, df, hard, _curve(df), _curve(hard), sv, sv_table, best)


# Each claim's kind (fusetrack.evaluation.KINDS), by id or fnmatch pattern, first match.
CLAIM_KINDS = ClaimKinds(
    {
        "BP_*": "diagnostic",  # the best possible on the printed model (issue 19)
        "C4_*_printed": "diagnostic",  # readings: the likelihood as printed, sigma_v = 2
        "C4_*_sigma_v_2": "diagnostic",
        "C4_*": "paper",
        "C12_priors_worthwhile": "paper",
        "rmse_max_open": "paper",
    }
)


def _relative(cid: str, statement: str, paper: float, ours: float, tol: float) -> Claim:
    """A claim that ``ours`` is within ``tol`` (relative) of the paper's number."""
    return CLAIM_KINDS.claim(
        cid,
        statement,
        paper,
        ours,
        f"+-{tol:.0%}",
        bool(np.isfinite(ours) and abs(ours / paper - 1) <= tol),
    )


def _main_claims(w: _Sweep, tol: float) -> list[Claim]:
    """C4 and C12 on the corrected sweep, and RMSE_max of the open room."""
    table, ratio, std_ratio, cross, gain_real = w.main
    rmse_max = float(w.df["rmse_max"].mean())
    rho = float(table[["rmse_occ", "mean"]].corr(method="spearman").iloc[0, 1])
    return [
        _relative(
            "C4_gain_perfect",
            "mean RMSE_tr with no occluder information / with perfect information",
            2.34,
            ratio,
            tol,
        ),
        _relative(
            "C4_crossing",
            "RMSE_occ where mean RMSE_tr = RMSE_occ (priors no better than the tracker)",
            3.72,
            cross,
            tol,
        ),
        _relative(
            "C4_gain_realistic",
            "mean RMSE_tr with no information / RMSE_tr at the crossing",
            1.94,
            gain_real,
            tol,
        ),
        CLAIM_KINDS.claim(
            "C4_std_gain",
            "std of RMSE_tr over runs, no information / perfect information",
            3.4,
            std_ratio,
            "> 1 (the paper's 3.4 is from 5 runs; a ratio of standard deviations of 5 runs is itself very noisy)",
            std_ratio > 1,
        ),
        CLAIM_KINDS.claim(
            "C4_ordering",
            "mean RMSE_tr does not fall as the priors get worse (Spearman rho of RMSE_occ vs RMSE_tr)",
            "increasing",
            rho,
            ">= 0.5",
            rho >= 0.5,
        ),
        CLAIM_KINDS.claim(
            "C12_priors_worthwhile",
            "conclusion: at realistic prior accuracy the gain over no priors is modest (<= 2.34x)",
            "~1.94x",
            gain_real,
            "between 1 and 2.34",
            bool(np.isfinite(gain_real) and 1 <= gain_real <= 2.34 * (1 + tol)),
        ),
        _relative("rmse_max_open", "RMSE_max without the static occluder", 21.4, rmse_max, 0.15),
    ]


def _variant_claims(w: _Sweep, tol: float) -> list[Claim]:
    """The C4 numbers again with the printed likelihood and with a noisier tracker."""
    _, hard_ratio, _, hard_cross, hard_gain = w.printed
    claims = [
        _relative(
            "C4_gain_perfect_printed",
            "as C4_gain_perfect, with the likelihood exactly as printed (hard zeros, full rectangles)",
            2.34,
            hard_ratio,
            tol,
        ),
        _relative(
            "C4_crossing_printed",
            "as C4_crossing, with the likelihood exactly as printed",
            3.72,
            hard_cross,
            tol,
        ),
        _relative(
            "C4_gain_realistic_printed",
            "as C4_gain_realistic, with the likelihood exactly as printed",
            1.94,
            hard_gain,
            tol,
        ),
    ]
    for cid, paper, ours in (
        ("C4_gain_perfect", 2.34, w.sv.ratio),
        ("C4_crossing", 3.72, w.sv.cross),
        ("C4_gain_realistic", 1.94, w.sv.gain),
    ):
        claims.append(
            _relative(
                f"{cid}_sigma_v_{SIGMA_V_SWEPT:g}",
                f"as {cid}, with a tracker that assumes motion noise sigma_v = {SIGMA_V_SWEPT:g} "
                "(Eq. 5; the paper does not give it, ours elsewhere is the walkers' 0.33)",
                paper,
                ours,
                tol,
            )
        )
    return claims


def _best_claims(best: bp.BestPossible) -> list[Claim]:
    """Diagnostics: each paper number is not below the best possible, and the posterior mean
    has converged (the two large counts agree)."""
    out = [
        possible_claim(
            CLAIM_KINDS,
            f"BP_possible_{p}",
            f"mean RMSE_tr {WITH[p]} (Fig. 7, implied)",
            PAPER_RMSE_TR[p],
            best.best(p),
        )
        for p in WITH
    ]
    out.append(
        possible_claim(
            CLAIM_KINDS,
            "BP_possible_crossing",
            "mean RMSE_tr at the crossing RMSE_tr = RMSE_occ (Gaussian priors); no prior can "
            "beat knowing the occluders, so compared with the perfect-prior best possible",
            PAPER_CROSSING,
            best.best("perfect"),
        )
    )
    return out + bp.converged_claims(CLAIM_KINDS, best, {p: (p, WITH[p]) for p in WITH})


def _report_best(best: bp.BestPossible, runs: int) -> str:
    """Report text: the best-possible rows beside Fig. 7's extremes."""
    nan = float("nan")
    rows: dict[str, dict[str, Any]] = {"paper (implied by Sec. 6.1)": {"particles": ""}}
    for p in WITH:
        rows["paper (implied by Sec. 6.1)"] |= {f"RMSE_tr {p}": PAPER_RMSE_TR[p], f"s.e. {p}": nan}
    for p in WITH:
        for name, (n, mean, se) in best.rows(p).items():
            rows.setdefault(name, {"particles": "" if n is None else str(n)})
            rows[name] |= {f"RMSE_tr {p}": mean, f"s.e. {p}": se}
    table = best_table(rows).rename_axis("estimator").reset_index()
    n1, n2 = best.counts
    return f"""{bp.intro(best, runs)} A paper number more than 3 standard errors below the posterior mean at
L = {n2} is *impossible on the printed model* (claims `BP_possible_*`); `BP_converged_*` check
that L = {n1} and L = {n2} agree. Mean over runs of the per-run RMSE_tr, ± its standard error.

{md(table)}

"""


def _figure(ctx: RunContext, w: _Sweep, size: dict[str, int], runs: int) -> None:
    """Fig. 7: RMSE_tr against RMSE_occ, corrected, printed and noisier-tracker curves."""
    both = pd.concat(
        [
            w.main.table.assign(series="corrected likelihood (floor, shortened rectangles)"),
            w.printed.table.assign(series="likelihood as printed"),
            w.sv.table.assign(series=f"corrected, tracker sigma_v = {SIGMA_V_SWEPT:g}"),
        ]
    )
    curve_plot(
        ctx.figure_path("fig7_rmse_vs_prior_accuracy"),
        both,
        "rmse_occ",
        "series",
        xlabel="RMSE_occ (units)",
        ylabel="RMSE_tr (units)",
        title=f"Fig. 7: N = 4, M = 40, no static occluder, {runs} runs x {size['steps']} steps",
        diagonal=True,
    )


def _show_table(w: _Sweep) -> pd.DataFrame:
    """The sweep as a table: corrected and printed RMSE_occ / RMSE_tr per sigma_psi."""
    show = w.main.table[["label", "rmse_occ", "mean", "std", "runs"]].rename(
        columns={"label": "sigma_psi", "mean": "RMSE_tr mean", "std": "RMSE_tr std"}
    )
    hard_show = w.printed.table.set_index("label")
    show["RMSE_occ printed"] = show["sigma_psi"].map(hard_show["rmse_occ"])
    show["RMSE_tr mean printed"] = show["sigma_psi"].map(hard_show["mean"])
    show["RMSE_tr std printed"] = show["sigma_psi"].map(hard_show["std"])
    return show


def _report_numbers(w: _Sweep, size: dict[str, int], runs: int) -> str:
    """Report text: setup and the paper's numbers beside ours."""
    table, ratio, std_ratio, cross, gain_real = w.main
    hard_table, hard_ratio, hard_std_ratio, hard_cross, hard_gain = w.printed
    perfect, none = table.iloc[0], table.iloc[-1]
    rmse_max = float(w.df["rmse_max"].mean())
    hard_mean = float(hard_table.iloc[0]["mean"])
    show = _show_table(w)
    return f"""
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

"ours (printed)" is the same sweep with the likelihood exactly as printed (p(eta | u) not floored, Eq. 7
rectangles up to the particle); "ours" uses the two corrections (floor {DEFAULTS["floor"]:g}, rectangles ending
{DEFAULTS["exclusion"]:g} D before the particle). Neither correction enters the no-prior likelihood, so the
sigma_psi = inf runs are shared.

| quantity | paper | ours (printed) |
|---|---|---|
| RMSE_tr(no info) / RMSE_tr(perfect) | 2.34 | {fmt(hard_ratio)} |
| RMSE_occ where RMSE_tr = RMSE_occ | 3.72 | {fmt(hard_cross)} |
| RMSE_tr(no info) / crossing | 1.94 | {fmt(hard_gain)} |
| std ratio | 3.4 | {fmt(hard_std_ratio)} |
| RMSE_tr(perfect) (implied) | ~3.1 | {fmt(hard_mean)} |

{md(show)}

![Fig. 7](fig7_rmse_vs_prior_accuracy.png)

"""


def _report_differences(w: _Sweep, runs: int, sweep: tuple[float, ...], tol: float) -> str:
    """Report text: differences from the paper and their causes, with the sigma_v sensitivity."""
    table, ratio = w.main.table, w.main.ratio
    hard_perfect, hard_ratio = w.printed.table.iloc[0], w.printed.ratio
    perfect, none = table.iloc[0], table.iloc[-1]
    hard_mean, hard_std = float(hard_perfect["mean"]), float(hard_perfect["std"])
    hard_hard = w.hard[w.hard["label"] == "0"]
    hard_ignored = float(hard_hard["ignored_steps"].mean())
    hard_reinit = float(hard_hard["reinitialisations"].mean())
    sv_table, sv_curve = w.sv_table, w.sv.table
    sv_ratio, sv_cross, sv_gain = w.sv.ratio, w.sv.cross, w.sv.gain
    return f"""## Differences and their causes

* Absolute RMSEs depend on the reconstructed camera layout and on details the paper leaves open (tracker motion
  noise, initial particles, the Kalman filter of the priors); the ratios are the comparable quantities.
* The crossing is read off the piecewise-linear mean curve; with {len(sweep)} sweep points it is coarse.
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
* What still differs: our trackers reach RMSE_tr {fmt(float(perfect["mean"]))} (perfect) and {fmt(float(none["mean"]))}
  (no information) against the paper's implied ~3.1 and ~7.2. The paper gives neither its camera layout nor
  tracker details beyond Algorithm 1; with our layout (cameras 1, 7, 5, 3 in the corners, each seeing the whole
  room) the object is rarely unobserved for long, and a not-seen report carries no information without priors,
  so the no-prior tracker rarely loses the object. The ratio 2.34 is {"reproduced" if abs(ratio / 2.34 - 1) <= tol else "not reproduced"}
  (ours {fmt(ratio)}, printed likelihood {fmt(hard_ratio)}).
* Intermediate priors doing worse than none: the tracker treats each step's seen/not-seen pattern as new
  evidence, but one real occlusion lasts many steps, so it is counted again and again; the experiment
  `ercan2013-prior-calibration` tests this against calibrated, white-error and constant-velocity priors.
* The std ratio is a ratio of two standard deviations of {runs} runs each and varies a lot between seeds.
* The tracker's motion noise sigma_v of Eq. 5 is "assumed to be known" and its value is not given; ours is the
  walkers' true 0.33, which is what "known" suggests. The gains measure how badly the no-prior tracker does while
  the object is hidden, and that depends on how fast its cloud spreads; a tracker that assumes more motion noise
  shows how strongly (same seeds and worlds; a sensitivity, not a claim that the paper used these values):

{md(sv_table)}

  At sigma_v = {SIGMA_V_SWEPT:g} the whole sweep was rerun (the third curve of the figure): gain {fmt(sv_ratio)} (paper
  2.34), crossing {fmt(sv_cross)} (3.72), realistic gain {fmt(sv_gain)} (1.94); the claims `*_sigma_v_{SIGMA_V_SWEPT:g}`
  above. The paper's implied RMSE_tr ~3.1 / ~7.2 against ours {fmt(float(sv_curve.iloc[0]["mean"]))} /
  {fmt(float(sv_curve.iloc[-1]["mean"]))} at this sigma_v.

{md(sv_curve[["label", "rmse_occ", "mean", "std"]].rename(columns={"label": "sigma_psi", "mean": "RMSE_tr mean", "std": "RMSE_tr std"}))}

* Why intermediate priors can do worse than none, and what kind of prior avoids it: see the experiment
  `ercan2013-prior-calibration` (the same setting with calibrated, constant-velocity and white-error priors).
"""


def run(ctx: RunContext) -> Outcome:
    """E2: scenario, estimation, claims, Fig. 7 and report text."""
    size = sizes(ctx)
    runs = ctx.n_runs(full=5, quick=2)
    sweep = SIGMA_PSI_QUICK if ctx.quick else SIGMA_PSI_FULL
    w = _estimate(ctx, size, runs)
    tol = 0.5 if ctx.quick else 0.25
    claims = [*_main_claims(w, tol), *_variant_claims(w, tol), *_best_claims(w.best)]
    _figure(ctx, w, size, runs)
    report = (
        _report_numbers(w, size, runs)
        + _report_best(w.best, runs)
        + _report_differences(w, runs, sweep, tol)
    )
    sv_table = w.sv_table
    gains = dict(
        zip(sv_table["tracker sigma_v"], sv_table["none / perfect (paper 2.34)"], strict=True)
    )
    return Outcome(
        w.results,
        claims,
        report,
        runs=runs,
        beyond_the_paper={
            "gain_perfect_by_tracker_sigma_v": {f"{k:g}": v for k, v in gains.items()}
        },
    )
