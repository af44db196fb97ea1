"""Nott (2009), Sec. 5.1 / Figs. 5.1-5.4: the numeric simulations S1-S4, the occlusion-length
sweep, irregular tag rates and tag clock offsets (spec claims H1-H4, H11, H12).

The thesis prints no numbers for these figures, only statements; the spec turns each into a
measurable claim and gives the magnitudes of its own prototype ([PROTO]) as sanity ranges.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from ...evaluation import Claim, ClaimKinds, Outcome, RunContext, plots
from . import best_possible as bp
from .scenario import METHOD_NAMES, run_once

BURN_IN = 5
SWEEP = (3, 5, 10, 15, 30, 60)
RATES = (1, 2, 5, 15)
OFFSETS_MS = (0, 10, 50, 100, 250)
V4_CASES = ("S1-V4", "S4-ca-V4")  # the camera reports head and foot points (V4), not corners
PROTO: dict[str, Any] = {  # spec Sec. 6.3 [PROTO] (CV / CA), mean Euclidean error (m)
    "S2": {"B1": 0.632, "B2": 0.296, "B3": 0.038, "B4": 0.025, "J": 0.025},
    "S1": {"B1": 0.632, "B2": 0.308, "B3": 0.044, "B4": 0.028, "J": 0.028},
    "S3-ca": {"B4": 0.052, "J": 0.051, "B5": 0.305},
    "S3-cv": {"B4": 0.045, "J": 0.045, "B5": 0.284},
    "S4-ca": {"B4": 0.293, "J": 0.187, "B5": 0.292},
    "S4-cv": {"B4": 0.199, "J": 0.174, "B5": 0.275},
    "sweep": {
        3: (0.058, 0.059, 0.281),
        5: (0.086, 0.084, 0.280),
        10: (0.179, 0.159, 0.295),
        15: (0.304, 0.206, 0.299),
        30: (0.881, 0.249, 0.296),
        60: (2.997, 0.270, 0.294),
    },
}


def proto_by_case() -> dict[str, dict[str, float]]:
    """The [PROTO] mean errors as ``{case: {method: m}}``, the sweep's as ``sweep-L{L}``."""
    out = {case: dict(v) for case, v in PROTO.items() if case != "sweep"}
    for L, values in PROTO["sweep"].items():
        out[f"sweep-L{L}"] = dict(zip(("B4", "J", "B5"), values))
    return out


def configs() -> list[dict[str, Any]]:
    c: list[dict[str, Any]] = [
        {"case": "S1", "dynamics": "ca"},
        {"case": "S2", "dynamics": "cv"},
        {"case": "S3-ca", "dynamics": "ca", "occ_len": 3},
        {"case": "S3-cv", "dynamics": "cv", "occ_len": 3},
        {"case": "S4-ca", "dynamics": "ca", "occ_len": 15},
        {"case": "S4-cv", "dynamics": "cv", "occ_len": 15},
        {"case": "S4-ca-CAfilter", "dynamics": "ca", "occ_len": 15, "filter_model": "ca"},
    ]
    c += [  # V4 (the thesis's Top Point / Bottom Point, spec E15) in place of V8
        {"case": "S1-V4", "dynamics": "ca", "variant": "head_foot"},
        {"case": "S4-ca-V4", "dynamics": "ca", "occ_len": 15, "variant": "head_foot"},
    ]
    c += [{"case": f"sweep-L{L}", "dynamics": "ca", "occ_len": L, "n_steps": 100} for L in SWEEP]
    c += [{"case": f"rate-k{k}", "dynamics": "ca", "occ_len": 15, "rfid_every": k} for k in RATES]
    c += [{"case": "rate-k5-cv", "dynamics": "cv", "occ_len": 15, "rfid_every": 5}]
    c += [
        {
            "case": f"offset-{ms}ms",
            "dynamics": "ca",
            "occ_len": 15,
            "mode": "event",
            "rfid_jitter": 0.02,
            "clock_offset": ms / 1000.0,
        }
        for ms in OFFSETS_MS
    ]
    return c


