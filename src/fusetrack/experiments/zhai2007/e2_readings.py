"""Zhai 2007 E2 (Figs 10-11) under what the thesis does not print (issue 19, item 4).

E2 leaves the sampling period ``T`` unprinted (the spec chose 1) and prints ``Q = 0.05 I`` and
``sigma_n^2 = 0.01``; the filters' prior is a spec choice. Each reading changes one of them and
reruns the paper's filters (EKF, bootstrap and PF-SP-PEKF with 200 particles) with the posterior
mean (:mod:`.best_possible`) beside them. The last reading is the thesis's own mechanism for its
proposals: a narrow bearing (DOA) noise under a wide prior, where the bootstrap's particles,
drawn blind to the measurement, rarely land near it and a measurement-informed proposal should
win. Along the readings: does PF-SP-PEKF beat the bootstrap at equal particles (the thesis's
central claim), and does Fig 10's ordering PF-SP-PEKF < bootstrap < EKF hold?
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from ...evaluation import Claim, RunContext
from ...filters import ExtendedKalmanFilter, ProposalParticleFilter
from ...motion import ConstantVelocity
from . import bearings as e2
from . import best_possible as bp
from .common import timed_gaussian, timed_sis

P0 = np.diag([1.0, 1.0, 0.1, 0.1])
READINGS: dict[str, dict[str, Any]] = {
    "printed": {},
    "T=0.25": {"dt": 0.25},
    "Q=0.005": {"q": 0.005},
    "Q=0.5": {"q": 0.5},
    "sigma_n^2=0.001": {"sigma": float(np.sqrt(0.001))},
    "sigma_n^2=0.0001": {"sigma": 0.01},
    "narrow DOA, wide prior": {"sigma": 0.01, "p0_scale": 25.0},
}
"""Each reading's changes to E2 (``p0_scale`` multiplies the spec's ``P_0``)."""
QUICK_READINGS = ("T=0.25", "narrow DOA, wide prior")
METHODS = ("EKF", "bootstrap", "PF-SP-PEKF", e2.POSTERIOR_MEAN)
LATE = 30
"""Fig 10's claim is about the error after this step."""


def readings(quick: bool) -> dict[str, dict[str, Any]]:
    """The readings this run covers: all, or :data:`QUICK_READINGS` with ``--quick``."""
    return {k: v for k, v in READINGS.items() if not quick or k in QUICK_READINGS}


def setting(changes: Mapping[str, Any]) -> dict[str, Any]:
    """E2's scenario with a reading's ``changes``."""
    scn = {**e2.scenario("E2"), **{k: v for k, v in changes.items() if k != "p0_scale"}}
    scn["p0"] = float(changes.get("p0_scale", 1.0)) * P0
    return scn


