"""Why Gaussian occluder priors can lose to no priors (Ercan et al. 2013; beyond the paper).

The paper's Figs. 6-7 put every Gaussian-prior curve between perfect priors and none. Ours does
not: with the random-walk Kalman priors, intermediate priors are often worse than none (E1's C3
ordering, E2's curve). Two causes are possible, and this experiment separates them by how the
priors are made, at the same virtual-reading noise ``sigma_psi``
(:func:`fusetrack.world.occluder_priors.prior_track`):

* ``random-walk``: the filter every other experiment uses; it lags walkers that keep their heading,
  so its priors are overconfident (squared error / claimed variance 1.1-2);
* ``constant-velocity``: a Kalman filter that follows the heading; calibrated (ratio ~1);
* ``calibrated-random-walk`` (oracle): the random walk's track with its covariance scaled until
  the ratio is 1 -- if this fixes the ordering, overconfidence was the cause;
* ``white`` (oracle): the random walk's accuracy and calibration, but fresh errors every step --
  if only this fixes it, the cause is that a prior's error persists over many steps;
* ``random-walk, gamma g``: the default priors with the occlusion evidence tempered,
  ``p(eta | u)^g`` (:class:`~fusetrack.sensors.occlusion_aware_camera.OcclusionAwareLikelihood`).
  A real occluder that hides the object does so for many steps in a row, but Eq. 6 counts
  each step's pattern as new evidence given the current priors; if tempering fixes the ordering,
  the cause is this repeated counting of one event, whatever the priors.

Two settings: E2's (open room, k = 4) and E1's (static occluder, k = 3, where E1's Gaussian priors
lost most). The claims are the paper's ordering (perfect <= Gaussian <= none) per construction.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ...evaluation import Claim, ClaimKinds, Outcome, RunContext
from ...world import PRIOR_FILTERS
from .common import curve_plot, fmt, md, mean_std, sizes
from .simulation import run_tracking

SETTINGS = {"E2": ("square-open", 4), "E1": ("square", 3)}
"""Setting label: (scene, k cameras of the fixed list)."""
SIGMA_PSI_FULL = (2.0, 8.0, 16.0, 32.0)
SIGMA_PSI_QUICK = (8.0, 32.0)
M = 40
ORACLES = ("calibrated-random-walk", "white")
SERIES: dict[str, dict[str, object]] = {
    **{kind: {"prior_filter": kind} for kind in PRIOR_FILTERS},
    **{
        f"random-walk, gamma {g:g}": {"prior_filter": "random-walk", "occlusion_power": g}
        for g in (0.3, 0.1)
    },
}
"""Gaussian-prior series: name -> configuration overrides."""


def _configs(sweep: tuple[float, ...], size: dict[str, int]) -> list[dict]:
    out = []
    for setting, (scene, k) in SETTINGS.items():
        base = {"scene": scene, "n_occluders": M, "k": k, "method": "fixed", **size}
        out.append({**base, "prior": "perfect", "sigma_psi": 0.0, "label": f"{setting}|perfect|0"})
        out.append({**base, "prior": "none", "sigma_psi": 0.0, "label": f"{setting}|none|inf"})
        for name, overrides in SERIES.items():
            for s in sweep:
                out.append(
                    {
                        **base,
                        **overrides,
                        "prior": "gaussian",
                        "sigma_psi": s,
                        "label": f"{setting}|{name}|{s:g}",
                    }
                )
    return out


def _ordering(table: pd.DataFrame, setting: str, kind: str) -> tuple[float, float]:
    """Share of sigma_psi with perfect <= Gaussian <= none (means), and with Gaussian <= none."""
    t = table[table["setting"] == setting]
    perfect = float(t[t["series"] == "perfect"]["mean"].iloc[0])
    none = float(t[t["series"] == "none"]["mean"].iloc[0])
    g = t[t["series"] == kind]["mean"].to_numpy()
    return float(np.mean((perfect <= g) & (g <= none))), float(np.mean(g <= none))


def _estimate(
    ctx: RunContext, sweep: tuple[float, ...], size: dict[str, int], runs: int
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Estimation: every series in both settings; RMSE_tr, RMSE_occ and calibration per point."""
    df = ctx.monte_carlo(run_tracking, _configs(sweep, size), runs, desc="prior calibration")
    parts = df["label"].str.split("|", expand=True)
    df = df.assign(setting=parts[0], series=parts[1], sigma=parts[2])
    table = mean_std(df, ["setting", "series", "sigma"])
    extra = df.groupby(["setting", "series", "sigma"])[["rmse_occ", "prior_nees"]].mean()
    table = table.join(extra, on=["setting", "series", "sigma"])
    return df, table