def _means(df: pd.DataFrame, case: str, window: bool) -> pd.Series:
    d = df[(df["case"] == case) & (df["step"] >= BURN_IN)]
    if window:
        d = d[d["occluded"]]
    return d.groupby("method")["err"].mean()


def _plot_case(ctx: RunContext, df: pd.DataFrame, case: str, title: str) -> str:
    d = df[(df["case"] == case) & (df["run"] == 0)]
    fig, axes = plots.panels(2, size=(11, 3.8))
    truth = d[d["method"] == "J"]
    occ = truth["occluded"].to_numpy()
    t = truth["step"].to_numpy()
    for ax, axis in zip(axes, ("x", "y")):
        if occ.any():
            plots.shade_intervals(ax, [(t[occ][0] - 0.5, t[occ][-1] + 0.5)], "occluded")
        ax.plot(t, truth[f"true_{axis}"], "k-", lw=2, alpha=0.6, label="true")
        for i, m in enumerate(("B1", "B2", "B4", "B5", "J")):
            dm = d[d["method"] == m]
            plots.curve(ax, dm["step"], dm[axis], index=i, label=f"{m} {METHOD_NAMES[m]}",
                        lw=1.2)  # fmt: skip
        plots.label_axes(ax, "time instant", f"{axis} (m)")
    plots.legend(axes[0], fontsize=7)
    fig.suptitle(title)
    return plots.save(fig, ctx.figure_path(f"{case}_xy")).name


def _plot_errors(ctx: RunContext, df: pd.DataFrame, case: str) -> str:
    d = df[df["case"] == case]
    fig, ax = plots.panel(size=(7, 3.8))
    occ = d[d["method"] == "J"].groupby("step")["occluded"].first()
    if occ.any():
        plots.shade_intervals(ax, plots.runs_of(occ.to_numpy(), occ.index.to_numpy()), "occluded")
    for i, m in enumerate(("B1", "B2", "B3", "B4", "B5", "J")):
        s = d[d["method"] == m].groupby("step")["err"].mean()
        plots.curve(ax, s.index, s.to_numpy(), index=i, label=f"{m} {METHOD_NAMES[m]}")
    ax.set_yscale("log")
    plots.label_axes(ax, "time instant", "mean position error (m)", f"{case}: mean error over runs")
    plots.legend(ax, fontsize=7)
    return plots.save(fig, ctx.figure_path(f"{case}_error")).name


def _tables(df: pd.DataFrame) -> dict[str, pd.Series]:
    """Mean error per method: S1/S2 over the run, S3/S4 (and the 8-D CA filter) in the window."""
    tables = {case: _means(df, case, window=False) for case in ("S1", "S2")}
    tables["S1-V4"] = _means(df, "S1-V4", window=False)
    for case in ("S3-ca", "S3-cv", "S4-ca", "S4-cv", "S4-ca-CAfilter", "S4-ca-V4"):
        tables[case] = _means(df, case, window=True)
    return tables


def _sweep_rate_offset(df: pd.DataFrame) -> tuple[pd.DataFrame, ...]:
    """Window errors over the occlusion-length sweep and the tag rates; whole-run and window
    errors over the clock offsets."""
    sweep = pd.DataFrame({L: _means(df, f"sweep-L{L}", window=True) for L in SWEEP}).T
    rate = pd.DataFrame({k: _means(df, f"rate-k{k}", window=True) for k in RATES}).T
    rate.loc["5 (CV)"] = _means(df, "rate-k5-cv", window=True)
    off = pd.DataFrame({ms: _means(df, f"offset-{ms}ms", window=False) for ms in OFFSETS_MS}).T
    off_w = pd.DataFrame({ms: _means(df, f"offset-{ms}ms", window=True) for ms in OFFSETS_MS}).T
    return sweep, rate, off, off_w


# Each claim's kind (fusetrack.evaluation.KINDS), by id or fnmatch pattern, first match.
CLAIM_KINDS = ClaimKinds(
    {
        "consistency": "diagnostic",  # NEES: not in the thesis
        "V4-*": "diagnostic",  # a reading of the camera measurement (TP/BP points, spec E15)
        "BP_*": "diagnostic",  # the best possible on the simulated model (issue 19, item 3)
        "H*": "paper",
    }
)


