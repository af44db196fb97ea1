"""Zhai 2007, E5-E8 (Sec. 3.4, Figs 25-30): regime transitions, manoeuvre models, MM-bootstrap.

* E5 (Fig 25): 10 000 model particles, uniform over CV, CCW, CW, CA, propagated with Pi_A.
* E6 (Fig 26): noise-free coordinated turns at several manoeuvre accelerations.
* E7 (Figs 27-28): bearings-only MM-bootstrap (CV, CCW, CW) on a target that turns sharply
  anticlockwise at t = 7; the CCW model's share of the resampled particles should peak there.
* E8 (Figs 29-30): one MM-bootstrap per sensor, fused with weights ∝ 1/d^2 (normalised
  "reflectivity"), against a single-sensor MM-bootstrap and a single-sensor single-model bootstrap.

Every number the thesis leaves out is the spec's choice (spec 001, Sec. 4, E5-E8); see the report.
Bearings use fusetrack's convention (angle from +x, anticlockwise) instead of the thesis's
``atan2(x, y)`` (from +y, clockwise); the two carry the same information.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from ...core import Gaussian
from ...evaluation import Claim, ClaimKinds, Outcome, RunContext, plots, run_seed
from ...filters import (
    InteractingMultipleModel,
    MultipleModelParticleFilter,
    ProposalParticleFilter,
    sample_regimes,
    stationary_distribution,
)
from ...motion import ConstantVelocity, ManeuverTurn
from ...sensors import Bearing
from .common import join_with_relations, timed_gaussian, timed_mm, timed_sis, track_rows
from .comparators import UPF_NOTE, Comparison, Scenario, run_comparators
from .equal_time import EqualTime
from .reporting import plot_rmse, plot_run_tracks, rmse_by_method, rmse_by_step

PI_A = np.array(
    [[0.7, 0.1, 0.1, 0.1], [0.4, 0.5, 0.05, 0.05], [0.4, 0.3, 0.2, 0.1], [0.4, 0.3, 0.2, 0.1]]
)
PI_3 = np.array([[0.8, 0.1, 0.1], [0.2, 0.7, 0.1], [0.2, 0.1, 0.7]])
MODEL_NAMES = ("CV", "CCW", "CW")
E7_STEPS, E7_TURN = 20, (7, 8, 9)
E8_STEPS = 50
E8_TURNS = {10: 1, 11: 1, 20: -1, 21: -1, 30: 1, 31: 1, 40: -1, 41: -1}
E8_SENSORS = ((0.0, 0.0), (60.0, 0.0), (30.0, 60.0))


def filter_models(q: float, a_m: float) -> list[Any]:
    """The filters' models: CV and anticlockwise/clockwise manoeuvre turns (Sec. 3.4)."""
    return [
        ConstantVelocity(q=q, noise="continuous"),
        ManeuverTurn(a_m, 1, q),
        ManeuverTurn(a_m, -1, q),
    ]


