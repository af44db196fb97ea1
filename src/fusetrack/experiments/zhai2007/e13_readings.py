"""Zhai 2007 E13 (Table 9) under what the thesis does not print (issue 19, item 4).

Table 9's example 1 leaves the sampling period ``T`` unprinted (the spec chose 1) and prints
``Q = 0.05 I`` and ``sigma_n^2 = 0.01``; the filters' prior is a spec choice. Each reading here
changes one of them and reruns the paper's filters (bootstrap 200 and 2000, the Galerkin PF with
200 particles) with the best possible beside them (:mod:`.best_possible`: the posterior mean,
the PCRB, the prior mean carried forward). The last reading is the thesis's own mechanism for
its proposals: a narrow bearing (DOA) noise under a wide prior, where the bootstrap's particles,
drawn blind to the measurement, rarely land near it.

Along the readings: does the Galerkin PF beat bootstrap(2000) (claim C12) and bootstrap(200) at
equal particles, do the bootstrap levels reach Table 9's order, and is Table 9's Galerkin row
possible (not below the posterior mean)?
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, replace
from typing import Any

import numpy as np
import pandas as pd

from ...evaluation import Claim, RunContext
from ...filters import ProposalParticleFilter
from . import best_possible as bp
from . import galerkin as e13
from .common import timed_sis

READINGS: dict[str, e13.Setting] = {
    "T=0.5": e13.Setting(dt=0.5),
    "T=0.3": e13.Setting(dt=0.3),
    "T=0.25": e13.Setting(dt=0.25),
    "T=0.1": e13.Setting(dt=0.1),
    "Q=0.005": e13.Setting(q=0.005),
    "Q=0.5": e13.Setting(q=0.5),
    "sigma_n^2=0.001": e13.Setting(sigma2=0.001),
    "sigma_n^2=0.0001": e13.Setting(sigma2=0.0001),
    "narrow DOA, wide prior": e13.Setting(sigma2=0.0001, p0_scale=25.0),
}
"""Each reading changes one unprinted (or printed) quantity of example 1 (the last two)."""
QUICK_STEPS = 30
QUICK_READINGS = ("narrow DOA, wide prior",)
"""With ``--quick`` only these readings run (:data:`QUICK_STEPS` steps each), to keep it cheap."""
METHODS = ("bootstrap 200", "bootstrap 2000", "Galerkin PF 200")
LEVEL_BAND = (0.5, 2.0)
"""'Same order as Table 9': our bootstrap(2000) within this factor of the paper's."""


def readings(quick: bool) -> dict[str, e13.Setting]:
    """The readings this run covers: all, or :data:`QUICK_READINGS` with ``--quick``."""
    return {k: v for k, v in READINGS.items() if not quick or k in QUICK_READINGS}


