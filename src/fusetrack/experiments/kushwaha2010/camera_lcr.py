"""Kushwaha 2010, Ch. V, the LCR experiment (spec E9, A-V-18): a box carried through a conference
room, tracked by T3.

The dissertation's real run (Figs 57-60): four cameras in a Large Conference Room, "a typical box"
moved in 3-D, tracker T3 with manual initialisation, frames shown at steps 1-90, the box in all
four fields of view, and the target's pixel fraction "above 1 % of the total pixels" at every step,
"perhaps the reason why tracker T3 ... works fine". There is no ground truth and no number. Spec
A-V-18 substitutes a rendered "real-like" run: a textured box (:class:`fusetrack.world.BoxTarget`)
in a 10 x 8 m room watched by four corner cameras, so that the trackers' ellipsoid model (Eq. 64;
here the ellipsoid of the box's volume) does not match the target they see. T0 and T2 run on the
same frames for comparison.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from ...evaluation import (
    Claim,
    ClaimKinds,
    Outcome,
    RunContext,
    interval_values,
    mean_interval,
    paired_interval,
    plots,
    shown_positive,
)
from ...filters import TrackerSettings
from ...sensors import EllipsoidCamera
from ...world import BoxTarget, corner_cameras, smooth_trajectory
from . import best_possible as bp
from .cameras import (
    ABLATIONS,
    SETUPS,
    TRACKERS,
    error_rows,
    reference_model,
    scene_bound,
    scene_from_truth,
)
from .cameras import track as track_scene
from .cameras import trackers as all_trackers

ROOM = (10.0, 8.0, 3.0)  # [C] the paper's Fig. 57 gives no dimensions; spec A-V-18: 10 x 8 m
CAMERA_HEIGHT = 2.8
FOCAL = 260.0  # px at 160 x 120: the box covers > 1.2 % of every image anywhere in the region
BOX = BoxTarget(half_sizes=(0.3, 0.22, 0.18), checker=0.1)  # a 60 x 44 x 36 cm carton
CARRY_LOW, CARRY_HIGH = (3.5, 3.0, 0.7), (6.5, 5.0, 1.5)  # where the box is carried
SPEED = 0.1  # m/step: walking pace at a few frames per second
ROTATION_DEG = 3.0  # the box turns in the carrier's hands
BASE = (0.0, 0.0, 0.0)  # base station at a corner (root of the routing tree)
LCR_TRACKERS = ("T3", "T2", "T0")
FRAME_STEPS = (1, 15, 30, 50, 70, 90)  # the steps of the paper's Fig. 58
IMAGE_PIXELS = 160 * 120


def lcr_cameras() -> list[EllipsoidCamera]:
    """Four cameras at the upper corners of the room, looking at its centre (Fig. 57, [C])."""
    return corner_cameras(room=ROOM, height=CAMERA_HEIGHT, focal=FOCAL)


def error_bound() -> float:
    """T3 "works" when its error stays below the box's smallest half-size: a point that close to
    the box's centre lies inside the box whatever its orientation, so the estimate is on the box."""
    return float(min(BOX.half_sizes))


