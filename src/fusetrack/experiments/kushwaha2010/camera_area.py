"""Kushwaha 2010, Ch. V conclusion (spec H19): where do T2 and T3 cross over as the target's image
shrinks?

The chapter's stated conclusion [L2552]: "tracker T3 performs better if the target is close to the
camera and occupies a significant number of pixels, while tracker T2 performs better if the target
is farther away ... and occupies a very small number of pixels"; the spec asks for a sweep of the
target pixel area to find the crossover (about 1 % of the image). Here setup A's room, cameras,
paths and backgrounds are kept and only the target is scaled (its semi-axes times ``s``), so its
image area scales by ``s^2`` and nothing else changes: run ``r`` at every scale has the same path,
the same backgrounds and the same noise, and the trackers are compared run by run (paired).
Fixed orientation only (rotation is setup A's other factor, not this one's).
"""

from __future__ import annotations

import math
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
    paired_median_interval,
    plots,
    shown_positive,
)
from ...filters import TrackerSettings
from ...world import EllipsoidTarget, smooth_trajectory
from . import best_possible as bp
from .cameras import (
    ABLATIONS,
    SETUPS,
    TRACKERS,
    appearance_model,
    error_rows,
    scene_bound,
    scene_from_truth,
)
from .cameras import track as track_scene
from .cameras import trackers as all_trackers

#: target scale factors (semi-axes x s; image area x s^2): about 0.1 % to 2 % of a 160 x 120 image
SCALES = (0.25, 0.4, 0.6, 1.0)
SWEPT = ("T0", "T2", "T3")
#: the spec's reading of the paper's crossover (Fig. 53b / Fig. 60 remarks): about 1 % of the image
CROSSOVER_RANGE = (0.003, 0.03)
BOUND_CLAIM = "BP_area_trackers_above_bound"


def scaled_target(scale: float) -> EllipsoidTarget:
    """Setup A's ellipsoid with every semi-axis times ``scale`` (same colours and stripes)."""
    return EllipsoidTarget(semi_axes=tuple(scale * a for a in EllipsoidTarget().semi_axes))  # type: ignore[arg-type]