# Each claim's kind (fusetrack.evaluation.KINDS), by id or fnmatch pattern, first match.
CLAIM_KINDS = ClaimKinds(
    {
        "ordering_*": "diagnostic",  # Figs. 6-7's ordering under our prior models
    }
)


def _claims(table: pd.DataFrame) -> tuple[list[Claim], dict[str, dict[str, float]]]:
    """The paper's ordering per setting and series, and the share of sigma_psi beating none."""
    claims: list[Claim] = []
    verdict: dict[str, dict[str, float]] = {}
    for setting, (scene, k) in SETTINGS.items():
        verdict[setting] = {}
        for kind in SERIES:
            share, beats = _ordering(table, setting, kind)
            verdict[setting][kind] = beats
            oracle = " (oracle)" if kind in ORACLES else ""
            claims.append(
                CLAIM_KINDS.claim(
                    f"ordering_{setting}_{kind.replace(', ', '_').replace(' ', '_')}",
                    f"{setting} setting ({scene}, k = {k}), {kind}{oracle} priors: perfect <= "
                    "Gaussian <= none in mean RMSE_tr (share of sigma_psi)",
                    "all (Figs. 6-7)",
                    share,
                    ">= 0.75",
                    share >= 0.75,
                )
            )
    return claims, verdict


def _figures(ctx: RunContext, table: pd.DataFrame, size: dict[str, int], runs: int) -> list[str]:
    """RMSE_tr against RMSE_occ per setting, perfect and no priors as lines; markdown links."""
    figures = []
    for setting, (scene, k) in SETTINGS.items():
        t = table[table["setting"] == setting]
        refs = {
            row.series: float(row.mean)
            for row in t[t["series"].isin(["perfect", "none"])].itertuples()
        }
        gauss = t[~t["series"].isin(["perfect", "none"])]
        stem = f"rmse_vs_prior_{setting}"
        curve_plot(
            ctx.figure_path(stem),
            gauss,
            "rmse_occ",
            "series",
            xlabel="RMSE_occ (units)",
            ylabel="RMSE_tr (units)",
            title=f"{setting} setting: {scene}, k = {k}, M = {M}, {runs} runs x {size['steps']} steps",
            hlines={f"{name} priors {fmt(v)}": v for name, v in refs.items()},
        )
        figures.append(f"![{setting}]({stem}.png)")
    return figures


def _show_table(table: pd.DataFrame) -> pd.DataFrame:
    """The whole table for the report, sorted by setting, series and RMSE_occ."""
    show = table.assign(sigma_psi=table["sigma"])[
        ["setting", "series", "sigma_psi", "rmse_occ", "prior_nees", "mean", "std"]
    ].rename(
        columns={
            "series": "priors",
            "prior_nees": "sq. error / claimed var",
            "mean": "RMSE_tr mean",
            "std": "RMSE_tr std",
        }
    )
    show = show.sort_values(["setting", "priors", "rmse_occ"])

    return show


def _wins(verdict: dict[str, dict[str, float]], kind: str) -> str:
    """Share of sigma_psi at which ``kind`` priors beat none, per setting."""
    return ", ".join(f"{s}: {verdict[s][kind]:.0%}" for s in SETTINGS)


def _recounting(verdict: dict[str, dict[str, float]]) -> dict[str, bool]:
    """Per tempered series: does it beat none more often than the untempered random walk?"""
    rw = PRIOR_FILTERS[0]
    tempered = [k for k in SERIES if "gamma" in k]
    return {k: all(verdict[s][k] > verdict[s][rw] for s in SETTINGS) for k in tempered}


