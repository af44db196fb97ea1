"""Kushwaha 2010, Ch. IV outdoor experiment, simulated (spec E6, H17): three nodes in an
equilateral triangle of side 9.144 m (the paper: "(15ft)", which is 4.572 m), source 1 fixed, source 2 at 0.5-8 m from it.

Fig. 34b (no numbers): "For smaller source separations, the average error remains low but the
algorithm is not able to disambiguate the two sources. For larger separations, the localization
error decreases" -- the trend of Fig. 30c. The paper's data are not available; this replica
runs the simulated pipeline of ``kushwaha2010-harmonic-sources`` (beamform over 2^14 samples at
100 kHz, 1 s PSD at 4 kHz, 30 PSD pairs, Gibbs + slice sampling, 25 dB) on the triangle. Source 1
sits at the triangle's centroid, source 2 in a random direction at each separation; run ``r``
shares its fundamentals, phases and noise across separations (paired).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from ...evaluation import (
    ClaimKinds,
    Outcome,
    RunContext,
    interval_values,
    paired_interval,
    shown_positive,
)
from ...perception import AcousticNetwork, BeamformModel, localise, match_error
from ...world import random_sources
from .harmonic_sources import FS, simulate_features

SIDE = 9.144  # m; the paper writes "9.144m (15ft)", but 9.144 m is 30 ft: the metres are used
NODES = np.array([[0.0, 0.0], [SIDE, 0.0], [SIDE / 2, SIDE * np.sqrt(3) / 2]])
CENTROID = NODES.mean(axis=0)
#: the field (uniform prior): 8.5 m about the centroid, so source 2 fits at every separation
BOX = (CENTROID[0] - 8.5, CENTROID[0] + 8.5, CENTROID[1] - 8.5, CENTROID[1] + 8.5)
SEPARATIONS = (0.5, 1.0, 2.0, 4.0, 8.0)


def second_position(separation: float, rng: np.random.Generator) -> np.ndarray:
    """Source 2 at ``separation`` m from the centroid in a random direction, inside the box and
    at least 1 m from the nodes."""
    for _ in range(1000):
        a = rng.uniform(-np.pi, np.pi)
        p = CENTROID + separation * np.array([np.cos(a), np.sin(a)])
        inside = BOX[0] <= p[0] <= BOX[1] and BOX[2] <= p[1] <= BOX[3]
        if inside and np.min(np.hypot(*(NODES - p).T)) >= 1.0:
            return np.asarray(p)
    raise RuntimeError(f"no position at {separation} m")  # pragma: no cover


def run_once(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    """One separation of one run (the run's sources differ only in source 2's position)."""
    rng = np.random.default_rng(seed)
    sep = float(config["separation"])
    direction_rng = np.random.default_rng([seed, int(1000 * sep)])
    pos = np.array([CENTROID, second_position(sep, direction_rng)])
    sources = random_sources(2, rng, field_box=BOX, avoid=NODES, positions=pos)
    net = AcousticNetwork(NODES, fs=FS, c=350.0)
    feats = simulate_features(sources, net, 25.0, rng)
    model = BeamformModel(field_box=BOX, n_samples=int(config["gibbs_samples"]))
    res = localise(net, feats, 2, rng, model=model)
    err, _ = match_error(res.positions, pos)
    single = localise(net, feats, 1, rng, model=model)  # one source asked for: the pair's blend
    return [
        {
            "separation": sep,
            "error": err,
            "error_over_separation": err / sep,
            "one_source_error": float(np.min(np.hypot(*(pos - single.positions[0]).T))),
            "prior_mean_error": match_error(np.array([PRIOR_MEAN, PRIOR_MEAN]), pos)[0],
        }
    ]


CLAIM_KINDS = ClaimKinds({"triangle_*": "paper", "BP_*": "diagnostic"})
PRIOR_MEAN = np.array([(BOX[0] + BOX[1]) / 2, (BOX[2] + BOX[3]) / 2])
"""The mean of the uniform prior over :data:`BOX`: a trivial estimator (both sources there) that
has heard nothing; it is the centroid, where source 1 stands."""


def _trivial_claims(df: pd.DataFrame) -> list[Any]:
    """Diagnostic: the localiser beats the trivial estimator that puts both sources at the prior
    mean (error: half the separation, source 1 being there), at the smallest and at the largest
    separation. At the smallest, a failure says the paper's "the average error remains low" is
    met without localising anything."""
    g = df.groupby("separation")[["error", "prior_mean_error"]].mean()
    claims = []
    for label, sep in (("close", g.index.min()), ("far", g.index.max())):
        ours, trivial = float(g.loc[sep, "error"]), float(g.loc[sep, "prior_mean_error"])
        claims.append(
            CLAIM_KINDS.claim(
                f"BP_triangle_beats_prior_mean_{label}",
                f"at {sep:g} m the localiser's mean error is below that of the prior mean (both "
                "sources at the centre of the uniform prior, the centroid)",
                "not in the paper",
                {"localiser": round(ours, 3), "prior mean": round(trivial, 3)},
                "localiser < prior mean",
                ours < trivial,
            )
        )
    return claims


def _claims(runs: pd.DataFrame) -> list[Any]:
    small, large = min(runs.columns), max(runs.columns)
    rel = runs / np.asarray(runs.columns, float)
    resolve = paired_interval(rel[small], rel[large])
    return [
        CLAIM_KINDS.claim(
            "triangle_unresolved_when_close",
            f"at {small:g} m the two sources are not disambiguated: error of the order of the "
            "separation (mean error / separation)",
            "not able to disambiguate the two sources (Fig. 34b)",
            round(float(rel[small].mean()), 3),
            ">= 0.3",
            float(rel[small].mean()) >= 0.3,
        ),
        CLAIM_KINDS.claim(
            "triangle_error_small_when_close",
            f"at {small:g} m the average error remains low (< 1 m, a ninth of the nodes' spacing)",
            "the average error remains low",
            round(float(runs[small].mean()), 3),
            "< 1 m",
            float(runs[small].mean()) < 1.0,
        ),
        CLAIM_KINDS.claim(
            "triangle_resolves_with_separation",
            f"relative to the separation, the error falls from {small:g} m to {large:g} m "
            "(paired per run)",
            "for larger separations, the localization error decreases (Fig. 34b, as Fig. 30c)",
            {"err/sep small - large (mean, 95% half-width)": interval_values(resolve)},
            "95% paired t-interval above 0",
            shown_positive(resolve),
        ),
    ]


def run(ctx: RunContext) -> Outcome:
    n_runs = ctx.n_runs(full=12, quick=1)
    seps = (0.5, 8.0) if ctx.quick else SEPARATIONS
    gibbs = 10 if ctx.quick else 40
    configs = [{"separation": s, "gibbs_samples": gibbs} for s in seps]
    df = ctx.monte_carlo(run_once, configs, n_runs, desc="separations")
    runs = df.pivot_table(index="run", columns="separation", values="error")
    table = df.groupby("separation")[["error", "error_over_separation", "one_source_error"]]
    summary = table.mean().join(table.median(), rsuffix=" (median)")
    trivial = df.groupby("separation")[["error", "one_source_error", "prior_mean_error"]].mean()
    body = f"""