def _h1_h2_claims(tables: dict[str, pd.Series]) -> list[Claim]:
    """H1 (joint beats the tag alone, S1 and S2) and H2 (visual EKF as good without occlusion)."""
    claims: list[Claim] = []
    for case in ("S1", "S2"):
        m = tables[case]
        ratio = float(min(m["B1"], m["B2"]) / m["J"])
        claims.append(
            CLAIM_KINDS.claim(
                f"H1-{case}",
                f"{case}: the joint tracker beats the RFID tracker (raw and KF) by >= 5x (mean error after burn-in)",
                "J better than RFID [PROTO J 0.025-0.028 m vs B2 ~0.30 m]",
                ratio,
                ">= 5",
                ratio >= 5,
            )
        )
    m = tables["S1"]
    rel = float(abs(m["B4"] - m["J"]) / m["J"])
    claims.append(
        CLAIM_KINDS.claim(
            "H2",
            "S1 (no occlusion): the visual EKF is about as good as the joint tracker, |B4 - J| / J",
            "visual 'as good as the joint tracker'",
            rel,
            "< 0.2",
            rel < 0.2,
        )
    )
    claims.append(
        CLAIM_KINDS.claim(
            "H2-raw",
            "S1: the raw visual measurement (B3) is noisier than the joint tracker, B3 / J",
            "visual 'much more noisy' (S2)",
            float(m["B3"] / m["J"]),
            "> 1",
            m["B3"] > m["J"],
        )
    )
    return claims


def _h3_claims(tables: dict[str, pd.Series]) -> list[Claim]:
    """H3: in a short occlusion joint beats switching to the tag, and matches the visual EKF."""
    claims: list[Claim] = []
    for case in ("S3-ca", "S3-cv"):
        w = tables[case]
        ratio = float(w["B5"] / w["J"])
        claims.append(
            CLAIM_KINDS.claim(
                f"H3-{case}",
                f"{case} (3-step occlusion): joint beats switching to the wireless tracker in the window, B5 / J",
                "combined more accurate than switching [PROTO 0.051 vs 0.305 m]",
                ratio,
                ">= 3",
                ratio >= 3,
            )
        )
        rel = float(abs(w["B4"] - w["J"]) / w["J"])
        claims.append(
            CLAIM_KINDS.claim(
                f"H3-{case}-B4",
                f"{case}: in a short occlusion the visual EKF is about as good as the joint one, |B4 - J| / J",
                "J ~ B4 (spec)",
                rel,
                "< 0.25",
                rel < 0.25,
            )
        )
    return claims


def _h4_claims(df: pd.DataFrame, tables: dict[str, pd.Series]) -> list[Claim]:
    """H4: in a long occlusion the visual EKF diverges and the joint tracker stays better."""
    claims: list[Claim] = []
    for case in ("S4-ca", "S4-cv"):
        w = tables[case]
        d = df[(df["case"] == case) & df["occluded"]]
        b4 = d[d["method"] == "B4"].groupby("step")["err"].mean()
        jj = d[d["method"] == "J"].groupby("step")["err"].mean()
        slope = float(np.polyfit(b4.index.to_numpy(float), b4.to_numpy(), 1)[0])
        claims.append(
            CLAIM_KINDS.claim(
                f"H4-{case}-diverges",
                f"{case} (15-step occlusion): the visual EKF's error grows through the window (slope, m/step)",
                "'the visual tracker diverges gradually'",
                slope,
                "> 0",
                slope > 0,
            )
        )
        claims.append(
            CLAIM_KINDS.claim(
                f"H4-{case}-mean",
                f"{case}: joint beats the visual EKF in the window, B4 / J (mean)",
                "'the joint wireless and visual tracker performs better'",
                float(w["B4"] / w["J"]),
                "> 1",
                w["B4"] > w["J"],
            )
        )
        last = float(b4.iloc[-1] / jj.iloc[-1])
        claims.append(
            CLAIM_KINDS.claim(
                f"H4-{case}-last",
                f"{case}: joint beats the visual EKF at the last occluded step, B4 / J",
                "J better",
                last,
                "> 1",
                last > 1,
            )
        )
    return claims


