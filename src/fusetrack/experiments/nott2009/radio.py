"""Nott (2009), Sec. 5.2 / Table 5.1 / Fig. 5.5: the radio tag's accuracy at six test points
(spec claim H7), and a simulated NFER tag whose errors match it.

Table 5.1 is the only table of numbers in the thesis. We recompute its summary exactly, then
draw the same experiment from :class:`~fusetrack.sensors.NferTagSimulator`'s realistic model
(spatially correlated bias + white noise + 0.098 m quantisation): one building (bias field) per
run, 32 calibration points along a 16 m hallway and the six test points, and compare the error
distribution with the table's. The noise model for the filter is estimated the corrected way
(sample covariance of calibration residuals; the thesis "averaged" them, which gives a bias).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from ...evaluation import (
    MARGIN_SE,
    Claim,
    ClaimKinds,
    Outcome,
    RunContext,
    expected_norm,
    plots,
    possible_claim,
    rms_over_runs,
)
from ...sensors import NferTagSimulator, fit_position_fix
from .radio_bound import known_field_crlb, reading_mmse

POINTS = ("A", "B", "C", "D", "E", "F")
TABLE_5_1_TRUTH = np.array(
    [
        [6.456, 2.653],
        [7.144, 5.150],
        [6.587, 6.897],
        [8.029, 9.550],
        [2.982, 11.953],
        [7.013, 11.797],
    ]
)
TABLE_5_1_RFID = np.array(
    [
        [7.013, 2.840],
        [7.013, 4.837],
        [7.013, 6.710],
        [7.111, 9.488],
        [3.277, 11.891],
        [7.111, 11.891],
    ]
)
TABLE_5_1_ERROR = np.array([0.588, 0.339, 0.465, 0.920, 0.301, 0.136])
ROUNDING = 0.01
"""The simulated tag's mean-square error may exceed the one-reading MMSE by this fraction: its
0.098 m rounding adds ``q²/12`` per axis (0.3 %), and a building's 256-feature bias field has the
Gaussian field's variance only on average."""


def tag_model(seed: int) -> NferTagSimulator:
    """The simulated NFER tag of one building (the field drawn from ``seed``)."""
    return NferTagSimulator("field", sigma=(0.1, 0.1), quantum=0.098, field_seed=seed)


def calibration_points() -> np.ndarray:
    """32 calibration points: two rows of 16 along a 16 m hallway (Fig. 5.5's layout, approximated)."""
    y = np.linspace(1.0, 16.0, 16)
    return np.vstack(
        [np.column_stack([np.full(16, 6.6), y]), np.column_stack([np.full(16, 7.6), y])]
    )


def table_summary() -> dict[str, Any]:
    """Table 5.1's errors, mean, standard deviations and residual bias / covariance."""
    e = TABLE_5_1_RFID - TABLE_5_1_TRUTH
    err = np.linalg.norm(e, axis=1)
    fit = fit_position_fix(TABLE_5_1_TRUTH, TABLE_5_1_RFID)
    return {
        "errors": err,
        "mean": float(err.mean()),
        "std_sample": float(err.std(ddof=1)),
        "std_population": float(err.std()),
        "bias": fit.bias,
        "cov": fit.cov,
        "axis_std": np.sqrt(np.diag(fit.cov)),
    }


