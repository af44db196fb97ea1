"""Lee 2009, Ch. 2: 3-D acoustic tracking on projected planes (PPS) against the direct 3-D filter.

Parts (spec 000, Sec. 4.9):

* E2.0 -- projected-angle noise variances, Monte Carlo against the closed form (Figs. 2-2, 2-3; C1);
* E2.1 -- weighted against equal combining, with correct models (Table 2.1; C2) and with the yz
  filter on constant velocity during steps 50-99 (Table 2.2; C3);
* E2.2 -- unnormalised weight sums of the selected yz plane against the direct 3-D filter over
  the measurement variance (Fig. 2-7; C4);
* Scenarios 1-4 -- PPS (literal and minimum-variance selection), direct 3-D, and the
  multi-sensor extended PPS, with per-axis RMSE beside the CRLB (Figs. 2-10 ... 2-13; C5, C6).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pandas as pd
from pydantic import Field

from ...evaluation import (
    Claim,
    ClaimKinds,
    ExperimentOptions,
    Outcome,
    RunContext,
    angle_pair_information,
    direct3d_crlb,
    fused_bound,
    interval_values,
    paired_interval,
    plane_crlb,
    plots,
    shown_positive,
)
from ...filters import Direct3DFilter, ProjectedPlanesTracker, select_pairs
from ...motion import AccelTurn
from ...sensors import PLANE_AXES, DoaSensor3D, monte_carlo_projected_variance, projected_variance


class Options(ExperimentOptions):
    """``fusetrack run lee2009-projected-planes`` options."""

    measurements: Literal["gaussian", "audio"] = Field(
        "gaussian",
        description="where the angles come from: gaussian (the dissertation's Ch. 2 noise) or "
        "audio (estimated from simulated sound by MUSIC)",
    )


DEG = math.pi / 180.0
SIGMA = math.sqrt(3.0) * DEG  # variance 3 deg^2 on both angles
AXES = "xyz"

# Table 2.1 / 2.2 (E2.1): x CV, (y, z) turning clockwise with alpha = 0.01 m/s^2, Ts = 1 s, 165 s.
TABLE_X0 = (10.0, 130.0, 18.0, 1.0, -0.75, 0.75)
TABLE_TRUTH = AccelTurn(3, (0.0, 0.0, 0.0), (1, 2), -0.01)
TABLE_STEPS, TABLE_DT = 165, 1.0
MISMATCH = (50, 100)  # the yz filter runs constant velocity over these steps (Table 2.2)

PAPER_T21 = {
    "equal": (1.8267, 0.5673, 1.6134, 1.3358),
    "weighted": (1.7258, 0.5378, 1.6235, 1.2957),
}
PAPER_T22 = {
    "equal": (1.7958, 17.3250, 1.5783, 6.8997),
    "weighted": (1.6459, 0.6243, 1.6431, 1.3044),
}

# Scenarios 1-4: Ts = 0.1 s, 50 instants, CV in x, A_y = 0.1, A_z = 0.5 m/s^2.
SCN_ACCEL = (0.0, 0.1, 0.5)
SCN_DT, SCN_STEPS = 0.1, 50
SCENARIOS = {
    "S1": ((3.0, 3.0, 1.0), (1.0, 1.0, 1.0)),
    "S2": ((1.0, 1.0, 3.0), (1.0, 1.0, 1.0)),
    "S3": ((2.0, 1.0, 2.0), (0.3, 0.3, 0.3)),
    "S4": ((2.0, 1.0, 2.0), (0.3, 0.3, 0.3)),
}
PRIOR_STD = 0.1  # CRLB prior and filter initial uncertainty, per axis (m and m/s)


@dataclass(frozen=True)
class Settings:
    n_particles: int = 1000
    sigma_a_table: float = 0.005  # filter process noise, Ts = 1 s
    sigma_a_scn: float = 0.1  # filter process noise, Ts = 0.1 s


def primary() -> DoaSensor3D:
    return DoaSensor3D("A0", (0.0, 0.0, 0.0), SIGMA)


def second_sensor() -> DoaSensor3D:
    """Scenario 4's sensor at (10, 10, 10) with every axis flipped (object in its positive octant)."""
    return DoaSensor3D("A1", (10.0, 10.0, 10.0), SIGMA, polarity=(-1.0, -1.0, -1.0))


def scenario_truth(name: str) -> np.ndarray:
    p0, v0 = SCENARIOS[name]
    return AccelTurn(3, SCN_ACCEL).trajectory(np.array(p0 + v0), SCN_DT, SCN_STEPS)


def start_state(
    x0: np.ndarray, rng: np.random.Generator, pos_std: float, vel_std: float
) -> np.ndarray:
    """The filters' initial mean: the given state plus a draw of the prior (so the CRLB applies)."""
    std = np.array([pos_std] * 3 + [vel_std] * 3)
    return x0 + std * rng.standard_normal(6)


def _sq_rows(part: str, scenario: str, method: str, est: np.ndarray, truth: np.ndarray) -> list:
    err = est[:, :3] - truth[:, :3]
    return [
        {
            "part": part,
            "scenario": scenario,
            "method": method,
            "step": n,
            "sq_x": float(err[n, 0] ** 2),
            "sq_y": float(err[n, 1] ** 2),
            "sq_z": float(err[n, 2] ** 2),
            "est_x": float(est[n, 0]),
            "est_y": float(est[n, 1]),
            "est_z": float(est[n, 2]),
        }
        for n in range(len(truth))
    ]