def _conclusion(
    verdict: dict[str, dict[str, float]], overconfidence: bool, persistence: bool
) -> str:
    """Which cause the series single out, if one does in both settings."""
    recounting = _recounting(verdict)
    tempered = list(recounting)
    if any(recounting.values()) and not (overconfidence or persistence):
        return (
            "how the priors are made does not matter (calibrated, white or constant-velocity priors lose to none "
            "as often as the random walk); counting each step's occlusion pattern as new evidence does: a real "
            "occlusion lasts many steps, and with the evidence tempered the Gaussian priors beat none at "
            f"{_wins(verdict, tempered[-1])} of sigma_psi ({tempered[-1]})."
        )
    return "no single series separates the causes in both settings; see the table."


def _report(
    verdict: dict[str, dict[str, float]],
    show: pd.DataFrame,
    figures: list[str],
    sweep: tuple[float, ...],
    size: dict[str, int],
    runs: int,
) -> str:
    """Report text: the question, setup, results and what they say about the causes."""
    rw, cv, cal, white = PRIOR_FILTERS

    def wins(kind: str) -> str:
        return _wins(verdict, kind)

    overconfidence = all(verdict[s][cal] > verdict[s][rw] for s in SETTINGS)
    persistence = all(verdict[s][white] > verdict[s][cal] for s in SETTINGS)
    recounting = _recounting(verdict)
    conclusion = _conclusion(verdict, overconfidence, persistence)
    return f"""
## Question

Figs. 6-7 of the paper put the Gaussian-prior curves between perfect priors and none; ours (E1, E2) lose to
none at intermediate accuracy. Is it because the random-walk priors are overconfident, because their error
persists over many steps, or because one real occlusion (lasting many steps) is counted as new evidence
every step? Same worlds and seeds for every series; only the priors or the tempering differ.

## Setup

{", ".join(f"{s}: {sc}, k = {k}" for s, (sc, k) in SETTINGS.items())} (first k of the fixed list), M = {M},
sigma_psi {", ".join(f"{s:g}" for s in sweep)}, {runs} runs x {size["steps"]} steps, L = {size["particles"]}, the
corrected likelihood of the other experiments. Series: {", ".join(SERIES)} (see the module; {" and ".join(ORACLES)}
use the truth and exist only for this diagnosis).

## Results

Share of sigma_psi at which the Gaussian priors beat no priors (mean RMSE_tr <= none's):

| priors | {" | ".join(SETTINGS)} |
|---|{"---|" * len(SETTINGS)}
{chr(10).join(f"| {kind} | " + " | ".join(f"{verdict[s][kind]:.0%}" for s in SETTINGS) + " |" for kind in SERIES)}

{md(show)}

{chr(10).join(figures)}

## Differences from the paper and their causes

* Overconfidence (calibrated-random-walk beats none more often than random-walk in both settings):
  {"yes" if overconfidence else "no"} ({wins(rw)} -> {wins(cal)}).
* Persistent errors (white beats none more often than calibrated-random-walk in both settings):
  {"yes" if persistence else "no"} ({wins(cal)} -> {wins(white)}).
* The practical constant-velocity filter (calibrated without the truth): {wins(cv)}.
* One occlusion counted again every step (tempered evidence beats none more often than the untempered
  random walk in both settings): {"; ".join(f"{k}: {'yes' if v else 'no'} ({wins(k)})" for k, v in recounting.items())}.
* Conclusion: {conclusion}
* The paper does not say how its priors were made beyond "a Kalman filter", nor whether its tracker did anything
  about occlusions that last many steps; its Figs. 6-7 ordering is what this experiment gets only where the
  evidence is {"tempered" if any(recounting.values()) else "(not reproduced by any series here)"}.
"""


def run(ctx: RunContext) -> Outcome:
    """Scenario, estimation, claims, figures and report text."""
    size = sizes(ctx)
    runs = ctx.n_runs(full=5, quick=2)
    sweep = SIGMA_PSI_QUICK if ctx.quick else SIGMA_PSI_FULL
    df, table = _estimate(ctx, sweep, size, runs)
    claims, verdict = _claims(table)
    figures = _figures(ctx, table, size, runs)
    report = _report(verdict, _show_table(table), figures, sweep, size, runs)
    return Outcome(df.drop(columns=["setting", "series", "sigma"]), claims, report, runs=runs)