def run_once(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    """One building: the test points' errors and the calibration fit."""
    rng = np.random.default_rng(seed)
    sim = tag_model(seed)
    samples = int(config.get("samples_per_point", 5))
    cal = calibration_points()
    cal_truth = np.repeat(cal, samples, axis=0)
    fit = fit_position_fix(cal_truth, sim.simulate(cal_truth, rng))
    z = sim.simulate(TABLE_5_1_TRUTH, rng)
    err = np.linalg.norm(z - TABLE_5_1_TRUTH, axis=1)
    crlb = known_field_crlb(sim.bias, sim.sigma, TABLE_5_1_TRUTH)  # this building surveyed
    rows = []
    for name, e, zz, B in zip(POINTS, err, z, crlb):
        rows.append(
            {
                "point": name,
                "err": float(e),
                "z_x": float(zz[0]),
                "z_y": float(zz[1]),
                "cal_std_x": float(np.sqrt(fit.cov[0, 0])),
                "cal_std_y": float(np.sqrt(fit.cov[1, 1])),
                "cal_bias_norm": float(np.linalg.norm(fit.bias)),
                "cal_mean_err": fit.mean_error,
                "crlb_ms": float(np.trace(B)),
                "crlb_mean_err": float(expected_norm(B)),
            }
        )
    return rows


# Each claim's kind (fusetrack.evaluation.KINDS), by id or fnmatch pattern, first match.
CLAIM_KINDS = ClaimKinds(
    {
        "H7-sim-*": "calibration",  # the simulated tag is tuned to Table 5.1
        "BP_*": "diagnostic",  # the best possible (issue 19): one-reading MMSE, surveyed CRLB
    }
)


def _best(df: pd.DataFrame) -> dict[str, Any]:
    """The best possible beside Table 5.1 (:mod:`.radio_bound`): our RMS over buildings (± s.e.),
    the one-reading MMSE's RMS and mean error, the surveyed building's CRLB (RMS and mean-error,
    over buildings and points) and per point."""
    mmse = reading_mmse(tag_model(0))  # the same for every building
    per_run = df.groupby("run")["err"].apply(lambda e: float(np.sqrt(np.mean(e**2))))
    by_point = df.groupby("point").agg(
        rms=("err", lambda e: float(np.sqrt(np.mean(e**2)))),
        crlb_rms=("crlb_ms", lambda v: float(np.sqrt(np.mean(v)))),
        crlb_mean=("crlb_mean_err", "mean"),
    )
    return {
        "ours": rms_over_runs(per_run),
        "mmse_rms": float(np.sqrt(np.trace(mmse))),
        "mmse_mean": float(expected_norm(mmse)),
        "crlb_rms": float(np.sqrt(df["crlb_ms"].mean())),
        "crlb_mean": float(df["crlb_mean_err"].mean()),
        "by_point": by_point.reindex(list(POINTS)),
    }


def _best_claims(best: dict[str, Any], paper_se: float) -> list[Claim]:
    """The simulated tag attains the one-reading MMSE (the reading is the posterior mean; a bound
    set too high or too low fails), and Table 5.1's mean error is not below it (margin: the
    table's own s.e., six points) nor below the surveyed building's CRLB."""
    (rms, se), bound = best["ours"], best["mmse_rms"]
    se = float(np.nan_to_num(se))  # one building: no s.e.
    ratio = rms / bound
    lo, hi = 1 - MARGIN_SE * se / bound, 1 + ROUNDING + MARGIN_SE * se / bound
    return [
        CLAIM_KINDS.claim(
            "BP_tag_attains_reading_mmse",
            "the simulated tag's RMS error over buildings equals the one-reading MMSE "
            "(diag(bias_std² + sigma²): its reading is the posterior mean); ours: RMS / bound",
            "not in the paper",
            round(ratio, 4),
            f"1 - {MARGIN_SE:g} s.e. <= ratio <= 1 + {ROUNDING:g} + {MARGIN_SE:g} s.e. "
            f"({lo:.3f}, {hi:.3f})",
            bool(lo <= ratio <= hi),
        ),
        possible_claim(
            CLAIM_KINDS,
            "BP_table_5_1_mean_possible",
            "Table 5.1's mean error (0.458 m) against the one-reading MMSE's mean error",
            0.458,
            (best["mmse_mean"], paper_se),
            bound=best["crlb_mean"],
            best_label="one-reading MMSE (± Table 5.1's s.e.)",
            bound_label="CRLB",
        ),
    ]


def _claims(df: pd.DataFrame, tol: float) -> list[Claim]:
    """H7: the simulated tag's error statistics against Table 5.1 (the tag is tuned to them).
    Not claims, as they hold by construction: Table 5.1's mean and std recomputed from its own
    typed points (the report shows them), and x dominating y in the calibration fit, which
    follows from the simulator's bias setting."""
    sim_mean = float(df["err"].mean())
    sim_std = float(df["err"].std(ddof=1))
    return [
        CLAIM_KINDS.claim(
            "H7-sim-mean",
            "simulated NFER tag (correlated bias + white + quantisation): mean test-point error (m)",
            0.458,
            sim_mean,
            tol,
            abs(sim_mean - 0.458) < tol,
        ),
        CLAIM_KINDS.claim(
            "H7-sim-std",
            "simulated NFER tag: standard deviation of the test-point errors (m)",
            0.273,
            sim_std,
            tol,
            abs(sim_std - 0.273) < tol,
        ),
    ]


def _figure(ctx: RunContext, tab: dict[str, Any], df: pd.DataFrame, runs: int) -> str:
    """Fig. 5.5 / Table 5.1: test points and simulated readings; error histogram; file name."""
    fig, axes = plots.panels(2, size=(11, 4.2))
    ax = axes[0]
    ax.plot(*TABLE_5_1_TRUTH.T, "ko", label="ground truth")
    ax.plot(*TABLE_5_1_RFID.T, "rx", label="RFID (Table 5.1)")
    run0 = df[df["run"] == 0]
    ax.plot(run0["z_x"], run0["z_y"], "b+", label="simulated tag, run 0")
    cal_pts = calibration_points()
    ax.plot(*cal_pts.T, ".", color="0.6", ms=4, label="calibration points (32)")
    for n, p in zip(POINTS, TABLE_5_1_TRUTH):
        ax.annotate(n, p, textcoords="offset points", xytext=(4, 4))
    ax.set_aspect("equal", adjustable="datalim")
    plots.label_axes(ax, title="Fig. 5.5 / Table 5.1: test points")
    plots.legend(ax, fontsize=7, loc="lower right")
    ax = axes[1]
    plots.histogram(ax, df["err"], bins=40, label=f"simulated ({runs} buildings)")
    for k, e in enumerate(tab["errors"]):
        plots.reference_line(ax, e, "Table 5.1 errors" if k == 0 else "", axis="x", color="r",
                             linestyle="-")  # fmt: skip
    plots.label_axes(ax, "test-point error (m)", "density (1/m)",
                     "errors: simulated (histogram) vs Table 5.1 (red)")  # fmt: skip
    plots.legend(ax, fontsize=7)
    return plots.save(fig, ctx.figure_path("table_5_1")).name


def _report(tab: dict[str, Any], df: pd.DataFrame, runs: int, fig_name: str) -> str:
    """Report text: Table 5.1 beside ours, differences and their causes."""
    per_run = df.groupby("run")["err"].agg(["mean", lambda s: s.std(ddof=1)])
    per_run.columns = ["mean", "std"]
    sim_mean = float(df["err"].mean())
    sim_std = float(df["err"].std(ddof=1))
    cal = df.groupby("run")[["cal_std_x", "cal_std_y"]].first().mean()
    repeats = float(
        np.mean([len(g) - len(np.unique(np.round(g["z_x"], 6))) for _, g in df.groupby("run")])
    )
    table = pd.DataFrame(
        {
            "ground truth (m)": [f"({a:.3f}, {b:.3f})" for a, b in TABLE_5_1_TRUTH],
            "RFID (m)": [f"({a:.3f}, {b:.3f})" for a, b in TABLE_5_1_RFID],
            "error, thesis (m)": TABLE_5_1_ERROR,
            "error, recomputed (m)": tab["errors"],
            "simulated mean error (m)": df.groupby("point")["err"]
            .mean()
            .reindex(POINTS)
            .to_numpy(),
        },
        index=list(POINTS),
    )
    return f"""
## Table 5.1 beside ours

{table.to_markdown(floatfmt=".4f")}

| statistic | thesis | recomputed from the table | simulated tag ({runs} buildings) |
|---|---|---|---|
| mean error (m) | 0.458 | {tab["mean"]:.4f} | {sim_mean:.4f} |
| std of error (m) | 0.273 | {tab["std_sample"]:.4f} (sample), {tab["std_population"]:.4f} (population) | {sim_std:.4f} |
| per-axis residual std x, y (m) | - | {tab["axis_std"][0]:.3f}, {tab["axis_std"][1]:.3f} | calibration fit {cal.mean() if False else ""}{df.groupby("run")["cal_std_x"].first().mean():.3f}, {df.groupby("run")["cal_std_y"].first().mean():.3f} |
| residual mean (bias) x, y (m) | - | {tab["bias"][0]:+.3f}, {tab["bias"][1]:+.3f} | - |

Sample covariance of the Table 5.1 residuals (the filter's R_z by the corrected Sec. 4.6 method):
{np.array2string(tab["cov"], precision=4)} m^2. Repeated identical x outputs per building in the
simulation (quantisation to 0.098 m): {repeats:.2f} of 6 on average (Table 5.1 repeats 7.013 three
times and 7.111 twice).

![Table 5.1]({fig_name})

## Differences and their causes

* The thesis's 0.273 m is the sample standard deviation (ddof = 1); the population value is
  {tab["std_population"]:.3f} m.
* Table 5.1 has six points, so its own mean and standard deviation are uncertain by about
  0.27/sqrt(6) = 0.11 m; the simulated tag is tuned (bias std 0.50 / 0.17 m, correlation length
  2 m, white 0.1 m, 0.098 m steps) so that its error distribution over many buildings has the
  table's mean and spread, not to reproduce the six individual errors. Across buildings the
  six-point mean varies with standard deviation {per_run["mean"].std():.3f} m.
* The thesis "averaged" calibration residuals to get the measurement noise (Sec. 4.6); an average
  measures a bias, so we use the residuals' sample covariance (and report the bias separately).
"""


def run(ctx: RunContext) -> Outcome:
    """Table 5.1 recomputed and simulated: estimation, claims, figure, report text."""
    runs = ctx.n_runs(full=200, quick=40)
    tab = table_summary()
    df = ctx.monte_carlo(run_once, [{"samples_per_point": 5}], runs)
    tol = 0.06 if ctx.quick else 0.04
    best = _best(df)
    claims = _claims(df, tol) + _best_claims(best, tab["std_sample"] / np.sqrt(len(POINTS)))
    fig_name = _figure(ctx, tab, df, runs)
    body = _report(tab, df, runs, fig_name) + _best_text(best, tab, runs)
    return Outcome(df, claims, body, runs)


def _best_text(best: dict[str, Any], tab: dict[str, Any], runs: int) -> str:
    """The report's best-possible section, beside Table 5.1."""
    pts = best["by_point"]
    table = pd.DataFrame(
        {
            "error, thesis (m)": TABLE_5_1_ERROR,
            "simulated RMS error (m)": pts["rms"].to_numpy(),
            "one-reading MMSE, RMS (m)": best["mmse_rms"],
            "one-reading MMSE, mean error (m)": best["mmse_mean"],
            "surveyed CRLB, RMS (m)": pts["crlb_rms"].to_numpy(),
            "surveyed CRLB, mean error (m)": pts["crlb_mean"].to_numpy(),
        },
        index=list(POINTS),
    )
    rms, se = best["ours"]
    return f"""
## The best possible beside Table 5.1

What no position estimate can beat on the simulated tag (issue 19; `radio_bound`). The tag
reports `z = p + b(p) + w`, rounded to 0.098 m: a building's smooth bias field `b` (std 0.50 /
0.17 m, 2 m correlation), white noise `w` of 0.1 m. Rounding only removes information, so both
bounds, computed without it, stay below.

* **One reading, building unknown**: the field's marginal at any point is N(0, diag(0.50², 0.17²)),
  so with a flat prior over the floor the posterior of `p` is N(z, diag(bias_std² + sigma²)): the
  reading is the posterior mean, and no estimator from one reading does better on average
  (RMS {best["mmse_rms"]:.3f} m, mean error {best["mmse_mean"]:.3f} m). The simulated tag attains it:
  RMS over {runs} buildings {rms:.4f} ± {se:.4f} m (`BP_tag_attains_reading_mmse`, two-sided, so a
  bound set too high or too low fails).
* **The building surveyed**: told the whole field, an estimator still faces the white noise through
  `p -> p + b(p)`, Fisher information `A^T diag(sigma²)^-1 A`, `A = I + db/dp` at the point (mean
  over the {runs} buildings: RMS {best["crlb_rms"]:.3f} m, mean error {best["crlb_mean"]:.3f} m): the
  floor no calibration goes below. The thesis's calibration (32 points) sets the filter's noise
  model and corrects no reading, so its errors sit at the one-reading level.

{table.to_markdown(floatfmt=".3f")}

Table 5.1's mean error, {tab["mean"]:.3f} m, is judged against the one-reading MMSE's mean error
with the table's own standard error ({tab["std_sample"]:.3f} / sqrt 6 m) as the margin, and against
the surveyed floor (`BP_table_5_1_mean_possible`). Its six single errors are one draw each; a
bound on the expected error does not bound a draw (F's 0.136 m is below the one-reading mean error
and above the surveyed floor), so they are not judged.
"""