def _sweep_claims(sweep: pd.DataFrame, q: bool) -> list[Claim]:
    """H4 over the sweep: the gap B4 - J widens with L; the joint error stays bounded."""
    claims: list[Claim] = []
    gap = (sweep["B4"] - sweep["J"]).to_numpy()
    tol = 0.02 if q else 0.01
    widens = bool(np.all(np.diff(gap) > -tol)) and gap[-1] > gap[0]
    claims.append(
        CLAIM_KINDS.claim(
            "H4-sweep",
            "occlusion-length sweep L = 3..60 (CA): the gap B4 - J in the window widens with L (m, at L = 60)",
            "[PROTO gap 0.00 at L=3 .. 2.73 m at L=60]",
            float(gap[-1]),
            f"non-decreasing within {tol} m",
            widens,
        )
    )
    bounded = float(sweep["J"].max())
    claims.append(
        CLAIM_KINDS.claim(
            "H4-sweep-bounded",
            "sweep: the joint tracker's window error stays bounded near the RFID KF level (max over L, m)",
            "[PROTO <= 0.27 m]",
            bounded,
            "<= 1.2 x max B2",
            bounded <= 1.2 * float(sweep["B2"].max()),
        )
    )
    return claims


def _rate_offset_claims(rate: pd.DataFrame, off: pd.DataFrame, off_w: pd.DataFrame) -> list[Claim]:
    """H12 (irregular tag rates) and H11 (a 10 ms tag clock offset does not matter)."""
    claims: list[Claim] = []
    for k in rate.index:
        r = float(rate.loc[k, "B4"] / rate.loc[k, "J"])
        claims.append(
            CLAIM_KINDS.claim(
                f"H12-k{k}".replace(" ", ""),
                f"RFID only every {k}th frame, 15-step occlusion: joint not worse than the visual EKF in the window, B4 / J",
                "J <= B4 [PROTO k=5: CA 0.199/0.216 ... CV slightly worse]",
                r,
                ">= 1",
                r >= 1,
            )
        )
    delta = float(abs(off.loc[10, "J"] - off.loc[0, "J"]))
    delta_w = float(abs(off_w.loc[10, "J"] - off_w.loc[0, "J"]))
    claims.append(
        CLAIM_KINDS.claim(
            "H11",
            "event-driven tag clock with 20 ms jitter: a 10 ms clock offset changes the joint error by < 1 cm (whole run, m)",
            "NTP 'within 10 ms' is enough",
            delta,
            "< 0.01",
            delta < 0.01,
        )
    )
    claims.append(
        CLAIM_KINDS.claim(
            "H11-window",
            "... and inside the 15-step occlusion, where the tag carries the estimate (m)",
            "NTP 'within 10 ms' is enough",
            delta_w,
            "< 0.01",
            delta_w < 0.01,
        )
    )
    return claims


def _v4_claims(tables: dict[str, pd.Series]) -> list[Claim]:
    """H1 and H4 with the camera reporting the head and foot points (V4, Nott 2009 Sec. 3.1's
    Top Point / Bottom Point) instead of the four corners (V8), and V4 against V8."""
    s1, s4 = tables["S1-V4"], tables["S4-ca-V4"]
    h1 = float(min(s1["B1"], s1["B2"]) / s1["J"])
    h4 = float(s4["B4"] / s4["J"])
    v4_v8 = float(s1["J"] / tables["S1"]["J"])
    return [
        CLAIM_KINDS.claim(
            "V4-H1",
            "V4 (head + foot points), S1: the joint tracker beats the RFID tracker (raw and KF), "
            "min(B1, B2) / J",
            "J better than RFID (H1, camera model not stated: spec E15)",
            h1,
            ">= 5",
            h1 >= 5,
        ),
        CLAIM_KINDS.claim(
            "V4-H4",
            "V4, S4-ca (15-step occlusion): joint beats the visual EKF in the window, B4 / J",
            "'the joint wireless and visual tracker performs better' (H4)",
            h4,
            "> 1",
            h4 > 1,
        ),
        CLAIM_KINDS.claim(
            "V4-vs-V8",
            "S1: the joint error with V4 over that with V8 (two points against four corners)",
            "not reported (spec E15: 'report V4 as well')",
            v4_v8,
            "in [0.67, 1.5]",
            0.67 <= v4_v8 <= 1.5,
        ),
    ]