def simulate_turns(
    x0: np.ndarray,
    steps: int,
    turns: Mapping[int, int],
    a_m: float,
    q: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """Truth ``(steps, 4)``: CV except at the steps in ``turns`` (direction +1 CCW / -1 CW);
    noise ``Gamma m``, ``m ~ N(0, q I)`` (Zhai 2007, Eq. 34, rank 2)."""
    cv = ConstantVelocity(q=q, noise="discrete")
    x, out = np.asarray(x0, float), []
    for k in range(1, steps + 1):
        model = ManeuverTurn(a_m, turns[k], q, noise="discrete") if k in turns else cv
        x = model.sample(x, 1.0, rng)
        out.append(x)
    return np.array(out)


def bearings(
    sensors: list[Bearing], truth: np.ndarray, rng: np.random.Generator
) -> list[list[np.ndarray]]:
    """One bearing per sensor for every state of ``truth``."""
    return [[s.simulate(x, rng) for s in sensors] for x in truth]


# ----------------------------------------------------------------------------- E7


def e7_scenario(config: Mapping[str, Any], seed: int) -> Scenario:
    """Run ``seed``'s E7 truth, bearing and prior as a :class:`Scenario` (CV for the single-model
    comparators; the IMM uses the three filter models and ``PI_3``)."""
    rng = np.random.default_rng(seed)
    q, a_m = 0.01, 0.5
    x0 = np.array([10.0, 30.0, 1.0, 0.0])
    truth = simulate_turns(x0, E7_STEPS, {k: 1 for k in E7_TURN}, a_m, q, rng)
    sensor = Bearing("s0", position=[0.0, 0.0], sigma=float(config["sigma"]))
    zs = bearings([sensor], truth, rng)
    p0 = np.diag([1.0, 1.0, 0.1, 0.1])
    prior = Gaussian(x0 + rng.multivariate_normal(np.zeros(4), p0), p0)
    models = filter_models(q, a_m)
    return Scenario(models[0], [sensor], prior, zs, 1.0, truth, models, PI_3)


def run_e7(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    cs = e7_scenario(config, seed)
    if "n_equal" in config:  # beyond the paper only (fewer runs)
        found = run_comparators(cs, seed, config["n_equal"], ("UPF", "bootstrap equal time"))
        return [
            r
            for m, t in found.items()
            for r in track_rows(m, t.estimates, cs.truth, seconds=t.seconds)
        ]
    n, sensor, prior, zs, truth = (
        int(config["n_particles"]),
        cs.sensors[0],
        cs.prior,
        cs.zs,
        cs.truth,
    )
    models = list(cs.imm_models)
    rows: list[dict[str, Any]] = []
    runs = {
        "MM-bootstrap": MultipleModelParticleFilter(models, PI_3, [sensor], n),
        "MMPF-SP": MultipleModelParticleFilter(
            models, PI_3, [sensor], 200, proposal="sp-pekf", n_channels=10
        ),
    }
    for k, (name, filt) in enumerate(runs.items()):
        est, probs, secs = timed_mm(filt, prior, zs, 1.0, np.random.default_rng([seed, k]))
        rows += track_rows(name, est, truth, seconds=secs, **model_columns(probs))
    imm_probs: list[np.ndarray] = []
    imm = InteractingMultipleModel(models, PI_3, [sensor])
    est, secs = timed_gaussian(imm, prior, zs, ["s0"], 1.0, imm_probs)
    rows += track_rows("IMM-EKF", est, truth, seconds=secs, **model_columns(np.array(imm_probs)))
    bs = ProposalParticleFilter(models[0], [sensor], n_particles=n)
    est, secs, _ = timed_sis(bs, prior, zs, 1.0, np.random.default_rng([seed, 9]))
    return rows + track_rows("bootstrap CV", est, truth, seconds=secs)


def model_columns(probs: np.ndarray) -> dict[str, np.ndarray]:
    """``{"p_CV": (T,), "p_CCW": ..., "p_CW": ...}`` from model probabilities ``(T, 3)``."""
    return {f"p_{m}": probs[:, i] for i, m in enumerate(MODEL_NAMES)}


# ----------------------------------------------------------------------------- E8


def fuse_by_reflectivity(estimates: np.ndarray, sensor_pos: np.ndarray) -> np.ndarray:
    """``sum_k w_k x_k`` with ``w_k ∝ 1/d_k^2``, ``d_k`` = distance from sensor k to its own estimate
    (Zhai 2007, Sec. 3.4.5, Fig 29; spec choice). ``estimates (K, ..., d)``, ``sensor_pos (K, 2)``."""
    d2 = np.sum(
        (
            estimates[..., :2]
            - sensor_pos.reshape((len(sensor_pos),) + (1,) * (estimates.ndim - 2) + (2,))
        )
        ** 2,
        axis=-1,
    )
    w = 1.0 / np.maximum(d2, 1e-9)
    w = w / w.sum(axis=0)
    return np.asarray(np.sum(w[..., None] * estimates, axis=0))


def e8_scenario(seed: int) -> Scenario:
    """Run ``seed``'s E8 truth, three bearings and prior as a :class:`Scenario` (centralised)."""
    rng = np.random.default_rng(seed)
    q, a_m = 0.01, float(np.deg2rad(10.0))
    x0 = np.array([15.0, 20.0, 0.8, 0.3])
    truth = simulate_turns(x0, E8_STEPS, E8_TURNS, a_m * float(np.hypot(0.8, 0.3)), q, rng)
    sensors = [Bearing(f"s{i}", position=list(p), sigma=0.05) for i, p in enumerate(E8_SENSORS)]
    zs = bearings(sensors, truth, rng)
    p0 = np.diag([1.0, 1.0, 0.1, 0.1])
    prior = Gaussian(x0 + rng.multivariate_normal(np.zeros(4), p0), p0)
    models = filter_models(q, 0.15)
    return Scenario(models[0], sensors, prior, zs, 1.0, truth, models, PI_3)


def fused_mmpf(cs: Scenario, n: int, seed: int) -> tuple[np.ndarray, np.ndarray, float]:
    """One MM-bootstrap per sensor fused by reflectivity: ``(fused, sensor 0's, seconds)``."""
    per_sensor, secs = [], 0.0
    for i, s in enumerate(cs.sensors):
        mm = MultipleModelParticleFilter(list(cs.imm_models), PI_3, [s], n)
        zi = [[z[i]] for z in cs.zs]
        est, _, t = timed_mm(mm, cs.prior, zi, 1.0, np.random.default_rng([seed, i]))
        per_sensor.append(est)
        secs += t
    fused = fuse_by_reflectivity(np.array(per_sensor), np.array(E8_SENSORS))
    return fused, per_sensor[0], secs


def run_e8(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    cs = e8_scenario(seed)
    if "n_equal" in config:  # beyond the paper only (fewer runs): centralised comparators
        found = run_comparators(cs, seed, config["n_equal"], ("UPF", "bootstrap equal time"))
        return [
            r
            for m, t in found.items()
            for r in track_rows(f"{m} centralised", t.estimates, cs.truth, seconds=t.seconds)
        ]
    n, sensors, prior, zs, truth = int(config["n_particles"]), cs.sensors, cs.prior, cs.zs, cs.truth
    models = list(cs.imm_models)
    out: dict[str, tuple[np.ndarray, float]] = {}
    fused, single, secs = fused_mmpf(cs, n, seed)
    out["MMPF single sensor"] = (single, secs / len(sensors))
    out["MMPF multi-sensor (fused)"] = (fused, secs)
    bs = ProposalParticleFilter(models[0], [sensors[0]], n_particles=n)
    z0 = [[z[0]] for z in zs]
    out["bootstrap single sensor"] = timed_sis(
        bs, prior, z0, 1.0, np.random.default_rng([seed, 5])
    )[:2]
    central = MultipleModelParticleFilter(models, PI_3, sensors, n)
    e, _, t = timed_mm(central, prior, zs, 1.0, np.random.default_rng([seed, 6]))
    out["MMPF centralised"] = (e, t)
    bsc = ProposalParticleFilter(models[0], sensors, n_particles=n)
    out["bootstrap centralised"] = timed_sis(bsc, prior, zs, 1.0, np.random.default_rng([seed, 7]))[
        :2
    ]
    ids = [s.sensor_id for s in sensors]
    single_imm = InteractingMultipleModel(models, PI_3, [sensors[0]])
    out["IMM-EKF single sensor"] = timed_gaussian(single_imm, prior, z0, ids[:1], 1.0)
    imm = InteractingMultipleModel(models, PI_3, sensors)
    out["IMM-EKF centralised"] = timed_gaussian(imm, prior, zs, ids, 1.0)
    return [
        row for name, (est, t) in out.items() for row in track_rows(name, est, truth, seconds=t)
    ]


# ----------------------------------------------------------------------------- report


def e5_shares(rng: np.random.Generator, n: int = 10_000, steps: int = 20) -> np.ndarray:
    """E5: shares of ``n`` model particles, uniform at step 0, propagated with Pi_A."""
    modes = rng.integers(0, 4, n)
    out = [np.bincount(modes, minlength=4) / n]
    for _ in range(steps):
        modes = sample_regimes(modes, PI_A, rng)
        out.append(np.bincount(modes, minlength=4) / n)
    return np.array(out)


def e6_tracks(
    a_values: tuple[float, ...] = (0.05, 0.1, 0.2, 0.5), steps: int = 60
) -> dict[str, np.ndarray]:
    """E6: noise-free CCW and CW turns from speed 1 at each ``a_m`` (Fig 26)."""
    out = {}
    for a in a_values:
        for direction, label in ((1, "CCW"), (-1, "CW")):
            m = ManeuverTurn(a, direction, 0.0)
            x = np.array([0.0, 0.0, 1.0, 0.0])
            xs = [x]
            for _ in range(steps):
                x = m.mean(x, 1.0)
                xs.append(x)
            out[f"{label} a_m={a:g}"] = np.array(xs)
    return out


CMP_RUNS = 30  # runs with the UPF and equal-time bootstrap (beyond the paper) at full size


def comparators(
    ctx: RunContext, df: pd.DataFrame, runs: int, n_part: int, sigmas: tuple[float, ...]
) -> Comparison:
    """Beyond the paper: UPF and bootstrap (CV) calibrated to the paper's filter's time (E7:
    MM-bootstrap; E8: the fused per-sensor MMPFs, against centralised comparators), on the first
    ``CMP_RUNS`` runs; the IMM-EKF rows come from every run."""
    k, eq, parts = min(runs, CMP_RUNS), EqualTime.for_run(ctx), []
    seed0 = run_seed(ctx.seed, 0)
    for sig in sigmas:
        cs = e7_scenario({"sigma": sig}, seed0)
        key = f"E7 sigma {sig:g}"

        def mm_ref(cs: Scenario = cs) -> object:
            f = MultipleModelParticleFilter(list(cs.imm_models), PI_3, cs.sensors, n_part)
            return timed_mm(f, cs.prior, cs.zs, 1.0, np.random.default_rng(0))

        cfg = {"experiment": "E7", "sigma": sig, "n_equal": eq.calibrate(key, cs, mm_ref)}
        parts.append(ctx.monte_carlo(run_e7, [cfg], k, desc=f"comparators {key}").assign(label=key))
    cs8 = e8_scenario(seed0)
    cfg8 = {
        "experiment": "E8",
        "n_equal": eq.calibrate("E8", cs8, lambda: fused_mmpf(cs8, n_part, 0)),
    }
    parts.append(ctx.monte_carlo(run_e8, [cfg8], k, desc="comparators E8").assign(label="E8"))
    label = np.where(
        df["experiment"] == "E8", "E8", "E7 sigma " + df["sigma"].map(lambda v: f"{v:g}")
    )
    rows = pd.concat([df[df["run"] < k].assign(label=label[df["run"] < k]), *parts])
    return eq.compare_runs(
        ctx,
        rows,
        ["label"],
        "sq_pos_err",
        {k: "MMPF multi-sensor (fused)" if k == "E8" else "MM-bootstrap" for k in eq.n_particles},
        ylabel="position RMSE per run (mean)",
        calibration=f" UPF and the equal-time bootstrap ran on the first {k} of the {runs} runs (same "
        "truths); the table compares every method on those runs. E8's reference is the fused "
        "multi-sensor MMPF (three filters); its comparators use all three bearings "
        "(centralised).",
        notes=[
            "IMM-EKF: the same three models (CV, CCW, CW) and matrix as the MMPFs, one EKF each.",
            "UPF and the equal-time bootstrap use the CV model (a single-model filter).",
            UPF_NOTE,
        ],
        runs=k,
    )


def run(ctx: RunContext) -> Outcome:
    """E5-E8: regime shares, turn shapes, the E7 and E8 runs, then the comparators."""
    runs = ctx.n_runs(full=100, quick=6)
    n_part = 2000 if ctx.quick else 5000

    shares = e5_shares(np.random.default_rng(ctx.seed))
    claims = claims_e5(shares)
    tracks = e6_tracks()
    claims.append(claim_e6(tracks))
    figs = {"fig25": figure_e5(ctx, shares), "fig26": figure_e6(ctx, tracks)}

    sigmas = (0.05, 0.005)
    df7 = ctx.monte_carlo(
        run_e7,
        [{"experiment": "E7", "n_particles": n_part, "sigma": s} for s in sigmas],
        runs,
        desc="E7",
    )
    share_tables = {sig: e7_shares(df7, sig) for sig in sigmas}
    claims += [claim_e7(df7, sig, share_tables[sig]) for sig in sigmas]
    figs["fig28"] = figure_e7(ctx, df7, share_tables, runs)

    df8 = ctx.monte_carlo(run_e8, [{"experiment": "E8", "n_particles": n_part}], runs, desc="E8")
    claims.append(claim_e8(df8))
    figs.update(figures_e8(ctx, df8, runs))

    df = pd.concat([df7, df8], ignore_index=True)
    cmp = comparators(ctx, df, runs, n_part, sigmas)
    body = (
        report_e5_e6(shares, figs)
        + report_e7(df7, share_tables, figs, n_part, runs)
        + report_e8(df8, figs, n_part, runs)
        + DIFFERENCES
        + cmp.section
    )
    return Outcome(df, claims, body, runs, beyond_the_paper=cmp.summary)


E8_ORDER = ["MMPF multi-sensor (fused)", "MMPF single sensor", "bootstrap single sensor"]


# Each claim's kind (fusetrack.evaluation.KINDS), by id or fnmatch pattern, first match.
CLAIM_KINDS = ClaimKinds(
    {
        "C10_ccw_peak_sigma0.005": "diagnostic",  # a reading: the paper's sigma is 0.05
        "C9_*": "paper",
        "C10_*": "paper",
        "C11_*": "paper",
        "E6_circles": "paper",
    }
)


def claims_e5(shares: np.ndarray) -> list[Claim]:
    """C9: the shares after 20 steps order as 1 > 2 > 3 > 4 and equal Pi_A's stationary law."""
    stat = stationary_distribution(PI_A)
    last = shares[-1]
    return [
        CLAIM_KINDS.claim(
            "C9_order",
            "model probabilities under Pi_A order as 1 > 2 > 3 > 4 (Fig 25)",
            "1 > 2 > 3 > 4",
            join_with_relations(list(last), [f"{v:.4f}" for v in last]),
            "strict",
            bool(np.all(np.diff(last) < 0)),
        ),
        CLAIM_KINDS.claim(
            "C9_stationary",
            "the shares after 20 steps equal the stationary distribution of Pi_A",
            [round(float(v), 4) for v in stat],
            [round(float(v), 4) for v in last],
            "±0.015 each",
            bool(np.all(np.abs(last - stat) <= 0.015)),
        ),
    ]


def figure_e5(ctx: RunContext, shares: np.ndarray) -> str:
    """Fig 25: each model's share per step, with the stationary share dotted."""
    stat = stationary_distribution(PI_A)
    fig, ax = plots.panel(size=(6, 3.6))
    for i in range(4):
        plots.curve(ax, np.arange(len(shares)), shares[:, i], index=i, label=f"model {i + 1}")
    for i in range(4):
        plots.reference_line(ax, stat[i], "stationary shares" if i == 0 else "", color=f"C{i}")
    plots.label_axes(ax, "step", "share of 10 000 model particles", "Fig 25: regimes under Pi_A")
    plots.legend(ax)
    return plots.save(fig, ctx.figure_path("fig25_model_shares")).name


def claim_e6(tracks: Mapping[str, np.ndarray]) -> Claim:
    """E6: every noise-free turn at speed 1 stays on its circle of radius ``1 / a_m``."""
    radius_err = max(
        float(
            np.max(
                np.abs(
                    np.hypot(
                        tr[:, 0],
                        tr[:, 1] - np.sign(1 if "CCW" in k else -1) / float(k.split("=")[1]),
                    )
                    - 1 / float(k.split("=")[1])
                )
            )
        )
        for k, tr in tracks.items()
    )
    return CLAIM_KINDS.claim(
        "E6_circles",
        "a CT model at speed 1 drives a circle of radius 1/a_m (Fig 26)",
        "circles",
        radius_err,
        "max radius error < 1e-9",
        radius_err < 1e-9,
    )


def figure_e6(ctx: RunContext, tracks: Mapping[str, np.ndarray]) -> str:
    """Fig 26: the coordinated turns."""
    fig, ax = plots.panel(size=(5, 5))
    plots.draw_paths(ax, list(tracks.values()), labels=list(tracks))
    ax.set(aspect="equal")
    plots.label_axes(ax, "x (m)", "y (m)", "Fig 26: coordinated turns (speed 1 m/s)")
    plots.legend(ax, fontsize=6)
    return plots.save(fig, ctx.figure_path("fig26_turns")).name


def e7_shares(df7: pd.DataFrame, sig: float) -> pd.DataFrame:
    """The MM-bootstrap's mean model shares per step (columns ``p_CV``, ...) at bearing ``sig``."""
    mm7 = df7[(df7["method"] == "MM-bootstrap") & (df7["sigma"] == sig)]
    return mm7.groupby("step")[[f"p_{m}" for m in MODEL_NAMES]].mean()


def claim_e7(df7: pd.DataFrame, sig: float, p_t: pd.DataFrame) -> Claim:
    """C10: the CCW share peaks within the turn and leads there (Fig 28)."""
    mm7 = df7[(df7["method"] == "MM-bootstrap") & (df7["sigma"] == sig)]
    peak_t = int(p_t["p_CCW"].idxmax())
    peak_top = p_t.loc[peak_t].idxmax()
    per_run_peak = mm7.loc[mm7.groupby("run")["p_CCW"].idxmax(), "step"]
    frac = float(per_run_peak.between(7, 9).mean())
    return CLAIM_KINDS.claim(
        f"C10_ccw_peak_sigma{sig:g}",
        f"bearing sigma {sig:g} rad: the CCW model's share peaks at the turn (t = 7-9) and leads there (Fig 28)",
        "t = 7",
        f"t = {peak_t} ({peak_top[2:]} leads, CCW share {p_t.loc[peak_t, 'p_CCW']:.2f}); "
        f"{frac:.0%} of runs peak in 7-9",
        "t in [7, 9] and CCW leads there",
        7 <= peak_t <= 9 and peak_top == "p_CCW",
    )


def figure_e7(
    ctx: RunContext, df7: pd.DataFrame, share_tables: Mapping[float, pd.DataFrame], runs: int
) -> str:
    """Figs 27-28: run 0's tracks at the first sigma, and the model shares per step."""
    sigmas = list(share_tables)
    fig, (ax1, ax2) = plots.panels(2, size=(11, 4))
    r0 = df7[(df7["run"] == 0) & (df7["sigma"] == sigmas[0])]
    tr = r0[r0["method"] == "MM-bootstrap"]
    ax1.plot(tr["true_x"], tr["true_y"], "k-", lw=2, alpha=0.6, label="truth")
    methods = ["MM-bootstrap", "bootstrap CV", "MMPF-SP", "IMM-EKF"]
    plots.draw_paths(ax1, [r0[r0["method"] == m][["x", "y"]].to_numpy() for m in methods],
                     labels=methods)  # fmt: skip
    plots.label_axes(ax1, "x (m)", "y (m)", "Fig 27: run 0")
    plots.legend(ax1, fontsize=7)
    plots.shade_intervals(ax2, [(E7_TURN[0] - 0.5, E7_TURN[-1] + 0.5)], "turn")
    k = 0
    for sig, dashes in zip(sigmas, ("-", "--")):
        for m in MODEL_NAMES:
            pt = share_tables[sig]
            plots.curve(ax2, pt.index, pt[f"p_{m}"], index=k, label=f"{m}, sigma {sig:g} rad",
                        color=f"C{MODEL_NAMES.index(m)}", linestyle=dashes)  # fmt: skip
            k += 1
    plots.label_axes(ax2, "time step", "model share", f"Fig 28: model shares (mean of {runs} runs)")
    plots.legend(ax2, fontsize=6)
    return plots.save(fig, ctx.figure_path("fig27_28_mm_bootstrap")).name


def claim_e8(df8: pd.DataFrame) -> Claim:
    """C11: fused multi-sensor MMPF < single-sensor MMPF < single-model bootstrap (Fig 30)."""
    avg8 = rmse_by_method(df8, "sq_pos_err")
    return CLAIM_KINDS.claim(
        "C11_order",
        "multi-sensor MMPF < single-sensor MMPF < single-model bootstrap (Fig 30)",
        "multi < single MMPF < bootstrap",
        join_with_relations(
            [float(avg8[m]) for m in E8_ORDER], [f"{avg8[m]:.2f}" for m in E8_ORDER]
        ),
        "strict (position RMSE)",
        bool(avg8[E8_ORDER[0]] < avg8[E8_ORDER[1]] < avg8[E8_ORDER[2]]),
    )


def figures_e8(ctx: RunContext, df8: pd.DataFrame, runs: int) -> dict[str, str]:
    """Fig 30 (position RMSE over time) and Fig 29 (run 0's tracks and the sensors)."""
    rm8 = rmse_by_step(df8, "sq_pos_err")
    fig30 = plot_rmse(ctx, "fig30_rmse", rm8, rm8.columns, f"Fig 30: {runs} runs")
    fig29 = plot_run_tracks(
        ctx,
        "fig29_run0",
        df8[df8["run"] == 0],
        E8_ORDER[0],
        [*E8_ORDER, "MMPF centralised"],
        [(f"s{i}", np.array(p)) for i, p in enumerate(E8_SENSORS)],
        "Fig 29: run 0",
    )
    return {"fig30": fig30.name, "fig29": fig29.name}


def report_e5_e6(shares: np.ndarray, figs: Mapping[str, str]) -> str:
    """The report's E5 and E6 sections."""
    stat = stationary_distribution(PI_A)
    return f"""
## E5: regime transitions under Pi_A (Fig 25)

10 000 model particles, uniform at step 0, propagated with Pi_A (rows = from). Shares after 20
steps: {", ".join(f"{v:.4f}" for v in shares[-1])}; stationary distribution {", ".join(f"{v:.4f}" for v in stat)}.

![Fig 25]({figs["fig25"]})

## E6: coordinated turns (Fig 26)

![Fig 26]({figs["fig26"]})
"""


def report_e7(
    df7: pd.DataFrame,
    share_tables: Mapping[float, pd.DataFrame],
    figs: Mapping[str, str],
    n_part: int,
    runs: int,
) -> str:
    """The report's E7 section: RMSE per sigma, the MM-bootstrap's and IMM-EKF's model shares."""
    sigmas = list(share_tables)
    t7 = pd.DataFrame(
        {
            "position RMSE (all t)": df7.groupby(["sigma", "method"])["sq_pos_err"].mean().pow(0.5),
            "position RMSE (t = 7-12)": df7[df7["step"].between(7, 12)]
            .groupby(["sigma", "method"])["sq_pos_err"]
            .mean()
            .pow(0.5),
        }
    )
    shares_md = pd.concat({f"sigma {k:g}": v.T for k, v in share_tables.items()}).to_markdown(
        floatfmt=".2f"
    )
    cols = [f"p_{m}" for m in MODEL_NAMES]
    imm7 = df7[df7["method"] == "IMM-EKF"].groupby(["sigma", "step"])[cols].mean()
    imm_md = pd.concat({f"sigma {k:g}": imm7.loc[k].T for k in sigmas}).to_markdown(floatfmt=".2f")
    imm_peak = {k: int(imm7.loc[k]["p_CCW"].idxmax()) for k in sigmas}
    best7 = {k: t7.loc[k]["position RMSE (all t)"].idxmin() for k in sigmas}
    return f"""
## E7: MM-bootstrap through a sharp anticlockwise turn (Figs 27-28)

Truth: start (10, 30) m at (1, 0) m/s, CV with Q_m = 0.01 I, anticlockwise turn at a_m = 0.5 during
steps {E7_TURN} (about 86 degrees), then CV; one bearing sensor at the origin, sigma = 0.05 rad
(spec choice, sigma^2 = 0.0025) and, as a second reading, sigma = 0.005 rad; {n_part} particles,
3 models with the spec's 3-model matrix; {runs} runs. The thesis prints neither the matrix nor the
numbers.

{t7.to_markdown(floatfmt=".3f")}

Model shares of the MM-bootstrap (mean over runs):

{shares_md}

IMM-EKF (beyond the paper: the same three models and matrix, one EKF per model) regime
probabilities (mean over runs); its CCW probability peaks at t = {imm_peak[sigmas[0]]} (sigma
{sigmas[0]:g}) and t = {imm_peak[sigmas[1]]} (sigma {sigmas[1]:g}):

{imm_md}

Lowest position RMSE over all steps: {"; ".join(f"sigma {k:g}: **{v}**" for k, v in best7.items())}.

![Figs 27-28]({figs["fig28"]})
"""


def report_e8(df8: pd.DataFrame, figs: Mapping[str, str], n_part: int, runs: int) -> str:
    """The report's E8 section: position RMSE of every filter over all steps."""
    avg8 = rmse_by_method(df8, "sq_pos_err")
    return f"""
## E8: multi-sensor MM-bootstrap (Figs 29-30)

Sensors at {E8_SENSORS}; the target makes four ±20 degree turns (steps {sorted(E8_TURNS)});
{n_part} particles per filter; {runs} runs (the thesis shows one). Position RMSE over all steps:

{avg8.to_frame("position RMSE").to_markdown(floatfmt=".3f")}

Lowest position RMSE: **{avg8.idxmin()}**. The IMM-EKF rows (beyond the paper) run one EKF per model
with the same models and matrix, on the first sensor alone and on all three bearings.

![Fig 29]({figs["fig29"]})

![Fig 30]({figs["fig30"]})
"""


DIFFERENCES = """
## Differences and their causes

* E7: at the spec's sigma = 0.05 rad the turn is nearly invisible: at t = 7 the CCW regime moves
  the position by only about a_m T^2/2 = 0.25 m, while one bearing at ~33 m is uncertain by ~1.7 m,
  and the turn happens mostly along the line of sight; the regime shares then barely move. With a
  ten times sharper sensor (sigma = 0.005 rad) the CCW share rises at the turn and peaks within the
  turn window. The thesis's Fig 28 (a sharp peak at t = 7) therefore implies a much more accurate
  sensor, or a geometry with the turn across the line of sight, than the spec's choice.
* The thesis's E7/E8 figures are single realisations with unstated parameters; ours are Monte Carlo
  averages under the spec's choices, so only the qualitative claims (C9-C11) are comparable.
* Single-sensor bearings-only tracking is range-unobservable for a CV leg; its error is set by the
  prior's range error and grows with time whatever the filter, so the single-sensor comparisons in
  C11 are dominated by that and not by the turns. The fused three-sensor estimate is what makes the
  target observable.
* The fusion rule (weights ∝ 1/d², distances to each sensor's own estimate) is the thesis's
  "reflectivity"; a centralised filter using all three bearings (beyond the paper) is the
  statistically efficient alternative and is shown for comparison.

"""