def run_reading(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    """One run of example 1 under ``config["setting"]``: the paper's filters, the posterior
    mean and the prior carried forward; one row per method with the per-run RMSE in x and y."""
    setting = e13.Setting(**config["setting"])
    cs = e13.comparator_scenario(1, seed, setting)
    pfs = {
        "bootstrap 200": ProposalParticleFilter(cs.motion, cs.sensors, n_particles=200),
        "bootstrap 2000": ProposalParticleFilter(cs.motion, cs.sensors, n_particles=2000),
        "Galerkin PF 200": e13.galerkin_pf(cs),
    }
    est = {}
    for k, (name, f) in enumerate(pfs.items()):
        est[name] = timed_sis(f, cs.prior, cs.zs, cs.dt, np.random.default_rng([seed, k]))[0]
    rng = np.random.default_rng([seed, 1000])
    model = e13.truth_model(setting)
    n = int(config["n_best"])
    est[e13.POSTERIOR_MEAN] = bp.posterior_mean(model, cs.sensors, cs.prior, cs.zs, cs.dt, n, rng)[
        0
    ]
    est[e13.DEAD_RECKONING] = e13.dead_reckoning(cs)
    rows = []
    for name, e in est.items():
        d = np.where(np.isfinite(e[:, :2]), e[:, :2], 1e9) - cs.truth[:, :2]
        rmse = np.sqrt(np.mean(d**2, axis=0))
        rows.append({"method": name, "e_x": float(rmse[0]), "e_y": float(rmse[1])})
    return rows


def pcrb(setting: e13.Setting, seed: int, n_truths: int) -> tuple[float, float]:
    """The PCRB on the RMS over runs of the per-run RMSE in x and in y under ``setting``
    (truths from Eq. 34 with ``x_0 ~ N(X_1, P_0)``; rank-2 noise regularised by 1e-6 q)."""
    model = e13.truth_model(setting)
    rng = np.random.default_rng([seed, 19])
    x0 = rng.multivariate_normal(e13.x0(1), setting.p0, size=n_truths)
    x = bp.simulate_many(lambda x, r: model.sample(x, setting.dt, r), x0, setting.steps, rng)
    reg = bp.Regularised(model, 1e-6 * setting.q)
    per_axis = [
        bp.pcrb_rms(reg, [setting.bearing()], x, setting.dt, setting.p0, [i]) for i in (0, 1)
    ]
    return float(np.sqrt(np.mean(per_axis[0] ** 2))), float(np.sqrt(np.mean(per_axis[1] ** 2)))


def run_readings(ctx: RunContext, runs: int) -> pd.DataFrame:
    """Every reading's runs (``QUICK_STEPS`` steps with ``--quick``), one frame."""
    n_best = bp.best_n(ctx.quick)
    steps = QUICK_STEPS if ctx.quick else e13.PRINTED.steps
    configs = [
        {"reading": name, "setting": asdict(replace(s, steps=steps)), "n_best": n_best}
        for name, s in readings(ctx.quick).items()
    ]
    return ctx.monte_carlo(run_reading, configs, runs, desc="readings")


def summarise(df: pd.DataFrame, printed: pd.DataFrame) -> dict[str, dict[str, Any]]:
    """Per reading (the printed one from the main runs ``printed``): RMS over runs of the
    per-run RMSE in x and y per method, with the posterior mean's standard errors."""
    out: dict[str, dict[str, Any]] = {}
    frames = {"printed": printed, **{r: d for r, d in df.groupby("reading", sort=False)}}
    for reading, d in frames.items():
        g = {m: dm for m, dm in d.groupby("method")}
        out[reading] = {
            m: {ax: bp.rms_over_runs(g[m][f"e_{ax}"]) for ax in "xy"}
            for m in (*METHODS, e13.POSTERIOR_MEAN, e13.DEAD_RECKONING)
        }
    return out


def verdicts(
    table: Mapping[str, Mapping[str, Any]], bounds: Mapping[str, tuple[float, float]]
) -> pd.DataFrame:
    """Each reading's verdict on Table 9's central claims (rows: readings)."""
    paper = {
        ax: bp.paper_rms(
            e13.PAPER.loc["Galerkin PF 200", f"mean e_{ax}"],
            e13.PAPER.loc["Galerkin PF 200", f"var e_{ax}"],
        )
        for ax in "xy"
    }
    b2000_paper = {
        ax: bp.paper_rms(
            e13.PAPER.loc["bootstrap 2000", f"mean e_{ax}"],
            e13.PAPER.loc["bootstrap 2000", f"var e_{ax}"],
        )
        for ax in "xy"
    }
    rows = {}
    for r, t in table.items():
        val = {m: {ax: t[m][ax][0] for ax in "xy"} for m in t}
        best = t[e13.POSTERIOR_MEAN]
        ratio = max(val["bootstrap 2000"][ax] / b2000_paper[ax] for ax in "xy")
        rows[r] = {
            "Galerkin < BS2000 (C12)": all(
                val["Galerkin PF 200"][a] < val["bootstrap 2000"][a] for a in "xy"
            ),
            "Galerkin < BS200": all(
                val["Galerkin PF 200"][a] < val["bootstrap 200"][a] for a in "xy"
            ),
            "BS2000 / Table 9 (worse axis)": ratio,
            "BS2000 at Table 9's order": LEVEL_BAND[0] <= ratio <= LEVEL_BAND[1],
            "Table 9 Galerkin row": "possible"
            if all(
                bp.verdict(paper[a], best[a][0], best[a][1], bounds[r][i]) == bp.POSSIBLE
                for i, a in enumerate("xy")
            )
            else bp.IMPOSSIBLE,
            "posterior mean x / y": f"{best['x'][0]:.3g} / {best['y'][0]:.3g}",
            "Galerkin x / y": f"{val['Galerkin PF 200']['x']:.3g} / {val['Galerkin PF 200']['y']:.3g}",
            "BS200 x / y": f"{val['bootstrap 200']['x']:.3g} / {val['bootstrap 200']['y']:.3g}",
            "BS2000 x / y": f"{val['bootstrap 2000']['x']:.3g} / {val['bootstrap 2000']['y']:.3g}",
            "PCRB x / y": f"{bounds[r][0]:.3g} / {bounds[r][1]:.3g}",
        }
    return pd.DataFrame.from_dict(rows, orient="index")


def claims(v: pd.DataFrame) -> list[Claim]:
    """Per reading: C12 (Galerkin < bootstrap 2000), Galerkin < bootstrap 200 (equal particles,
    the thesis's central claim) and Table 9's Galerkin row possible."""
    out = []
    for r, row in v.iterrows():
        key = str(r).replace(" ", "").replace(",", "_")
        out.append(
            e13.CLAIM_KINDS.claim(
                f"R_{key}_C12",
                f"reading '{r}': Galerkin PF(200) < bootstrap(2000) in x and y (Table 9's claim)",
                "1.14/1.16 < 3.62/3.65",
                f"Galerkin {row['Galerkin x / y']} vs bootstrap 2000 {row['BS2000 x / y']}",
                "both axes",
                bool(row["Galerkin < BS2000 (C12)"]),
            )
        )
        out.append(
            e13.CLAIM_KINDS.claim(
                f"R_{key}_proposal_beats_bootstrap",
                f"reading '{r}': Galerkin PF(200) < bootstrap(200) in x and y (equal particles)",
                "Galerkin PF < bootstrap (Sec. 4.2)",
                f"Galerkin {row['Galerkin x / y']} vs bootstrap 200 {row['BS200 x / y']}",
                "both axes",
                bool(row["Galerkin < BS200"]),
            )
        )
        out.append(
            e13.CLAIM_KINDS.claim(
                f"R_{key}_possible",
                f"reading '{r}': Table 9's Galerkin row is not below the best possible",
                "1.16 / 1.18 (RMS over runs)",
                f"posterior mean {row['posterior mean x / y']}, PCRB {row['PCRB x / y']}: "
                f"{row['Table 9 Galerkin row']}",
                f"paper >= posterior mean - {bp.MARGIN_SE:g} s.e. and >= PCRB",
                row["Table 9 Galerkin row"] == bp.POSSIBLE,
            )
        )
    return out


def section(v: pd.DataFrame, runs: int, quick: bool) -> str:
    """The report's section: the verdict along the readings and where the paper's result
    comes out."""
    come_out = [
        str(r)
        for r, row in v.iterrows()
        if row["Galerkin < BS2000 (C12)"]
        and row["Table 9 Galerkin row"] == bp.POSSIBLE
        and row["BS2000 at Table 9's order"]
    ]
    order = [str(r) for r, row in v.iterrows() if row["BS2000 at Table 9's order"]]
    steps = QUICK_STEPS if quick else e13.PRINTED.steps
    narrow = v.loc["narrow DOA, wide prior"]
    left_out = "" if not quick else " (--quick: only " + ", ".join(QUICK_READINGS) + ")"
    return f"""
## Readings of what Table 9 does not print (issue 19)

Example 1 with one quantity changed per row{left_out} ({runs} runs each, {steps} steps; the row "printed" is
the main runs above): the sampling period T (never printed), the process noise Q and the bearing
variance sigma_n^2 (printed 0.05 and 0.01), and the thesis's own mechanism for its proposals,
a narrow bearing under a wide prior (sigma_n^2 = 1e-4, P_0 x 25), where bootstrap particles drawn
blind to the bearing rarely land near it. Values are the RMS over runs of the per-run RMSE (x / y);
"BS2000 / Table 9" is ours over the paper's ({LEVEL_BAND[0]:g}-{LEVEL_BAND[1]:g}: the same order);
"Table 9 Galerkin row" compares the paper's 1.16 / 1.18 with the posterior mean (minus
{bp.MARGIN_SE:g} s.e.) and the PCRB of that reading.

{v.to_markdown(floatfmt=".3g")}

* Readings where the bootstrap levels reach Table 9's order: {", ".join(order) if order else "none"}.
* Readings where the paper's result comes out (the Galerkin PF beats bootstrap(2000), Table 9's
  Galerkin level is possible and the bootstrap is at Table 9's order): {", ".join(come_out) if come_out else "none"}.
* Narrow DOA under a wide prior: Galerkin {narrow["Galerkin x / y"]} against bootstrap(200)
  {narrow["BS200 x / y"]} and bootstrap(2000) {narrow["BS2000 x / y"]} (posterior mean
  {narrow["posterior mean x / y"]}): the proposal {"beats" if narrow["Galerkin < BS200"] else "does not beat"}
  the bootstrap at equal particles.
"""


__all__ = [
    "READINGS",
    "claims",
    "pcrb",
    "readings",
    "run_readings",
    "section",
    "summarise",
    "verdicts",
]