def _consistency_claim(df: pd.DataFrame) -> Claim:
    """The joint EKF's position NEES in S1 (not in the thesis)."""
    nees = float(
        df[(df["case"] == "S1") & (df["method"] == "J") & (df["step"] >= BURN_IN)]["nees"].mean()
    )
    return CLAIM_KINDS.claim(
        "consistency",
        "S1: the joint EKF's mean position NEES (2 = consistent)",
        "not in the thesis",
        nees,
        "in [1, 3]",
        1 <= nees <= 3,
    )


def _sweep_figure(ctx: RunContext, sweep: pd.DataFrame) -> str:
    """Window error against occlusion length, ours and the spec's prototype."""
    fig, ax = plots.panel(size=(6.5, 3.8))
    for i, m in enumerate(("B4", "J", "B5", "B2")):
        plots.curve(ax, sweep.index, sweep[m], index=i, label=f"{m} {METHOD_NAMES[m]}")
    for i, m in enumerate(("B4", "J")):
        ys = [v[i] for v in PROTO["sweep"].values()]
        plots.curve(ax, list(PROTO["sweep"]), ys, index=i, label=f"{m} [PROTO]", fmt=f"C{i}:x")
    ax.set_xscale("log")
    ax.set_yscale("log")
    plots.label_axes(ax, "occlusion length L (time instants)", "mean error in the window (m)")
    plots.legend(ax, fontsize=7)
    return plots.save(fig, ctx.figure_path("occlusion_sweep")).name


def _figures(ctx: RunContext, df: pd.DataFrame, sweep: pd.DataFrame) -> list[str]:
    """Figs. 5.1-5.4 (one run each), S4's mean error over time, the sweep; file names."""
    figs = [
        _plot_case(ctx, df, c, t)
        for c, t in (
            ("S1", "S1 (Fig. 5.1): constant acceleration, no occlusion"),
            ("S2", "S2 (Fig. 5.2): constant velocity, no occlusion"),
            ("S3-ca", "S3 (Fig. 5.3): occlusion of 3 time instants"),
            ("S4-ca", "S4 (Fig. 5.4): occlusion of 15 time instants"),
        )
    ]
    figs += [_plot_errors(ctx, df, "S4-ca")]
    figs.append(_sweep_figure(ctx, sweep))
    return figs


def _md(s: pd.Series | pd.DataFrame) -> str:
    return s.to_markdown(floatfmt=".3f")


def _ours_and_proto(tables: dict[str, pd.Series]) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Mean errors per method and case: ours, and the spec prototype's."""
    rows = []
    for case in ("S1", "S2", "S3-ca", "S3-cv", "S4-ca", "S4-cv", "S4-ca-CAfilter", *V4_CASES):
        for mth in ("B1", "B2", "B3", "B4", "B5", "J"):
            p = PROTO.get(case, {}).get(mth)
            rows.append(
                {
                    "case": case,
                    "method": f"{mth} {METHOD_NAMES[mth]}",
                    "ours (m)": tables[case].get(mth, np.nan),
                    "spec [PROTO] (m)": p if p is not None else np.nan,
                }
            )
    main = pd.DataFrame(rows).pivot(index="method", columns="case", values="ours (m)")
    proto = pd.DataFrame(rows).pivot(index="method", columns="case", values="spec [PROTO] (m)")
    main = pd.DataFrame(rows).pivot(index="method", columns="case", values="ours (m)")
    proto = pd.DataFrame(rows).pivot(index="method", columns="case", values="spec [PROTO] (m)")
    return main, proto


def _sweep_table(sweep: pd.DataFrame) -> pd.DataFrame:
    """The sweep's window errors beside the prototype's."""
    sweep_tab = sweep[["B4", "J", "B5", "B2"]].copy()
    sweep_tab["B4 [PROTO]"] = [PROTO["sweep"][L][0] for L in SWEEP]
    sweep_tab["J [PROTO]"] = [PROTO["sweep"][L][1] for L in SWEEP]
    sweep_tab.index.name = "L"
    return sweep_tab