def run_once(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    """One carried-box path rendered by the four cameras; T3, T2 and T0 on its frames. One row per
    tracker and step, with the estimate, the truth and each camera's pixel fraction."""
    rng = np.random.default_rng(seed)
    cams = lcr_cameras()
    truth = smooth_trajectory(
        rng, int(config["steps"]), CARRY_LOW, CARRY_HIGH, SPEED, rotation_deg=ROTATION_DEG
    )
    scene = scene_from_truth(cams, BOX, reference_model(BOX), truth, BASE, rng)
    settings = TrackerSettings(
        n_particles=int(config["n_particles"]),
        n_particles_2d=int(config["n_particles_2d"]),
        sigma=SETUPS["a"].sigma,
    )
    built = all_trackers(scene.net, settings)
    fractions = scene.frames.target_pixels / IMAGE_PIXELS
    rows: list[dict[str, Any]] = []
    for name in LCR_TRACKERS:
        trng = np.random.default_rng([seed, [*TRACKERS, *ABLATIONS].index(name)])
        beliefs = track_scene(built[name], scene, trng)
        for row, belief in zip(error_rows(name, beliefs, scene), beliefs):
            t = row["t"]
            rows.append(
                {
                    **row,
                    **dict(zip(("x", "y", "z"), map(float, belief.position))),
                    **dict(zip(("true_x", "true_y", "true_z"), map(float, truth.positions[t]))),
                    "min_camera_fraction": float(fractions[t].min()),
                }
            )
    return scene_bound(rows, scene)


def run_errors(df: pd.DataFrame) -> pd.DataFrame:
    """Mean 3-D error over the steps of each run (rows) and tracker (columns)."""
    return df.groupby(["run", "tracker"])["err3d"].mean().unstack("tracker")


BOUND_CLAIM = "BP_lcr_trackers_above_bound"
CLAIM_KINDS = ClaimKinds(
    {
        "BP_*": "diagnostic",  # the best possible (issue 19): every tracker above the PCRB
        "lcr_in_all_four_views": "diagnostic",  # checks of our set-up against Figs 58-60
        "lcr_pixel_fraction_above_1pct": "diagnostic",
        "lcr_t3_tracks_box": "paper",  # "T3 works fine", made falsifiable by error_bound()
        "lcr_*": "diagnostic",  # T3 against T2 / T0: the paper runs only T3 here
    }
)


def _setup_claims(t3: pd.DataFrame) -> list[Claim]:
    four = bool((t3.participating == 4).all())
    low_cam = float(t3.min_camera_fraction.min())
    low_mean = float(t3.groupby(["run", "t"]).pixel_fraction.first().min())
    return [
        CLAIM_KINDS.claim(
            "lcr_in_all_four_views",
            "the box is in all four cameras' views (at least 12 target pixels) at every step of "
            "every run",
            "the moving target was in the fields-of-view of four cameras",
            {"min cameras": int(t3.participating.min())},
            "4 participating cameras at every step",
            four,
        ),
        CLAIM_KINDS.claim(
            "lcr_pixel_fraction_above_1pct",
            "the box covers more than 1 % of the image in every camera at every step of every run "
            "(so also in their average, Fig. 60's quantity)",
            "above 1 % of the total pixels at all time steps (Fig. 60)",
            {
                "min over cameras and steps (%)": round(100 * low_cam, 3),
                "min over steps of the camera average (%)": round(100 * low_mean, 3),
            },
            "min over cameras and steps > 1 %",
            low_cam > 0.01,
        ),
    ]


def _tracker_claims(runs: pd.DataFrame) -> list[Claim]:
    bound = error_bound()
    t3 = mean_interval(runs["T3"])
    t3_t2 = paired_interval(runs["T2"], runs["T3"])
    t3_t0 = paired_interval(runs["T3"], runs["T0"])
    return [
        CLAIM_KINDS.claim(
            "lcr_t3_tracks_box",
            f"T3 tracks the box: its mean 3-D error over the steps of a run stays below the box's "
            f"smallest half-size ({bound:.2f} m; closer than that the estimate lies inside the box "
            "whatever its orientation), judged by the 95 % t-interval over runs",
            "tracker T3 ... works fine (no number)",
            {"T3 mean error (m) (mean, 95% half-width)": interval_values(t3)},
            f"upper end of the 95 % t-interval of the per-run mean error < {bound:.2f} m",
            bool(np.isfinite(t3[0]) and t3[0] + t3[1] < bound),
        ),
        CLAIM_KINDS.claim(
            "lcr_t3_beats_t2",
            "with > 1 % pixels T3 tracks the box better than T2 (the paper's conclusion: T3 "
            "better when the target occupies a significant number of pixels)",
            "T3 better than T2 on large targets (Ch. V conclusion); T2 not run on LCR",
            {"T2 - T3 (m) (mean, 95% half-width)": interval_values(t3_t2)},
            "95 % paired t-interval of T2 - T3 over runs above 0",
            shown_positive(t3_t2),
        ),
        CLAIM_KINDS.claim(
            "lcr_t0_beats_t3",
            "T0 tracks the box better than T3 (setup A's ranking: T0 best)",
            "T0 best, then T3/T4 (setup A); T0 not run on LCR",
            {"T3 - T0 (m) (mean, 95% half-width)": interval_values(t3_t0)},
            "95 % paired t-interval of T3 - T0 over runs above 0",
            shown_positive(t3_t0),
        ),
    ]


def _figures(ctx: RunContext, df: pd.DataFrame) -> list[str]:
    """Fig. 59 analogue (run 0's estimated and true paths, top view and height) and Fig. 60
    analogue (pixel fraction per step)."""
    run0 = df[df.run == df.run.min()]
    t3 = run0[run0.tracker == "T3"].sort_values("t")
    fig, axes = plots.panels(2, size=(11, 4.4))
    plots.draw_truth(axes[0], [t3[["true_x", "true_y"]].to_numpy()])
    plots.draw_paths(
        axes[0],
        [run0[run0.tracker == k].sort_values("t")[["x", "y"]].to_numpy() for k in LCR_TRACKERS],
        labels=list(LCR_TRACKERS),
        mark_start=True,
    )
    plots.draw_sensors(axes[0], [(c.sensor_id, c.centre) for c in lcr_cameras()], label="camera")
    axes[0].set_xlim(-0.5, ROOM[0] + 0.5)
    axes[0].set_ylim(-0.5, ROOM[1] + 0.5)
    axes[0].set_aspect("equal")
    plots.label_axes(axes[0], title="top view")
    plots.legend(axes[0], fontsize=7)
    plots.curves(
        axes[1],
        t3.t,
        {
            "truth": t3.true_z,
            **{k: run0[run0.tracker == k].sort_values("t").z for k in LCR_TRACKERS},
        },
        styles={"truth": "k-"},
    )
    plots.label_axes(axes[1], "time step", "height z (m)", "height")
    plots.legend(axes[1], fontsize=7)
    fig.suptitle("LCR analogue, run 0: estimated and true box trajectory (Fig. 59)")
    names = [plots.save(fig, ctx.figure_path("lcr_trajectory")).name]

    fig, ax = plots.panel(size=(7, 3.6))
    per_step = df[df.tracker == "T3"].groupby("t")
    plots.curves(
        ax,
        t3.t,
        {
            "run 0: mean over participating cameras": 100 * t3.pixel_fraction,
            "run 0: smallest camera": 100 * t3.min_camera_fraction,
            "all runs: smallest camera": 100 * per_step.min_camera_fraction.min(),
        },
    )
    plots.reference_line(ax, 1.0, "1 % (paper: above at all steps)")
    plots.label_axes(ax, "time step", "target pixels (% of image)", "pixel fraction (Fig. 60)")
    plots.legend(ax, fontsize=7)
    names.append(plots.save(fig, ctx.figure_path("lcr_pixel_fraction")).name)
    return names


def _text(df: pd.DataFrame, runs: pd.DataFrame, cfg: Mapping[str, Any], figs: list[str]) -> str:
    t3 = df[df.tracker == "T3"]
    table = pd.DataFrame(
        {
            "mean 3-D error (m)": runs.mean(),
            "median run (m)": runs.median(),
            "worst run (m)": runs.max(),
            "runs below bound": (runs < error_bound()).sum(),
            "2-D error (px)": df.groupby("tracker").err2d.mean(),
        }
    ).reindex(list(LCR_TRACKERS))
    best = ""
    if bp.has_bound(df):
        bound = pd.DataFrame({"mean 3-D error (m)": bp.bound_row(df)})
        table = pd.concat([table, bound])
        best = bp.section(bp.bound_table(df, LCR_TRACKERS), BOUND_CLAIM)
    per_t = df.groupby(["tracker", "t"])["err3d"].median().unstack(0)
    shown = [t for t in FRAME_STEPS if t in per_t.index]
    along = per_t.loc[shown, list(LCR_TRACKERS)]
    along.insert(0, "pixel % (median)", 100 * t3.groupby("t").pixel_fraction.median().loc[shown])
    a, b, c = BOX.semi_axes
    return f"""
## Set-up

The dissertation's LCR run is real video without ground truth; spec A-V-18 replaces it by a
rendered run. Four cameras (160 x 120, f = {FOCAL:.0f} px) at the upper corners ({CAMERA_HEIGHT} m)
of a {ROOM[0]:.0f} x {ROOM[1]:.0f} x {ROOM[2]:.0f} m room, looking at its centre; base station at a
corner. The target is a box of {2 * BOX.half_sizes[0]:.2f} x {2 * BOX.half_sizes[1]:.2f} x
{2 * BOX.half_sizes[2]:.2f} m with six coloured faces, each with a {BOX.checker:.2f} m checkerboard,
ray-cast exactly over cluttered backgrounds (`fusetrack.world.BoxTarget`). The trackers model it as
the ellipsoid of the same volume (semi-axes {a:.3f} x {b:.3f} x {c:.3f} m), with the reference
appearance model rendered from the box itself (26 views): the shape is the mismatch, the colours
are known, as after a manual initialisation. The box is carried on smooth random paths at
{SPEED} m/step inside ({CARRY_LOW[0]}-{CARRY_HIGH[0]}, {CARRY_LOW[1]}-{CARRY_HIGH[1]},
{CARRY_LOW[2]}-{CARRY_HIGH[2]}) m, turning {ROTATION_DEG:.0f} degrees per step about a random axis,
for {int(df.t.max()) + 1} steps; {runs.shape[0]} runs. Manual initialisation at step 0 from the
truth. M = {cfg["n_particles"]} 3-D particles (T0, T2), {cfg["n_particles_2d"]} image-plane
particles (T3), proposal sd {SETUPS["a"].sigma} m, weights rho^20 (as setup A).

## Results

Mean over steps per run, then over runs (the bound is the box's smallest half-size,
{error_bound():.2f} m):

{table.to_markdown(floatfmt=".3f")}

Median over runs of the 3-D error (m) at the steps of the paper's Fig. 58:

{along.to_markdown(floatfmt=".3f")}

![trajectory]({figs[0]})

![pixel fraction]({figs[1]})
{best}
The bound's detector sees the box's centre; the trackers model an ellipsoid of the box's volume,
a mismatch the bound does not have.

## Differences from the paper and their causes

* The paper's run is real video of a real box with no ground truth and no error number; ours is
  rendered with exact truth, so "T3 works fine" becomes a stated bound (`lcr_t3_tracks_box`).
* Room size, camera poses, the box, its path and speed, and every tracker constant are the spec's
  or our choices ([C]); the paper's Fig. 57 shows the layout only as a sketch. The camera focal
  length is chosen so that the box fills more than 1 % of every image, as Fig. 60 reports, so
  `lcr_pixel_fraction_above_1pct` checks our set-up against the paper's, it is not a result.
* The paper runs only T3 on LCR; T2 and T0 are added on the same frames as diagnostics.
* The model mismatch is the silhouette only: the box's colours and texture enter the reference
  model, while the likelihood regions are the projected ellipses of the equal-volume ellipsoid.
"""


def run(ctx: RunContext) -> Outcome:
    runs_n = ctx.n_runs(full=4, quick=1)  # ~100 s per run on a shared core
    cfg = {
        "steps": 8 if ctx.quick else 91,
        "n_particles": 150 if ctx.quick else 500,
        "n_particles_2d": 60 if ctx.quick else 200,
    }
    df = ctx.monte_carlo(run_once, [cfg], runs_n, desc="carried-box paths")
    runs = run_errors(df)
    claims = _setup_claims(df[df.tracker == "T3"]) + _tracker_claims(runs)
    if bp.has_bound(df):
        table = bp.bound_table(df, LCR_TRACKERS)
        claims.append(bp.above_claim(CLAIM_KINDS, BOUND_CLAIM, table, "LCR analogue"))
    return Outcome(df, claims, _text(df, runs, cfg, _figures(ctx, df)), runs_n)


__all__ = ["BOX", "error_bound", "lcr_cameras", "run", "run_errors", "run_once"]