def run_reading(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    """One run of E2 under ``config["changes"]``: each method's mean squared position error
    over the steps after :data:`LATE` (one row per method)."""
    scn = setting(config["changes"])
    cs = e2.scenario_of(scn, seed)
    est = {
        "EKF": timed_gaussian(
            ExtendedKalmanFilter(cs.motion, cs.sensors), cs.prior, cs.zs, ["radar"], cs.dt
        )[0]
    }
    pfs = {
        "bootstrap": ProposalParticleFilter(cs.motion, cs.sensors, n_particles=200),
        "PF-SP-PEKF": e2.sp_pekf(cs, 200),
    }
    for k, (name, f) in enumerate(pfs.items()):
        est[name] = timed_sis(f, cs.prior, cs.zs, cs.dt, np.random.default_rng([seed, k]))[0]
    model = ConstantVelocity(q=scn["q"], noise="discrete")
    rng = np.random.default_rng([seed, 1000])
    n = int(config["n_best"])
    est[e2.POSTERIOR_MEAN] = bp.posterior_mean(model, cs.sensors, cs.prior, cs.zs, cs.dt, n, rng)[0]
    rows = []
    for name, e in est.items():
        err2 = np.sum((e[:, :2] - cs.truth[:, :2]) ** 2, axis=1)
        err2 = np.where(np.isfinite(err2), err2, 1e18)
        rows.append({"method": name, "late_mse": float(np.mean(err2[LATE:]))})
    return rows


def run_readings(ctx: RunContext, runs: int) -> pd.DataFrame:
    n_best = bp.best_n(ctx.quick)
    configs = [
        {"reading": name, "changes": changes, "n_best": n_best}
        for name, changes in readings(ctx.quick).items()
    ]
    return ctx.monte_carlo(run_reading, configs, runs, desc="readings")


def verdicts(df: pd.DataFrame) -> pd.DataFrame:
    """Per reading: each method's position RMSE after step :data:`LATE` (root of the mean over
    runs and steps) and the verdicts on the central claims."""
    rmse = df.groupby(["reading", "method"], sort=False)["late_mse"].mean().pow(0.5).unstack()
    rmse = rmse[list(METHODS)]
    out = rmse.copy()
    out["PF-SP-PEKF < bootstrap"] = rmse["PF-SP-PEKF"] < rmse["bootstrap"]
    out["PF-SP-PEKF < bootstrap < EKF (Fig 10)"] = (rmse["PF-SP-PEKF"] < rmse["bootstrap"]) & (
        rmse["bootstrap"] < rmse["EKF"]
    )
    return out


def claims(v: pd.DataFrame) -> list[Claim]:
    """Per reading: PF-SP-PEKF beats the bootstrap at equal particles, and Fig 10's order."""
    out = []
    for r, row in v.iterrows():
        key = str(r).replace(" ", "").replace(",", "_")
        sp, bs, ekf = (float(row[m]) for m in ("PF-SP-PEKF", "bootstrap", "EKF"))
        out.append(
            e2.CLAIM_KINDS.claim(
                f"R_{key}_proposal_beats_bootstrap",
                f"reading '{r}': PF-SP-PEKF(200) < bootstrap(200) in position RMSE after t = {LATE}",
                "PF-SP-PEKF < bootstrap (Fig 10)",
                f"PF-SP-PEKF {sp:.3g} vs bootstrap {bs:.3g} (posterior mean {row[e2.POSTERIOR_MEAN]:.3g})",
                "strict",
                sp < bs,
            )
        )
        out.append(
            e2.CLAIM_KINDS.claim(
                f"R_{key}_C4_order",
                f"reading '{r}': PF-SP-PEKF < bootstrap < EKF after t = {LATE} (Fig 10)",
                "PF-SP-PEKF < bootstrap < EKF",
                f"{sp:.3g} / {bs:.3g} / {ekf:.3g}",
                "strict",
                sp < bs < ekf,
            )
        )
    return out


def section(v: pd.DataFrame, runs: int, quick: bool) -> str:
    """The report's section on the readings."""
    wins = [str(r) for r, row in v.iterrows() if row["PF-SP-PEKF < bootstrap"]]
    order = [str(r) for r, row in v.iterrows() if row["PF-SP-PEKF < bootstrap < EKF (Fig 10)"]]
    left_out = f" (--quick: only {', '.join(QUICK_READINGS)})" if quick else ""
    return f"""
## E2 under what the thesis does not print (issue 19)

E2 with one quantity changed per row{left_out}, {runs} runs each: the sampling period T (never
printed; the spec chose 1), the process noise Q and the bearing variance sigma_n^2 (printed 0.05
and 0.01), and the thesis's own mechanism for its proposals, a narrow bearing under a wide prior
(sigma_n^2 = 1e-4, P_0 x 25). Position RMSE after t = {LATE} (root of the mean over runs and
steps), bootstrap and PF-SP-PEKF with 200 particles, the posterior mean with {bp.BEST_N["full"]}
({bp.BEST_N["quick"]} with --quick):

{v.to_markdown(floatfmt=".3g")}

* Readings where PF-SP-PEKF beats the bootstrap at equal particles: {", ".join(wins) if wins else "none"}.
* Readings where Fig 10's ordering holds: {", ".join(order) if order else "none"}.
"""


__all__ = ["READINGS", "claims", "readings", "run_readings", "section", "verdicts"]