## Set-up

Three nodes (4-microphone arrays) at the corners of an equilateral triangle of side 9.144 m; source 1 at the centroid, source 2 at {", ".join(f"{s:g}" for s in seps)} m from it in a
random direction; harmonic sources as in `kushwaha2010-harmonic-sources` (fundamentals 40-200 Hz,
powers ∝ 1/h), 25 dB, 30 PSD pairs, {gibbs} Gibbs samples, a uniform prior over the 17 m x 17 m
square about the centroid; {n_runs} runs per separation.
"one_source_error": one source asked for instead of two, distance to the nearer source.

## Error against separation (m)

{summary.to_markdown(floatfmt=".3f")}

## The best possible: trivial estimators beside the errors

What a localiser must beat (issue 19), mean error (m) per separation: the prior mean (both
sources at the centre of the uniform prior, which is the centroid, where source 1 stands: error
half the separation, whatever was heard) and the one-source fit (one source asked for, scored
against the nearer source). `BP_triangle_beats_prior_mean_*` check that the localiser does
better than the prior mean at the smallest and the largest separation: at the smallest, an error
"low" only because the prior is centred on source 1 is no localisation.

{trivial.to_markdown(floatfmt=".3f")}

No Cramér-Rao bound is given here: the nodes' 36 beams lie 10° apart and source 1's bearings
from the three corners (30°, 150°, 270°) fall on beams, so the strongest beam's error for source
1 is exactly zero and the runs give no bearing noise to bound with; and the localiser fits the
beam energies of both sources at once, whose information a per-source bearing model does not
describe.

## Differences from the paper and their causes

* The paper ran 3 MICAz nodes outdoors with recorded sources and the FPGA; neither the sources
  nor the positions of source 2 are given, and no numbers. This is the simulated pipeline on the
  triangle, without the FPGA's 8-bit quantisation and integer delays (spec E6 reproduction list).
* Source 1 at the centroid; the paper does not say where source 1 stood. The uniform prior is
  centred there too, so the prior mean alone scores half the separation (see the best possible).
* The side is the paper's 9.144 m; its "(15ft)" beside it is 4.572 m (9.144 m is 30 ft).
"""
    return Outcome(df, _claims(runs) + _trivial_claims(df), body, n_runs)


__all__ = ["NODES", "run", "run_once", "second_position"]
