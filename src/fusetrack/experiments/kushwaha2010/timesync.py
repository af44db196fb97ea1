"""Kushwaha 2010, Ch. III: time synchronisation — its residual error, and what unsynchronised nodes cost.

The paper synchronises the mote network by time translation in the routing service, the PC
network by RBS and the two at the gateways, and gives no accuracy figure (the companion paper:
microseconds over several hops). Spec 003 §2.4 asks to check that the residual error is far
below the 250 ms fusion period and to inject offsets of 0.1–1 s to show tracking error grows.

Every run simulates one pass (:mod:`.kushwaha2010_scene`): all timestamps go through the
translation chain, and the residual (translated − true) of each packet is recorded. The same
recording is then fused (AVCP, AVCS, AP, VP) with each node's timestamps shifted by ±offset.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ...evaluation import ClaimKinds, Outcome, RunContext, plots
from .scene import (
    all_likelihoods,
    audio_prior,
    default_layout,
    fusion_input,
    run_sbe,
    simulate_single_pass,
    track_start,
)

OFFSETS = (0.0, 0.1, 0.25, 0.5, 1.0)
VARIANTS = ("AVCP", "AVCS", "AP", "VP")


def run_once(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    layout = default_layout()
    sim = simulate_single_pass(layout, np.random.default_rng(seed))
    rec, truth = sim.rec, sim.truth
    audio = np.array([p.sensor_id.startswith("A") for p in rec.packets])
    res = np.abs(rec.sync_residuals)
    rows: list[dict[str, Any]] = [
        {
            "kind": "residual",
            "network": "audio (hops + gateway + RBS)",
            "max_abs_us": float(res[audio].max() * 1e6),
            "mean_abs_us": float(res[audio].mean() * 1e6),
        },
        {
            "kind": "residual",
            "network": "video (RBS)",
            "max_abs_us": float(res[~audio].max() * 1e6),
            "mean_abs_us": float(res[~audio].mean() * 1e6),
        },
    ]
    for offset in OFFSETS:
        fin = fusion_input(rec, np.random.default_rng(seed + 7), sync_offset=offset)
        liks = all_likelihoods(layout, fin)
        start = track_start(fin, rec.audio_threshold)
        if start >= len(liks) - 1:
            continue
        prior = audio_prior(liks[start], fin.taken[start], rec.audio_threshold, layout)
        for variant in VARIANTS:
            means, _ = run_sbe(layout, liks, variant, start, prior=prior)
            err = np.linalg.norm(means[start:] - truth[start:], axis=1)
            rows.append(
                {
                    "kind": "tracking",
                    "offset": offset,
                    "variant": variant,
                    "error": float(err.mean()),
                }
            )
    return rows


# Each claim's kind (fusetrack.evaluation.KINDS), by id or fnmatch pattern, first match.
CLAIM_KINDS = ClaimKinds(
    {
        # the dissertation does not quantify time sync (spec 003, A-III-18): the spec's checks
        "small_offset_harmless": "diagnostic",
        "residual_far_below_period": "diagnostic",
        "offset_hurts_tracking": "diagnostic",
    }
)


def run(ctx: RunContext) -> Outcome:
    runs = ctx.n_runs(full=10, quick=2)
    df = ctx.monte_carlo(run_once, [{}], runs, desc="passes")
    res = df[df.kind == "residual"]
    trk = df[df.kind == "tracking"]
    worst_us = float(res.max_abs_us.max())
    err = trk.groupby(["offset", "variant"])["error"].mean().unstack("variant")
    claims = [
        CLAIM_KINDS.claim(
            "residual_far_below_period",
            "after hop translation, gateway translation and RBS the residual timestamp error is far below the 250 ms fusion period (spec: < 1 ms)",
            "µs over several hops (companion paper); < 1 ms",
            worst_us,
            "1000 µs",
            worst_us < 1000.0,
        ),
        CLAIM_KINDS.claim(
            "offset_hurts_tracking",
            "unsynchronised timestamps (±1 s per node) raise the AVCP tracking error",
            "error grows with offset",
            {str(k): float(v) for k, v in err["AVCP"].items()},
            "err(1 s) > err(0) + 0.5 m",
            bool(err["AVCP"].loc[1.0] > err["AVCP"].loc[0.0] + 0.5),
        ),
        CLAIM_KINDS.claim(
            "small_offset_harmless",
            "an offset of 0.1 s (under half the fusion period) costs less than 1 m for AVCP",
            "(spec 003 §2.4)",
            float(err["AVCP"].loc[0.1] - err["AVCP"].loc[0.0]),
            "1 m",
            bool(err["AVCP"].loc[0.1] - err["AVCP"].loc[0.0] < 1.0),
        ),
    ]
    fig = plots.plot_series(
        ctx.figure_path("error_vs_sync_offset"),
        err.index.to_numpy(),
        {v: err[v].to_numpy() for v in VARIANTS},
        xlabel="injected timestamp offset per node (s)",
        ylabel="mean tracking error (m)",
        title="Tracking error against synchronisation error",
    )
    resid = res.groupby("network")[["max_abs_us", "mean_abs_us"]].agg(
        {"max_abs_us": "max", "mean_abs_us": "mean"}
    )
    body = f"""
## Set-up

{runs} simulated passes. Clocks: offset U[0, 1] s, skew U[−50, 50] ppm per node. Audio packets:
elapsed-time translation over 1–3 mote hops (5 µs timestamping jitter per hop, 5–20 ms residence),
a gateway mote→PC map fitted on 16 paired readings (20 µs jitter), then RBS (8 beacons, 1 per s,
10 µs reception jitter) to the fusion node's clock. Video packets: RBS. Then each node's
timestamps are shifted by ±offset (random sign) and the recording is fused again.

## Residual synchronisation error

{resid.to_markdown(floatfmt=".1f")}

## Tracking error against injected offset (m)

{err.to_markdown(floatfmt=".2f")}

![Error against offset]({fig.name})

## Differences from the paper and their causes

The dissertation gives no synchronisation accuracy; our residuals are those of the simulated
protocols with the jitters above, not measurements of [141]'s implementation.
"""
    return Outcome(df, claims, body, runs)