def run_table(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    """E2.1: one run of Table 2.1 (``mismatch`` False) or 2.2 (True); equal and weighted share the filters."""
    rng = np.random.default_rng(seed)
    x0 = np.array(TABLE_X0)
    truth = TABLE_TRUTH.trajectory(x0, TABLE_DT, TABLE_STEPS)
    sensor = primary()
    z = sensor.simulate(truth[:, :3], rng)[:, None, :]
    sa = float(config["sigma_a"])
    model = AccelTurn(3, (0.0, 0.0, 0.0), (1, 2), -0.01, sigma_a=sa)
    override = {}
    if config["mismatch"]:
        override["yz"] = (*MISMATCH, AccelTurn(2, (0.0, 0.0), None, 0.0, sa))
    tracker = ProjectedPlanesTracker(
        [sensor],
        model,
        int(config["n_particles"]),
        init_std=(0.1, 0.05),
        plane_model_override=override,
    )
    res = tracker.run(z, TABLE_DT, x0, rng)  # "the initial object state is given"
    case = "table22" if config["mismatch"] else "table21"
    rows = _sq_rows(case, case, "equal", res.equal, truth)
    rows += _sq_rows(case, case, "weighted", res.weighted, truth)
    # The yz filter's own (y, z); on the rare step where noise pushes phi below 45 deg the
    # literal rule selects zx instead and the fused (y, z) stands in.
    yz = np.array(
        [e.get((0, "yz"), res.weighted[n, [1, 2, 4, 5]]) for n, e in enumerate(res.plane_estimates)]
    )
    plane_own = np.column_stack([truth[:, 0], yz[:, 0], yz[:, 1]])
    rows += _sq_rows(case, case, "yz filter alone", plane_own, truth)
    lw = np.array([[w[(0, "xy")], w.get((0, "yz"), np.nan)] for w in res.log_weight_sums])
    for r in rows[-TABLE_STEPS:]:
        r["log_w_xy"], r["log_w_yz"] = lw[r["step"]]
    return rows


def run_weight_sums(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    """E2.2: mean log weight sums of the selected yz plane filter and of the direct 3-D filter (Scenario 1)."""
    rng = np.random.default_rng(seed)
    var_deg2 = float(config["variance_deg2"])
    sensor = DoaSensor3D("A0", (0.0, 0.0, 0.0), math.sqrt(var_deg2) * DEG)
    truth = scenario_truth("S1")
    z = sensor.simulate(truth[:, :3], rng)[:, None, :]
    model = AccelTurn(3, SCN_ACCEL, sigma_a=0.1)
    n = int(config["n_particles"])
    x0 = start_state(truth[0], rng, PRIOR_STD, PRIOR_STD)
    pps = ProjectedPlanesTracker([sensor], model, n, init_std=(PRIOR_STD, PRIOR_STD)).run(
        z, SCN_DT, x0, rng
    )
    d3 = Direct3DFilter(sensor, model, n, init_std=(PRIOR_STD, PRIOR_STD)).run(z, SCN_DT, x0, rng)
    sel = [w[(0, "yz")] for w in pps.log_weight_sums if (0, "yz") in w]
    return [
        {"part": "E2.2", "method": "yz plane (PPS)", "mean_log_w": float(np.mean(sel))},
        {"part": "E2.2", "method": "direct 3-D", "mean_log_w": float(np.mean(d3.log_weight_sums))},
    ]


def run_scenario(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    """Scenarios 1-4: PPS literal / minvar and direct 3-D (S4: extended PPS with two sensors)."""
    rng = np.random.default_rng(seed)
    name = str(config["scenario"])
    truth = scenario_truth(name)
    n = int(config["n_particles"])
    model = AccelTurn(3, SCN_ACCEL, sigma_a=float(config["sigma_a"]))
    sensors = [primary()] + ([second_sensor()] if name == "S4" else [])
    z = np.stack([s.simulate(truth[:, :3], rng) for s in sensors], axis=1)
    # "given": particles around the true initial state (the text); "prior": around a draw of
    # N(truth, P_0), which is what the CRLB with J_0 = P_0^-1 bounds.
    x0 = truth[0] if config["init"] == "given" else start_state(truth[0], rng, PRIOR_STD, PRIOR_STD)
    rows = []
    for sel in ("literal", "minvar"):
        tracker = ProjectedPlanesTracker(
            sensors, model, n, selection=sel, init_std=(PRIOR_STD, PRIOR_STD)
        )
        res = tracker.run(z, SCN_DT, x0, np.random.default_rng([seed, 1]))
        rows += _sq_rows(name, name, f"PPS {sel}", res.weighted, truth)
        for r, pairs in zip(rows[-len(truth) :], res.pairs):
            r["planes"] = " + ".join(f"{p}@A{k}" for k, p in pairs)
    if name != "S4":
        d3 = Direct3DFilter(sensors[0], model, n, init_std=(PRIOR_STD, PRIOR_STD))
        out = d3.run(z, SCN_DT, x0, np.random.default_rng([seed, 2]))
        rows += _sq_rows(name, name, "direct 3-D", out.estimates, truth)
    return rows


def run_once(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    part = config["part"]
    if part == "table":
        return run_table(config, seed)
    if part == "weights":
        return run_weight_sums(config, seed)
    return run_scenario(config, seed)


# ----------------------------------------------------------------------------------------------
# Bounds (deterministic: computed once per scenario)


def prior_sensitivity(priors: tuple[float, ...] = (0.02, 0.05, 0.1, 0.5, 2.0)) -> pd.DataFrame:
    """Time-averaged 3-D CRLB (mean over axes) of S1-S3 for several prior stds (position = velocity)."""
    rows = []
    for name in ("S1", "S2", "S3"):
        truth = scenario_truth(name)
        model = AccelTurn(3, SCN_ACCEL)
        row: dict[str, Any] = {"scenario": name}
        for sd in priors:
            b3 = direct3d_crlb(truth, primary(), model, SCN_DT, sigma_pos=sd, sigma_vel=sd)
            bp = direct3d_crlb(
                truth, primary(), model, SCN_DT, sigma_pos=sd, sigma_vel=sd, transition="printed"
            )
            row[f"3-D, prior {sd}"] = float(b3[:, :3].mean())
            row[f"3-D printed F, prior {sd}"] = float(bp[:, :3].mean())
        rows.append(row)
    return pd.DataFrame(rows).set_index("scenario").T


def scenario_sensors(name: str) -> list[DoaSensor3D]:
    return [primary()] + ([second_sensor()] if name == "S4" else [])


def scenario_bounds(name: str) -> dict[str, np.ndarray]:
    """Always-on plane bounds, switched (literal-selection) plane bounds and the 3-D bound, per axis.

    Keys ``"{axis}|{plane}"`` (``"{axis}|{plane}@A1"`` for the second sensor of S4), with
    ``" switched"`` for the selection-gated bound; ``"{axis}|PPS"`` is the bound of the (extended)
    PPS estimate: the selected pairs holding the axis, fused when two do (Lee 2009, Eqs.
    2.25-2.27 with independent estimates); ``"{axis}|3-D"`` the direct 3-D filter's bound with
    every sensor of the scenario (``"{axis}|3-D A0"``: the primary sensor alone, for S4).
    """
    truth = scenario_truth(name)
    model = AccelTurn(3, SCN_ACCEL)
    sensors = scenario_sensors(name)
    z = np.stack([np.stack(s.angles(truth[:, :3]), axis=-1) for s in sensors], axis=1)  # (T, K, 2)
    selected = {(k, p): np.zeros(len(truth), bool) for k in range(len(sensors)) for p in PLANE_AXES}
    for n in range(len(truth)):
        for pair in select_pairs(z[n], sensors, "literal")[0]:
            selected[pair][n] = True
    out: dict[str, np.ndarray] = {}
    for (k, plane), sel in selected.items():
        tag = plane if k == 0 else f"{plane}@A{k}"
        on = plane_crlb(
            truth, sensors[k], plane, model, SCN_DT, sigma_pos=PRIOR_STD, sigma_vel=PRIOR_STD
        )
        sw = plane_crlb(
            truth,
            sensors[k],
            plane,
            model,
            SCN_DT,
            selected=sel,
            sigma_pos=PRIOR_STD,
            sigma_vel=PRIOR_STD,
        )
        for j, axis in enumerate(PLANE_AXES[plane]):
            out[f"{AXES[axis]}|{tag}"] = on[:, j]
            out[f"{AXES[axis]}|{tag} switched"] = sw[:, j]
    d3 = direct3d_crlb(truth, sensors, model, SCN_DT, sigma_pos=PRIOR_STD, sigma_vel=PRIOR_STD)
    for axis in range(3):
        out[f"{AXES[axis]}|3-D"] = d3[:, axis]
    if len(sensors) > 1:
        d30 = direct3d_crlb(
            truth, sensors[0], model, SCN_DT, sigma_pos=PRIOR_STD, sigma_vel=PRIOR_STD
        )
        for axis in range(3):
            out[f"{AXES[axis]}|3-D A0"] = d30[:, axis]
    pps = np.zeros((len(truth), 3))
    for n in range(len(truth)):
        for axis in range(3):
            vals = [
                out[f"{AXES[axis]}|{p if k == 0 else f'{p}@A{k}'} switched"][n]
                for (k, p), sel in selected.items()
                if sel[n] and axis in PLANE_AXES[p]
            ]
            pps[n, axis] = vals[0] if len(vals) == 1 else fused_bound(vals[0], vals[1])
    for axis in range(3):
        out[f"{AXES[axis]}|PPS"] = pps[:, axis]
    out["selected_yz"] = selected[(0, "yz")]
    return out


# ----------------------------------------------------------------------------------------------
# Report


def _rmse(df: pd.DataFrame, by: list[str]) -> pd.DataFrame:
    g = df.groupby(by)[["sq_x", "sq_y", "sq_z"]].mean().pow(0.5)
    g.columns = ["x", "y", "z"]
    g["average"] = g[["x", "y", "z"]].mean(axis=1)
    return g


# Each claim's kind (fusetrack.evaluation.KINDS), by id or fnmatch pattern, first match.
CLAIM_KINDS = ClaimKinds(
    {
        "C1_closed_form": "diagnostic",  # our closed form against Monte Carlo
        "C5_3d_filter_above_bound": "diagnostic",  # sanity of the bounds
        "C5_no_pps_bound_below_3d": "diagnostic",  # why C5_pps_bound_vs_3d cannot hold
        "C6_s4_above_bound": "diagnostic",
        "C1_*": "paper",
        "C2_*": "paper",
        "C3_*": "paper",
        "C4_*": "paper",
        "C5_*": "paper",
        "C6_*": "paper",
    }
)


def _variance_part(ctx: RunContext) -> tuple[list[Claim], str, pd.DataFrame]:
    rng = np.random.default_rng([ctx.seed, 20])
    n_mc = 20_000 if ctx.quick else 100_000
    thetas = np.arange(0.0, 360.0, 15.0 if ctx.quick else 5.0)
    phis = np.arange(10.0, 171.0, 20.0)
    rows = []
    for ph in phis:
        for th in thetas:
            mc = monte_carlo_projected_variance(th * DEG, ph * DEG, DEG, n_mc, rng) / DEG**2
            cf = projected_variance(th * DEG, ph * DEG)
            rows.append(
                {
                    "part": "E2.0",
                    "theta_deg": th,
                    "phi_deg": ph,
                    "mc_xy": mc[0],
                    "mc_yz": mc[1],
                    "mc_zx": mc[2],
                    "cf_yz": cf[1],
                    "cf_zx": cf[2],
                }
            )
    df = pd.DataFrame(rows)
    finite = (df.cf_yz < 50) & (df.cf_zx < 50)
    rel = np.maximum(
        np.abs(df.mc_yz / df.cf_yz - 1)[finite], np.abs(df.mc_zx / df.cf_zx - 1)[finite]
    )
    # Sampling error of a variance estimate is sqrt(2/n) relative, plus delta-method bias.
    tol_rel = 5 * math.sqrt(2 / n_mc) + 0.02
    xy_dev = float(np.max(np.abs(df.mc_xy - 1)))
    inside = (df.phi_deg > 45) & (df.phi_deg < 135)
    yz_below_inside = int(np.sum((df.cf_yz < 1) & inside))
    yz_below_outside = float(np.mean((df.cf_yz < 1)[~inside]))
    claims = [
        CLAIM_KINDS.claim(
            "C1_closed_form",
            "closed-form projected variances match Monte Carlo of Eq. 2.1 (max relative deviation)",
            "MC only (Figs. 2-2, 2-3)",
            float(rel.max()),
            f"<= {tol_rel:.3f}",
            rel.max() <= tol_rel,
        ),
        CLAIM_KINDS.claim(
            "C1_xy_equal",
            "sigma_xy^2 = sigma^2 (Monte Carlo, max |var_xy/sigma^2 - 1|)",
            "sigma_xy^2 = sigma^2",
            xy_dev,
            f"<= {5 * math.sqrt(2 / n_mc):.3f}",
            xy_dev <= 5 * math.sqrt(2 / n_mc),
        ),
        CLAIM_KINDS.claim(
            "C1_yz_region",
            "grid points with 45 < phi < 135 deg where var_yz < sigma^2 (text: yz smaller there)",
            "yz < sigma^2 for 45 <= phi <= 135",
            yz_below_inside,
            "text's description holds only if > 0",
            yz_below_inside > 0,
        ),
    ]
    fig, axes = plots.panels(2, size=(11, 4))
    for ax, col, name in ((axes[0], "yz", "Fig. 2-2"), (axes[1], "zx", "Fig. 2-3")):
        for i, ph in enumerate(phis[:5]):
            sub = df[df.phi_deg == ph]
            ax.plot(sub.theta_deg, sub[f"mc_{col}"], ".", ms=3, color=f"C{i}",
                    label="Monte Carlo" if i == 0 else None)  # fmt: skip
            plots.curve(ax, sub.theta_deg, sub[f"cf_{col}"], index=i, label=f"phi = {ph:.0f} deg",
                        marker="", lw=1)  # fmt: skip
        plots.reference_line(ax, 1.0, "sigma^2", linestyle="--", lw=0.8)
        ax.set_yscale("log")
        ax.set_ylim(0.1, 100.0)  # the closed form diverges where the plane is edge-on
        plots.label_axes(ax, "azimuth theta (deg)", f"var_{col} / sigma^2 (ratio, clipped at 100)",
                         f"{name}: {col} plane (dots MC, lines closed form)")  # fmt: skip
        plots.legend(ax, fontsize=7)
    fig_path = plots.save(fig, ctx.figure_path("projected_variance"))
    body = f"""
### E2.0 Projected-angle noise (Figs. 2-2, 2-3; C1)

{len(df)} grid points (theta every {thetas[1] - thetas[0]:.0f} deg, phi = 10 ... 170 deg), {n_mc} Monte
Carlo samples each with sigma^2 = 1 deg^2. Largest relative gap between Monte Carlo and the
closed form: {rel.max():.4f} (median {rel.median():.4f}). var_xy equals sigma^2 to {xy_dev:.4f}.
Grid points with 45 < phi < 135 deg where var_yz < sigma^2: **{yz_below_inside}**; outside that band
{100 * yz_below_outside:.0f} % of points have var_yz < sigma^2. So, with phi the polar angle (the only
reading consistent with the text's numbers), the yz plane is the *better* one only *outside*
45-135 deg, the opposite of what Sec. 2.1.2 says; the published PPS rule (yz inside 45-135 deg) is
kept as "literal" and the minimum-variance rule is run beside it.

![projected variances]({fig_path.name})
"""
    return claims, body, df


def run(ctx: RunContext) -> Outcome:
    """``--measurements gaussian`` (default): the dissertation's Ch. 2; ``audio``: angles from sound."""
    if Options.of(ctx).measurements == "audio":
        from .projected_planes_audio import run as run_audio

        return run_audio(ctx)
    return run_gaussian(ctx)


def run_gaussian(ctx: RunContext) -> Outcome:
    """The dissertation's Ch. 2 with Gaussian angle noise: scenario, estimation, claims, figures, text."""
    s = Settings()
    runs = ctx.n_runs(full=100, quick=5)
    n_part = 500 if ctx.quick else s.n_particles
    df = ctx.monte_carlo(run_once, _gaussian_configs(ctx.quick, s, n_part), runs)
    claims, var_body, var_df = _variance_part(ctx)
    tab = df[df["part"].isin(["table21", "table22"])]
    rm = _rmse(tab, ["part", "method"])
    claims += _table_claims(rm, ctx.quick)
    ws = df[df["part"] == "E2.2"].groupby(["variance_deg2", "method"])["mean_log_w"].mean()
    ws = ws.unstack("method")
    claims.append(_weight_sum_claim(ws))
    sc_all = df[df["part"].isin(list(SCENARIOS))]
    sc = sc_all[sc_all["init"] == "given"]
    sc_prior = sc_all[sc_all["init"] == "prior"]
    srm = _rmse(sc, ["part", "method"])
    srm_prior = _rmse(sc_prior, ["part", "method"])
    bounds = {name: scenario_bounds(name) for name in SCENARIOS}  # S4: both sensors
    scenario_claims, avg_bound = _scenario_claims(srm, srm_prior, bounds, ctx.quick)
    claims += scenario_claims
    claims += _rmse_order_claims(sc_all)
    claims.append(_information_claim(bounds))
    figs = _gaussian_figures(ctx, tab, ws, sc, bounds, runs)
    body = _gaussian_text(
        var_body, s, n_part, runs, rm, ws, sc, srm, srm_prior, bounds, avg_bound, figs
    )
    results = pd.concat([df, var_df], ignore_index=True)
    return Outcome(results, claims, body, runs)


def _gaussian_configs(quick: bool, s: Settings, n_part: int) -> list[dict[str, Any]]:
    """E2.1 tables, E2.2 weight sums and Scenarios 1-4, from a given and from a prior start."""
    configs: list[dict[str, Any]] = [
        {"part": "table", "mismatch": False, "sigma_a": s.sigma_a_table, "n_particles": n_part},
        {"part": "table", "mismatch": True, "sigma_a": s.sigma_a_table, "n_particles": n_part},
    ]
    variances = [0.5, 1.0, 3.0, 10.0] if quick else [0.5, 1.0, 2.0, 3.0, 5.0, 7.0, 10.0]
    configs += [{"part": "weights", "variance_deg2": v, "n_particles": 100} for v in variances]
    configs += [
        {
            "part": "scenario",
            "scenario": name,
            "init": init,
            "sigma_a": s.sigma_a_scn,
            "n_particles": n_part,
        }
        for init in ("given", "prior")
        for name in SCENARIOS
    ]
    return configs


def _table_claims(rm: pd.DataFrame, quick: bool) -> list[Claim]:
    """C2, C3: Tables 2.1 and 2.2."""
    claims: list[Claim] = []
    tol = 0.5 if quick else 0.2
    t21 = rm.loc["table21"].loc[["equal", "weighted"]]
    t22 = rm.loc["table22"].loc[["equal", "weighted"]]
    within = [
        abs(t21.loc[m].iloc[i] / PAPER_T21[m][i] - 1) <= tol
        for m in ("equal", "weighted")
        for i in range(4)
    ]
    claims.append(
        CLAIM_KINDS.claim(
            "C2_table21_values",
            f"Table 2.1 RMSEs (x, y, z, avg; equal and weighted) within +-{tol:.0%} of the paper",
            PAPER_T21,
            {m: [round(float(v), 4) for v in t21.loc[m]] for m in ("equal", "weighted")},
            f"{sum(within)} of 8 within",
            all(within),
        )
    )
    ratio21 = float(t21.loc["weighted", "average"] / t21.loc["equal", "average"])
    claims.append(
        CLAIM_KINDS.claim(
            "C2_weighted_close_to_equal",
            "with correct models weighted and equal combining give averages within 10 %",
            round(1.2957 / 1.3358, 4),
            ratio21,
            "0.9 <= ratio <= 1.1",
            0.9 <= ratio21 <= 1.1,
        )
    )
    ratio22 = float(t22.loc["equal", "y"] / t22.loc["weighted", "y"])
    claims.append(
        CLAIM_KINDS.claim(
            "C3_weighted_robust",
            "yz filter mismatched (CV, steps 50-99): y RMSE equal / weighted",
            round(17.3250 / 0.6243, 2),
            ratio22,
            "> 5",
            ratio22 > 5,
        )
    )
    claims.append(
        CLAIM_KINDS.claim(
            "C3_weighted_not_worse",
            "yz filter mismatched: weighted average RMSE <= equal average RMSE",
            "1.3044 <= 6.8997",
            float(t22.loc["weighted", "average"] / t22.loc["equal", "average"]),
            "ratio <= 1",
            t22.loc["weighted", "average"] <= t22.loc["equal", "average"],
        )
    )

    return claims


def _weight_sum_claim(ws: pd.DataFrame) -> Claim:
    """C4: Fig. 2-7."""
    larger = bool((ws["yz plane (PPS)"] > ws["direct 3-D"]).all())
    return CLAIM_KINDS.claim(
        "C4_weight_sums",
        "selected-plane (yz) weight sums exceed the direct 3-D filter's at every noise level (Fig. 2-7)",
        "PPS > 3-D at every variance",
        {str(k): round(float(v), 3) for k, v in (ws["yz plane (PPS)"] - ws["direct 3-D"]).items()},
        "log W difference > 0 everywhere",
        larger,
    )


def _scenario_claims(
    srm: pd.DataFrame,
    srm_prior: pd.DataFrame,
    bounds: Mapping[str, Mapping[str, np.ndarray]],
    quick: bool,
) -> tuple[list[Claim], dict[str, float]]:
    """C5, C6: Scenarios 1-4 against each other and their CRLBs."""
    slack = 0.7 if quick else 0.9
    c6, avg_bound = _multisensor_claims(srm, srm_prior, bounds, slack)
    return _single_sensor_claims(srm, srm_prior, bounds, slack) + c6, avg_bound


def _single_sensor_claims(
    srm: pd.DataFrame,
    srm_prior: pd.DataFrame,
    bounds: Mapping[str, Mapping[str, np.ndarray]],
    slack: float,
) -> list[Claim]:
    """C5: PPS against the direct 3-D filter in Scenarios 1-3, RMSEs and CRLBs."""
    claims: list[Claim] = []
    bound_better, above = [], []
    for name in ("S1", "S2", "S3"):
        b = bounds[name]
        pps_b = np.mean([b[f"{c}|PPS"].mean() for c in AXES])
        d3_b = np.mean([b[f"{c}|3-D"].mean() for c in AXES])
        bound_better.append((name, round(float(pps_b), 4), round(float(d3_b), 4)))
        d3_rmse = float(srm_prior.loc[(name, "direct 3-D"), "average"])
        above.append((name, round(d3_rmse, 4), round(float(d3_b), 4)))
    claims.append(
        CLAIM_KINDS.claim(
            "C5_pps_bound_vs_3d",
            "time-averaged CRLB of the PPS selected planes (fused on the shared axis) <= 3-D CRLB (scenario, PPS, 3-D)",
            "selected-plane bounds below 3-D",
            bound_better,
            "PPS <= 3-D in all three",
            all(p <= d for _, p, d in bound_better),
        )
    )
    claims.append(
        CLAIM_KINDS.claim(
            "C5_3d_filter_above_bound",
            "direct 3-D filter time-averaged RMSE (started from a prior draw) >= its time-averaged CRLB "
            "(scenario, RMSE, bound; sanity of the bound)",
            "C >= J^-1",
            above,
            f"RMSE >= {slack} x bound (Monte Carlo slack)",
            all(r >= slack * b for _, r, b in above),
        )
    )
    return claims


def _multisensor_claims(
    srm: pd.DataFrame,
    srm_prior: pd.DataFrame,
    bounds: Mapping[str, Mapping[str, np.ndarray]],
    slack: float,
) -> tuple[list[Claim], dict[str, float]]:
    """C6: two sensors (S4, extended PPS) against one (S3), RMSEs and CRLBs."""
    claims: list[Claim] = []
    s3 = float(srm.loc[("S3", "PPS literal"), "average"])
    s4 = float(srm.loc[("S4", "PPS literal"), "average"])
    s4m = float(srm.loc[("S4", "PPS minvar"), "average"])
    s3b = bounds["S3"]
    s4b = bounds["S4"]
    avg_bound = {
        key: round(float(np.mean([b[f"{c}|{m}"].mean() for c in AXES])), 4)
        for key, b, m in (
            ("S3 PPS", s3b, "PPS"),
            ("S4 extended PPS", s4b, "PPS"),
            ("S3 3-D", s3b, "3-D"),
            ("S4 3-D, both sensors", s4b, "3-D"),
        )
    }
    claims.append(
        CLAIM_KINDS.claim(
            "C6_multisensor_bound",
            "two-sensor CRLB (S4, extended PPS: selected pairs fused on the shared axis) below the "
            "single-sensor PPS bound of S3 (time-averaged, mean over axes, m; 3-D bounds beside)",
            "multi-sensor better (Figs. 2-12, 2-13)",
            avg_bound,
            "S4 extended PPS < S3 PPS",
            avg_bound["S4 extended PPS"] < avg_bound["S3 PPS"],
        )
    )
    s4_rmse = float(srm_prior.loc[("S4", "PPS literal"), "average"])
    claims.append(
        CLAIM_KINDS.claim(
            "C6_s4_above_bound",
            "S4 extended PPS (literal) time-averaged RMSE, started from a prior draw, >= its two-sensor "
            "time-averaged CRLB (RMSE, bound; sanity of the bound)",
            "C >= J^-1",
            [round(s4_rmse, 4), avg_bound["S4 extended PPS"]],
            f"RMSE >= {slack} x bound",
            s4_rmse >= slack * avg_bound["S4 extended PPS"],
        )
    )
    claims.append(
        CLAIM_KINDS.claim(
            "C6_multisensor",
            "extended PPS with two sensors (S4, literal) beats single-sensor PPS (S3): avg RMSE S4 / S3 "
            "(and S4 min-variance / S3)",
            "multi-sensor better",
            {"literal": round(s4 / s3, 4), "minvar": round(s4m / s3, 4)},
            "< 1",
            s4 < s3,
        )
    )

    return claims, avg_bound


def _gaussian_figures(
    ctx: RunContext,
    tab: pd.DataFrame,
    ws: pd.DataFrame,
    sc: pd.DataFrame,
    bounds: Mapping[str, Mapping[str, np.ndarray]],
    runs: int,
) -> list[Path]:
    """Figs. 2-5/2-6 (combining), 2-7 (weight sums), 2-10 ... 2-13 (scenarios)."""
    figs = []
    steps = np.arange(TABLE_STEPS)
    for case, label in (
        ("table21", "Table 2.1 (correct models)"),
        ("table22", "Table 2.2 (yz mismatched)"),
    ):
        sub = tab[(tab.part == case) & (tab.run == 0)]
        truth = TABLE_TRUTH.trajectory(np.array(TABLE_X0), TABLE_DT, TABLE_STEPS)
        fig, axs = plots.panels(2, size=(11, 4))
        for ax, col, j in ((axs[0], "est_y", 1), (axs[1], "est_z", 2)):
            if case == "table22":
                plots.shade_intervals(ax, [MISMATCH], "yz model mismatched")
            ax.plot(steps, truth[:, j], "k-", lw=2, alpha=0.6, label="truth")
            ms = ("equal", "weighted", "yz filter alone")
            plots.curves(ax, steps, {m: sub[sub.method == m][col].to_numpy() for m in ms})
            plots.label_axes(ax, "time (s)", col[-1] + " (m)")
            plots.legend(ax, fontsize=7)
        fig.suptitle(f"Figs. 2-5/2-6, run 0: {label}")
        figs.append(plots.save(fig, ctx.figure_path(f"combining_{case}")))
    fig, ax = plots.panel(size=(6, 4))
    plots.curves(ax, ws.index, {str(m): ws[m] for m in ws.columns})
    plots.label_axes(ax, "measurement variance (deg^2)", "mean log weight sum (nats)",
                     "Fig. 2-7: unnormalised weight sums (100 particles, Scenario 1)")  # fmt: skip
    plots.legend(ax)
    figs.append(plots.save(fig, ctx.figure_path("weight_sums")))
    for name in SCENARIOS:
        b = bounds.get(name, {})
        t = np.arange(SCN_STEPS) * SCN_DT
        fig, axs = plots.panels(3, size=(14, 4))
        sub = sc[sc.part == name]
        greys, dashes = ("0.1", "0.35", "0.55", "0.75"), ("--", "-.", ":", (0, (6, 2)))
        for k, (ax, c) in enumerate(zip(axs, AXES)):
            bounds_c = [(key, v) for key, v in b.items() if key.startswith(f"{c}|")]
            for i, (key, vals) in enumerate(k_v for k_v in bounds_c if "switched" not in k_v[0]):
                plots.curve(ax, t, vals, index=i, label=f"CRLB {key.split('|')[1]}", marker="",
                            color=greys[i % 4], linestyle=dashes[i % 4], lw=1)  # fmt: skip
            for i, m in enumerate(sub.method.unique()):
                r = np.sqrt(sub[sub.method == m].groupby("step")[f"sq_{c}"].mean())
                plots.curve(ax, t, r, index=i, label=f"RMSE {m}")
            plots.label_axes(ax, "time (s)", f"{c} error (m)")
            if k == 0:
                plots.legend(ax, fontsize=6)
        fig.suptitle(f"{name}: per-axis RMSE ({runs} runs) and CRLBs (prior std {PRIOR_STD})")
        figs.append(plots.save(fig, ctx.figure_path(f"scenario_{name}")))

    return figs


def _gaussian_text(
    var_body: str,
    s: Settings,
    n_part: int,
    runs: int,
    rm: pd.DataFrame,
    ws: pd.DataFrame,
    sc: pd.DataFrame,
    srm: pd.DataFrame,
    srm_prior: pd.DataFrame,
    bounds: Mapping[str, Mapping[str, np.ndarray]],
    avg_bound: Mapping[str, float],
    figs: Sequence[Path],
) -> str:
    """The report body: E2.1, E2.2, then the scenarios."""
    return _tables_text(var_body, s, n_part, runs, rm, ws, figs) + _scenarios_text(
        s, n_part, runs, sc, srm, srm_prior, bounds, avg_bound, figs
    )


def _table_md(ours: pd.DataFrame, paper: Mapping[str, tuple[float, ...]]) -> str:
    lines = [
        "| RMSE (m) | paper equal | ours equal | paper weighted | ours weighted |",
        "|---|---|---|---|---|",
    ]
    for i, c in enumerate(["x", "y", "z", "average"]):
        lines.append(
            f"| {c} | {paper['equal'][i]:.4f} | {ours.loc['equal', c]:.4f} | "
            f"{paper['weighted'][i]:.4f} | {ours.loc['weighted', c]:.4f} |"
        )
    return "\n".join(lines)


def _tables_text(
    var_body: str,
    s: Settings,
    n_part: int,
    runs: int,
    rm: pd.DataFrame,
    ws: pd.DataFrame,
    figs: Sequence[Path],
) -> str:
    """E2.1 combining and E2.2 weight sums."""
    t21 = rm.loc["table21"].loc[["equal", "weighted"]]
    t22 = rm.loc["table22"].loc[["equal", "weighted"]]
    ratio22 = float(t22.loc["equal", "y"] / t22.loc["weighted", "y"])
    yz_alone = rm.loc["table22"].loc["yz filter alone"]
    return f"""
{var_body}

### E2.1 Combining (Tables 2.1, 2.2; C2, C3)

Object from (10, 130, 18) m at (1, -0.75, 0.75) m/s, x constant velocity, (y, z) turning clockwise
with alpha = 0.01 m/s^2 (the sign that reproduces the text's angle ranges), 165 s at 1 s, angle
variance 3 deg^2, {n_part} particles per plane filter, {runs} runs. PPS-literal selects xy + yz
throughout. The yz filter has the true turn; the xy filter's y axis turns with z, which it does
not have: it takes the turn's current y acceleration from the last fused estimate. Filter process
noise sigma_a = {s.sigma_a_table} m/s^2 (not given in the text; the spec's 0.02 m/s^2 gave
x RMSEs about twice the paper's in a trial, the xy filter drifting along the unobservable range).
Table 2.2: the yz filter runs constant velocity over steps {MISMATCH[0]}-{MISMATCH[1] - 1}.

Table 2.1 (correct models):

{_table_md(t21, PAPER_T21)}

Table 2.2 (yz filter mismatched):

{_table_md(t22, PAPER_T22)}

The yz filter's own y, z RMSE in the mismatched case (Fig. 2-5): y {yz_alone["y"]:.3f}, z {yz_alone["z"]:.3f} m.

**Differences.** The paper's equal-weight y error of 17.3 m in Table 2.2 means its mismatched yz
filter diverged far. Ours drifts less (its own y RMSE {yz_alone["y"]:.2f} m): with alpha = 0.01 m/s^2
the turn's acceleration is small, and a bearings-only plane filter can match every bearing by
sliding along the unobservable range, so a wrong model costs little likelihood. The weight sums
then separate the two filters only mildly and the weighted y error is only {ratio22:.2f} times
smaller than the equal one (paper {17.3250 / 0.6243:.1f}). In Table 2.1 our y error is larger than the
paper's and x, z smaller: y is shared by the xy filter, whose y axis only knows the turn through
the last fused estimate. The absolute RMSEs depend on the process noise and the initial
uncertainty, which the text does not give.

![combining, table 2.1]({figs[0].name})

![combining, table 2.2]({figs[1].name})

### E2.2 Weight sums (Fig. 2-7; C4)

Mean over time and runs of the log unnormalised weight sum, 100 particles, Scenario 1:

{ws.to_markdown(floatfmt=".3f")}

As the spec notes, the comparison favours PPS by construction: a 1-D kernel
exp(-r^2/2 s_P^2) against a product of two kernels, each at most 1.

![weight sums]({figs[2].name})

"""


def _scenarios_text(
    s: Settings,
    n_part: int,
    runs: int,
    sc: pd.DataFrame,
    srm: pd.DataFrame,
    srm_prior: pd.DataFrame,
    bounds: Mapping[str, Mapping[str, np.ndarray]],
    avg_bound: Mapping[str, float],
    figs: Sequence[Path],
) -> str:
    """Scenarios 1-4 against the CRLBs."""
    s4b = bounds["S4"]
    sc_table = srm.reset_index().rename(columns={"part": "scenario"})
    bound_rows = []
    for name in bounds:
        b = bounds[name]
        row: dict[str, Any] = {"scenario": name}
        for c in AXES:
            for key in (f"{c}|PPS", f"{c}|3-D"):
                row[key] = float(b[key].mean())
        bound_rows.append(row)
    selections = (
        sc[sc.step.isin([0, 12, 13, 49])]
        .drop_duplicates(["part", "method", "step"])
        .query("run == 0")[["part", "method", "step", "planes"]]
    )
    return f"""### Scenarios 1-4 (Figs. 2-10 ... 2-13; C5, C6)

Ts = 0.1 s, 50 instants, x constant velocity, A_y = 0.1, A_z = 0.5 m/s^2, variance 3 deg^2,
{n_part} particles, {runs} runs, filter process noise sigma_a = {s.sigma_a_scn} m/s^2. The filters'
particles start around the true state ("given", the text) with std {PRIOR_STD} per position and
velocity component; a second set of runs starts them around a draw of that prior, the setting of
the CRLB (J_0 = P_0^-1; with the text's J_0 = 0 and its state-dependent linear transition the
bound does not exist: a static bearing sensor cannot observe scale then). S4 adds a sensor at (10, 10, 10) with every axis
flipped. Time-averaged RMSE (m):

{sc_table.to_markdown(index=False, floatfmt=".4f")}

The same with the filters started from a draw of the prior N(truth, {PRIOR_STD}^2 I) (the setting
the CRLB describes):

{srm_prior.reset_index().rename(columns={"part": "scenario"}).to_markdown(index=False, floatfmt=".4f")}

Time-averaged CRLB (m): PPS = selected (sensor, plane) pairs (literal selection, switched
information), fused on the shared axis; 3-D = direct filter with every sensor of the scenario.
S4 is the two-sensor bound: its extended-PPS pairs come from both sensors (each plane filter's
bound in the global frame, Eqs. 2.22-2.27 with the corrected shifts), and its 3-D bound adds
both sensors' angle pairs every step; the S4 3-D bound of the primary sensor alone is
{np.mean([s4b[f"{c}|3-D A0"].mean() for c in AXES]):.4f} m (mean over axes):

{pd.DataFrame(bound_rows).to_markdown(index=False, floatfmt=".4f")}

Two sensors (S4 against S3, time-averaged bound, mean over axes): extended PPS
{avg_bound["S4 extended PPS"]:.4f} m against single-sensor PPS {avg_bound["S3 PPS"]:.4f} m; direct
3-D with both sensors {avg_bound["S4 3-D, both sensors"]:.4f} m against one sensor
{avg_bound["S3 3-D"]:.4f} m. The literal extended-PPS selection uses one plane per sensor after
instant 13 (zx of the primary sensor, yz of the second), so it trades the primary sensor's xy
plane for the second sensor's yz plane, seen from about twice the range: its bound is
{"lower" if avg_bound["S4 extended PPS"] < avg_bound["S3 PPS"] else "not lower"} than S3's. Only
a filter that uses both sensors' full angle pairs (the 3-D bound) gains clearly from the second
sensor here; claim C6_multisensor above reports what the filters' errors give.

Sensitivity of the bound to the prior (time-averaged 3-D CRLB, m, mean over x, y, z), with the
true (affine) transition and with the text's state-dependent linear F (Eq. 2.15, "printed"): with
the printed F the bound grows in proportion to the prior (scale unobservable), with the true
transition it grows more slowly (the known accelerations carry some scale information):

{prior_sensitivity().to_markdown(floatfmt=".4f")}

Selected planes (run 0) at steps 0, 12, 13, 49:

{selections.to_markdown(index=False)}

The text gives no numbers for the scenarios, only that the selected planes "show good
performance" and that PPS "outperforms the direct 3-D method". The selections match the text
(S1 xy + yz, S2 xy + zx, S3 switching from yz to zx at instant 13, S4 yz + xy then zx + yz).
On the bounds: the text compares each plane's bound with the 3-D bound; a 2-D plane bound uses
one projected bearing, the 3-D bound both angles, so the 3-D bound of a coordinate can be lower
than a single plane's, and the claim C5_pps_bound_vs_3d reports what the fused PPS bound gives.

![S1]({figs[3].name})

![S2]({figs[4].name})

![S3]({figs[5].name})

![S4]({figs[6].name})
"""


def _rmse_order_claims(sc_all: pd.DataFrame) -> list[Claim]:
    """C5: PPS (literal) against direct 3-D in Scenarios 1-3, from the true start ("given", the
    text) and from a draw of the prior, judged on the paired per-run difference of the
    time-averaged RMSE (mean over axes; runs share their seeds and measurements)."""
    claims = []
    for init, suffix in (("given", ""), ("prior", "_from_prior")):
        g = sc_all[(sc_all["init"] == init) & sc_all["part"].isin(["S1", "S2", "S3"])]
        per_run = g.groupby(["part", "method", "run"])[["sq_x", "sq_y", "sq_z"]].mean().pow(0.5)
        avg = per_run.mean(axis=1).unstack("method")
        ours, shown = {}, []
        for name in ("S1", "S2", "S3"):
            a = avg.loc[name]
            gap = paired_interval(a["direct 3-D"], a["PPS literal"])
            ours[name] = {
                "PPS": round(float(a["PPS literal"].mean()), 4),
                "3-D": round(float(a["direct 3-D"].mean()), 4),
                "3-D - PPS": interval_values(gap, 4),
            }
            shown.append(shown_positive(gap))
        start = "the true start (the text)" if init == "given" else "a draw of the prior"
        claims.append(
            CLAIM_KINDS.claim(
                "C5_pps_rmse_vs_3d" + suffix,
                "PPS (literal) average RMSE below direct 3-D average RMSE in Scenarios 1-3, filters "
                f"started from {start}; paired over runs: 3-D - PPS [mean, 95% half-width]",
                "PPS outperforms direct 3-D",
                ours,
                "interval of 3-D - PPS above 0 in all three",
                all(shown),
            )
        )
    return claims


def _information_claim(bounds: Mapping[str, Mapping[str, np.ndarray]]) -> Claim:
    """Why no valid PPS bound can lie below the 3-D bound (computed, Scenarios 1-3, every step):
    the selected planes' bearings are two functions of the same angle pair, so their joint
    information equals the 3-D pair's and either plane's alone is below it; only summing the
    planes as independent exceeds it (:func:`angle_pair_information`)."""
    pair_gap, single_min, indep_min, below = 0.0, np.inf, np.inf, 0
    for name in ("S1", "S2", "S3"):
        truth = scenario_truth(name)
        for n, p in enumerate(truth[:, :3]):
            planes = ("xy", "yz") if bounds[name]["selected_yz"][n] else ("xy", "zx")
            J = angle_pair_information(p, primary(), planes)
            scale = float(np.linalg.norm(J["3-D"]))
            pair_gap = max(pair_gap, float(np.abs(J["pair"] - J["3-D"]).max()) / scale)
            for q in planes:
                single_min = min(
                    single_min, float(np.linalg.eigvalsh(J["3-D"] - J[q]).min()) / scale
                )
            indep_min = min(
                indep_min, float(np.linalg.eigvalsh(J["3-D"] - J["independent"]).min()) / scale
            )
        b = bounds[name]
        below += sum(int(np.sum(b[f"{c}|PPS"] < b[f"{c}|3-D"])) for c in AXES)
    return CLAIM_KINDS.claim(
        "C5_no_pps_bound_below_3d",
        "the selected planes' bearings are two functions of the measured (theta, phi): with the "
        "noise propagated jointly their Fisher information equals the 3-D pair's, either plane "
        "alone carries less, so no valid PPS bound is below the 3-D bound; summing the planes as "
        "independent exceeds it (Scenarios 1-3, every step; relative to ||J_3D||: max |J_pair - "
        "J_3D|, min eig(J_3D - J_plane), min eig(J_3D - J_independent); steps x axes where our "
        "fused-independent PPS bound is below the 3-D bound)",
        "selected-plane bounds below 3-D (C5)",
        {
            "pair - 3-D": round(pair_gap, 10) + 0.0,  # rounding-level: machine-independent
            "min eig 3-D - plane": round(single_min, 10) + 0.0,
            "min eig 3-D - independent": round(indep_min, 4),
            "PPS bound below 3-D (of 450)": below,
        },
        "pair - 3-D <= 1e-6 and min eig 3-D - plane >= -1e-9",
        pair_gap <= 1e-6 and single_min >= -1e-9,
    )