def _worst_differences(
    tables: dict[str, pd.Series], sweep_tab: pd.DataFrame
) -> tuple[float, float, float]:
    """Largest absolute and relative difference from the prototype (cases, then the sweep)."""
    diffs = [
        (abs(tables[c][m] - p), abs(tables[c][m] - p) / p)
        for c in ("S1", "S2", "S3-ca", "S3-cv", "S4-ca", "S4-cv")
        for m, p in PROTO[c].items()
        if m != "B3"
    ]
    worst_abs = max(d[0] for d in diffs)
    worst_rel = max(d[1] for d in diffs)
    sweep_rel = float(
        np.max(
            np.abs(
                sweep_tab[["B4", "J"]].to_numpy()
                - sweep_tab[["B4 [PROTO]", "J [PROTO]"]].to_numpy()
            )
            / sweep_tab[["B4 [PROTO]", "J [PROTO]"]].to_numpy()
        )
    )
    return worst_abs, worst_rel, sweep_rel


def _report_numbers(
    tables: dict[str, pd.Series],
    sweep: pd.DataFrame,
    rate: pd.DataFrame,
    off: pd.DataFrame,
    off_w: pd.DataFrame,
    runs: int,
) -> str:
    """Report text: set-up, the thesis's words, and our numbers beside the prototype's."""
    main, proto = _ours_and_proto(tables)
    sweep_tab = _sweep_table(sweep)
    return f"""
## Set-up

Spec Sec. 6.3 defaults: 640x480 camera at (4.5, -5, 3.5) m tilted 15 degrees down, f = 500 px;
dt = 0.2 s, 50 steps (100 in the sweep), start (1, 1) m with the thesis's 3 ft/s x 2 ft/s;
CA truth acceleration (-0.10, 0.05) m/s^2; truth white acceleration 0.2 m/s^2; tag noise
0.6 m / 0.4 m, camera 1 px (both standard deviations, Nott 2009 Sec. 5.1); camera measurement
V8 (four corners); filter q_a = 0.5 m/s^2; prior (z_0, 1.70 m, 0.5 m, 0, 0) with
P0 = diag(1, 1, 0.01, 0.04, 1, 1). Errors are Euclidean foot-position errors averaged over
{runs} runs and the steps after a {BURN_IN}-step burn-in ("window": the occluded steps only).

## The thesis's figures, its words, and our numbers

The thesis (Sec. 5.1, Figs. 5.1-5.4) shows single-run plots and states:
S1 "the joint wireless and visual tracking scheme works better than the RFID tracking scheme alone
or a visual tracking scheme alone ... when there is no occlusion the visual tracker seems to work
as good as the joint tracker"; S2 "the wireless tracker and also the visual tracker are much more
noisy than the joint tracker"; S3 "the combined tracker ensures that the prediction ... is more
accurate compared to switching to the wireless tracker during occlusion"; S4 "the visual tracker
diverges gradually from the actual position ... the joint wireless and visual tracker performs
better". No error values are printed, so the numbers beside ours are the spec's prototype.

Ours (mean error, m; S1/S2 over all steps, S3/S4 in the occlusion window):

{_md(main)}

Spec prototype [PROTO] (same definitions):

{_md(proto)}

Occlusion-length sweep (CA, 100 steps, window mean error, m):

{_md(sweep_tab)}

Irregular tag rate (tag every k-th frame, 15-step occlusion, window mean, m):

{_md(rate[["B4", "J", "B2", "B5"]])}

Tag clock offset (event-driven filter, tag at 5 Hz with 20 ms jitter, 15-step occlusion; whole
run / window, joint tracker, m):

{_md(pd.DataFrame({"J whole run": off["J"], "J window": off_w["J"], "B2 whole run": off["B2"]}))}

"""