def run_once(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    """Setup A at one target scale: the path and backgrounds depend on the run only."""
    setup = SETUPS["a"]
    rng = np.random.default_rng(seed)
    truth = smooth_trajectory(rng, int(config["steps"]), setup.low, setup.high, speed=setup.speed)
    target, model = appearance_model(scaled_target(float(config["scale"])))
    scene = scene_from_truth(setup.cameras(), target, model, truth, setup.base, rng)
    settings = TrackerSettings(
        n_particles=int(config["n_particles"]),
        n_particles_2d=int(config["n_particles_2d"]),
        sigma=setup.sigma,
    )
    built = all_trackers(scene.net, settings)
    rows: list[dict[str, Any]] = []
    for name in SWEPT:
        trng = np.random.default_rng([seed, [*TRACKERS, *ABLATIONS].index(name)])
        rows += error_rows(name, track_scene(built[name], scene, trng), scene)
    return scene_bound(rows, scene)


def per_run(df: pd.DataFrame) -> pd.DataFrame:
    """Mean 3-D error of each run, scale and tracker: index ``(scale, run)``, a column per tracker."""
    return df.groupby(["scale", "run", "tracker"])["err3d"].mean().unstack("tracker")


def pixel_fractions(df: pd.DataFrame) -> pd.Series:
    """Median share of the image the target covers (over steps and participating cameras)."""
    return df[df.tracker == "T0"].groupby("scale")["pixel_fraction"].median()


def crossover(fractions: pd.Series, gap: pd.Series) -> float:
    """The pixel fraction where ``gap`` (T3 - T2, per scale) changes sign from positive (small
    target: T2 better) to negative (large: T3 better), interpolated in log fraction; ``nan`` if it
    does not change sign that way."""
    f = np.log(fractions.sort_index().to_numpy())
    g = gap.sort_index().to_numpy()
    for i in range(len(g) - 1):
        if g[i] > 0 >= g[i + 1]:
            w = g[i] / (g[i] - g[i + 1])
            return float(np.exp(f[i] + w * (f[i + 1] - f[i])))
    return math.nan


CLAIM_KINDS = ClaimKinds(
    {
        "BP_*": "diagnostic",  # the best possible (issue 19): every tracker above the PCRB
        "area_sweep_spans_1pct": "diagnostic",  # the sweep covers the range the claim is about
        "area_*": "paper",
    }
)


def _claims(runs: pd.DataFrame, fractions: pd.Series) -> list[Any]:
    small, large = min(SCALES), max(SCALES)
    lo_f, hi_f = float(fractions.loc[small]), float(fractions.loc[large])
    t2_small = paired_interval(runs.loc[small, "T3"], runs.loc[small, "T2"])
    t3_large = paired_interval(runs.loc[large, "T2"], runs.loc[large, "T3"])
    gap = runs["T3"].sub(runs["T2"]).groupby("scale")
    cross = crossover(fractions, gap.median())
    cross_mean = crossover(fractions, gap.mean())
    return [
        CLAIM_KINDS.claim(
            "area_sweep_spans_1pct",
            "the sweep's target covers well under and well over 1 % of the image",
            "< 1 % (setup B) and > 1 % (LCR)",
            {"smallest": round(100 * lo_f, 3), "largest": round(100 * hi_f, 3)},
            "median pixel share < 0.3 % at the smallest scale and > 1.5 % at the largest",
            lo_f < 0.003 and hi_f > 0.015,
        ),
        CLAIM_KINDS.claim(
            "area_t3_better_large",
            f"with the largest target ({100 * hi_f:.1f} % of the image) T3 beats T2",
            "T3 better when the target is close and occupies many pixels",
            {
                "T2 - T3 (mean, 95% half-width)": interval_values(t3_large),
                "median of T2 - T3": round(
                    paired_median_interval(runs.loc[large, "T2"], runs.loc[large, "T3"])[0], 3
                ),
            },
            "95% paired t-interval of T2 - T3 over runs above 0",
            shown_positive(t3_large),
        ),
        CLAIM_KINDS.claim(
            "area_t2_better_small",
            f"with the smallest target ({100 * lo_f:.2f} % of the image) T2 beats T3",
            "T2 better when the target is far and occupies very few pixels",
            {
                "T3 - T2 (mean, 95% half-width)": interval_values(t2_small),
                "median of T3 - T2": round(
                    paired_median_interval(runs.loc[small, "T3"], runs.loc[small, "T2"])[0], 3
                ),
            },
            "95% paired t-interval of T3 - T2 over runs above 0",
            shown_positive(t2_small),
        ),
        CLAIM_KINDS.claim(
            "area_crossover_near_1pct",
            "T2 and T3 cross over near 1 % of the image (median over runs of T3 - T2 changes "
            "sign from + at small to - at large targets)",
            "about 1 % (spec H19)",
            {
                "crossover % (medians)": round(100 * cross, 3) if math.isfinite(cross) else None,
                "crossover % (means)": round(100 * cross_mean, 3)
                if math.isfinite(cross_mean)
                else None,
            },
            f"between {100 * CROSSOVER_RANGE[0]:.1f} % and {100 * CROSSOVER_RANGE[1]:.0f} %",
            bool(CROSSOVER_RANGE[0] <= cross <= CROSSOVER_RANGE[1]),
        ),
    ]


def _table(runs: pd.DataFrame, fractions: pd.Series, df: pd.DataFrame) -> pd.DataFrame:
    by = runs.groupby("scale")
    gap = runs["T3"].sub(runs["T2"])
    bounds = {s: bp.bound_row(df[df.scale == s]) for s in SCALES} if bp.has_bound(df) else {}
    rows = {
        "target scale s": list(SCALES),
        "median pixel share (%)": [100 * float(fractions.loc[s]) for s in SCALES],
        **{f"{k} mean (m)": [float(by[k].mean().loc[s]) for s in SCALES] for k in SWEPT},
        **{f"{k} median (m)": [float(by[k].median().loc[s]) for s in SCALES] for k in SWEPT},
        "T3 - T2 mean": [float(gap.loc[s].mean()) for s in SCALES],
        "T3 - T2 median": [float(gap.loc[s].median()) for s in SCALES],
        "runs T2 better": [f"{int((gap.loc[s] > 0).sum())} of {gap.loc[s].size}" for s in SCALES],
        **{
            f"{label} (m)": [bounds[s][label] for s in SCALES]
            for label in (bp.LABELS.values() if bounds else ())
        },
    }
    return pd.DataFrame(rows)


def _figure(ctx: RunContext, runs: pd.DataFrame, fractions: pd.Series) -> str:
    """3-D error (median run, and mean) of T0, T2, T3 against the target's pixel share."""
    fig, ax = plots.panel(size=(6.2, 3.8))
    x = 100 * fractions.reindex(SCALES).to_numpy()
    by = runs.groupby("scale")
    for k, name in enumerate(SWEPT):
        line = plots.curve(
            ax, x, by[name].median().reindex(SCALES).to_numpy(), index=k, label=f"{name} median run"
        )
        plots.curve(
            ax,
            x,
            by[name].mean().reindex(SCALES).to_numpy(),
            index=k,
            label=f"{name} mean",
            color=line.get_color(),
            linestyle=":",
        )
    plots.reference_line(ax, 1.0, "1 % of the image (spec H19)", axis="x", linestyle="--")
    plots.log_axis(ax, "x")
    plots.log_axis(ax, "y")
    plots.label_axes(
        ax,
        "median target pixel share (% of the image)",
        "3-D error (m)",
        "Setup A, target scaled: T2 against T3 (spec H19)",
    )
    plots.legend(ax, fontsize=7, ncol=2)
    return plots.save(fig, ctx.figure_path("error_vs_pixel_share")).name


def run(ctx: RunContext) -> Outcome:
    runs_n = ctx.n_runs(full=8, quick=2)
    base = {
        "steps": 10 if ctx.quick else 30,
        "n_particles": 150 if ctx.quick else 1000,
        "n_particles_2d": 60 if ctx.quick else 200,
    }
    configs = [{**base, "scale": s} for s in SCALES]
    df = ctx.monte_carlo(run_once, configs, runs_n, desc="target scales")
    runs = per_run(df)
    fractions = pixel_fractions(df)
    claims = _claims(runs, fractions)
    best = ""
    if bp.has_bound(df):
        table = bp.bound_table(df, SWEPT, by=("scale",))
        claims.append(bp.above_claim(CLAIM_KINDS, BOUND_CLAIM, table, "every target scale"))
        best = bp.section(table, BOUND_CLAIM)
    fig = _figure(ctx, runs, fractions)
    body = f"""
## Set-up

Setup A (four corner cameras, 160 x 120, f = 200 px, the same room, clutter and noise) with the
target's semi-axes scaled by s in {", ".join(map(str, SCALES))} (image area x s^2); {runs_n} runs
per scale, {base["steps"]} steps, fixed orientation, M = {base["n_particles"]} 3-D particles (T0, T2)
and {base["n_particles_2d"]} image-plane particles (T3). Run r has the same path, backgrounds and
noise at every scale, so T2 and T3 (and T0) are compared on the same frames, and the scales too.

## Error against the target's pixel share

{_table(runs, fractions, df).to_markdown(index=False, floatfmt=".3f")}

"runs T2 better": runs in which T2's mean 3-D error is below T3's. The paper's conclusion
(Ch. V, [L2552]) is qualitative; the ~1 % crossover is the spec's reading of Figs 53b and 60
(setup B's target < 1 %: T2 best; LCR's > 1 %: T3 "works fine").

![error against pixel share]({fig})
{best}
The bound hardly moves with the target's size: the idealised detector sees a point whatever the
target's image area; only cameras where the small target covers fewer than 12 pixels drop out.

## Differences from the paper and their causes

* The paper has no sweep: it compares two networks (setups A and B) that differ in the camera
  layout, the distances and the number of cameras as well as in the target's image size. Here
  only the image size changes. Scaling the target is, for the cameras, the same as moving it
  away by 1/s, except that the speed of the target and the trackers' proposal spread (0.15 m)
  stay the same in metres, so a small target moves further in its own sizes per step.
* Our T3 lifts 2-D particles to 3-D Gaussians along the viewing rays (A-V-3, not described in
  the paper); how it fares with few pixels depends on that choice and on its 6 px image-plane
  proposal, which is not scaled with the target.
"""
    return Outcome(df, claims, body, runs_n)


__all__ = ["SCALES", "crossover", "run", "run_once", "scaled_target"]