def _report_differences(
    tables: dict[str, pd.Series], sweep: pd.DataFrame, rate: pd.DataFrame, off_w: pd.DataFrame
) -> str:
    """Report text: differences from the thesis and the prototype, and their causes."""
    worst_abs, worst_rel, sweep_rel = _worst_differences(tables, _sweep_table(sweep))
    return f"""

## Differences and their causes

* The column S4-ca-CAfilter is the spec's optional 8-D constant-acceleration filter
  (state with the foot acceleration) on the same constant-acceleration walks: window error
  J {tables["S4-ca-CAfilter"]["J"]:.3f} m and B4 {tables["S4-ca-CAfilter"]["B4"]:.3f} m against the
  6-D filter's {tables["S4-ca"]["J"]:.3f} m and {tables["S4-ca"]["B4"]:.3f} m (the thesis's state
  cannot hold an acceleration, so its CA simulations used a CV filter).

* The columns S1-V4 and S4-ca-V4 repeat S1 and S4-ca with the camera reporting the head and
  foot points (V4, the thesis's Top Point / Bottom Point of Sec. 3.1 and Fig. 4.2; the width is
  then unobservable and stays in the state with process noise only) instead of the four corners
  (V8): joint error {tables["S1-V4"]["J"]:.3f} m in S1 (V8 {tables["S1"]["J"]:.3f} m), and in S4-ca's
  window J {tables["S4-ca-V4"]["J"]:.3f} m, B4 {tables["S4-ca-V4"]["B4"]:.3f} m (V8
  {tables["S4-ca"]["J"]:.3f} m, {tables["S4-ca"]["B4"]:.3f} m); claims V4-*.

* No numbers exist in the thesis for these figures; every claim above is the spec's measurable
  reading of a sentence. Against the spec's prototype, our B1, B2, B4, J and B5 differ by at most
  {worst_abs:.3f} m ({worst_rel:.0%} of the prototype's value) in the six cases above, and the
  occlusion sweep by at most {sweep_rel:.0%}; our raw-visual error B3 ({tables["S1"]["B3"]:.3f} m for S1)
  is larger than the prototype's (0.044 m) because we back-project the midpoint of the bottom
  edge of the measured box, which carries the noise of two corners and of the width.
* S2's "the visual tracker [is] much more noisy than the joint tracker" holds for the raw visual
  measurement (B3), not for the visual EKF (B4), which equals the joint tracker without occlusion:
  the 1 px camera dominates 0.6 m of tag noise by two orders of magnitude.
* The benefit of fusion during a long occlusion depends on how often the tag reports: the
  window ratio B4 / J is {", ".join(f"{r:.2f} (k = {k})" for k, r in (rate["B4"] / rate["J"]).items())};
  the claims H12 report each rate, including any that fail.
* A clock offset of 10 ms (NTP) moves a tag report by about 1 cm at walking speed against 0.6 m
  of noise; measured inside the occlusion window the joint error changes by
  {", ".join(f"{off_w.loc[ms, 'J'] - off_w.loc[0, 'J']:+.3f} m at {ms} ms" for ms in OFFSETS_MS[1:])}.
"""


def run(ctx: RunContext) -> Outcome:
    """S1-S4, the sweep, tag rates and clock offsets: estimation, claims, figures, report."""
    runs = ctx.n_runs(full=100, quick=8)
    df = ctx.monte_carlo(run_once, configs(), runs)
    tables = _tables(df)
    sweep, rate, off, off_w = _sweep_rate_offset(df)
    claims = [
        *_h1_h2_claims(tables),
        *_h3_claims(tables),
        *_h4_claims(df, tables),
        *_sweep_claims(sweep, ctx.quick),
        *_rate_offset_claims(rate, off, off_w),
        *_v4_claims(tables),
        _consistency_claim(df),
    ]
    bounds = bp.estimate(df, configs(), BURN_IN)
    proto = bp.proto_rows(bounds, proto_by_case())
    claims += [
        *bp.above_claims(CLAIM_KINDS, bounds),
        *bp.proto_claims(CLAIM_KINDS, proto),
        bp.prior_claim(CLAIM_KINDS, bounds),
    ]
    figs = _figures(ctx, df, sweep)
    body = (
        _report_numbers(tables, sweep, rate, off, off_w, runs)
        + bp.report(bounds, proto, runs, BURN_IN)
        + "\n".join(f"![{f}]({f})" for f in figs)
        + _report_differences(tables, sweep, rate, off_w)
    )
    return Outcome(df, claims, body, runs)
