"""What no tracker can beat on the model the video trackers use (issue 19, item 3): the PCRB
along the rendered videos' own truth, beside nott2009-video's error tables.

**The bound.** The posterior Cramér-Rao bound (Tichavský, Muravchik & Nehorai 1998) of the joint
tag + camera model of :class:`~fusetrack.tools.VideoRadioTracker`, with the machinery of
:mod:`.best_possible` (:func:`~.best_possible.pcrb_positions`, covariance form for the singular
noise), on the state ``[x, y, h, w, vx, vy]``:

* motion: the trackers' own :class:`~fusetrack.motion.WalkingPerson` (``q_a = 2 m/s^2``, small
  height and width noise), taken as the prior over walks;
* tag: the trackers' :class:`~fusetrack.sensors.PositionFix` (the simulated NFER tag's
  covariance) on its reporting frames (every ``TAG_EVERY``-th from frame 0);
* camera: the trackers' foot :class:`~fusetrack.sensors.HomographyCamera` with the pixel noise
  they are given (``TrackerConfig.sigma_px`` = 1 px; the report's section "The camera's
  measurement model" measures 0.2-0.3 px for a standing subject, 0.43 px median while walking),
  Fisher information ``D^T D / sigma^2`` of its analytic Jacobian at the true state, on every
  frame where the rendered subject is at least 80 % visible (``occluded_true`` false) and the
  experiment does not drop the visual update (frames 22-53 of the ``-drop`` runs), and on every
  frame where one of the case's trackers took a visual update (so the bound's camera has at
  least the frames each tracker had);
* prior: ``N(true start, P0)`` with the trackers' ``P0 = diag(1, 1, 0.01, 0.04, 1, 1)``;
* truth: the rendered foot path of each run (``true_x``, ``true_y``), its velocity by central
  differences (as :attr:`~fusetrack.world.Walk.velocity`), height 1.75 m and width 0.5 m.

The bound is for that idealised Gaussian measurement model, not for the background-subtraction
chain: the blob's foot point is not a Gaussian 1 px measurement (its error is smaller while the
subject is clear and gross while it is partly hidden), the tag's error has a correlated bias
and steps, and the rendered walks are smooth curves, not draws of the Wiener prior. A tracker
below the bound therefore means that the real data carry more information than the model the
trackers assume (e.g. a foot point better than 1 px), not necessarily a wrong bound. The
comparisons (RMS over runs against the RMS bound, the Gaussian mean-error bound for mean
errors) are those of :mod:`.best_possible`.

Sec. 5.2 of the thesis prints no tracking error ("all tracking results are qualitative plots",
spec 004): no paper number is judged against the bound.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from ...evaluation import MARGIN_SE, Claim, ClaimKinds
from .best_possible import (
    PRIOR_COV,
    CaseBound,
    ModelBound,
    above_claims,
    best_table_md,
    case_bound,
    pcrb_positions,
    span_bounds,
    table,
    tracker_errors,
)

Array = np.ndarray
SPANS = {"run": "whole video", "window": "camera-less frames"}
"""The spans: every frame, and the frames the model's camera does not report on."""
MODELS: dict[str, tuple[str, dict[str, str], bool]] = {
    "single": ("single", {"J": "J", "B4": "B4"}, False),
    "single-drop": ("single", {"J": "J-drop", "B4": "B4-drop"}, True),
    "crossing": ("crossing", {"J": "J", "B4": "B4"}, False),
    "wall": ("wall", {"J": "J", "B4": "B4"}, False),
}
"""Bound cases: ``name -> (scene, {role: tracker run}, visual updates dropped on frames
22-53)``; the raw tag held between fixes (B1) comes with every case."""
MODEL = "trackers' model (Gaussian tag, 1 px foot point)"


def _flag(s: pd.Series) -> pd.Series:
    """Booleans from a flag column that a round trip through parquet may have made strings."""
    return s.astype(str).str.lower() == "true"


def _grid(rows: pd.DataFrame, column: str) -> Array:
    """``(R, T)`` values of ``column`` by run and frame; every run must have every frame."""
    wide = rows.pivot(index="run", columns="frame", values=column).sort_index(axis=1)
    frames = wide.columns.to_numpy()
    if wide.isna().any().any() or not np.array_equal(frames, np.arange(len(frames))):
        raise RuntimeError(f"the tracking rows do not cover every frame of every run ({column})")
    return wide.to_numpy()


def case_rows(tr: pd.DataFrame, name: str) -> pd.DataFrame:
    """One bound case's rows in :func:`~.best_possible.tracker_errors`'s columns (``case``,
    ``method``, ``run``, ``step``, ``err``, ``occluded`` = the camera-less frames, ``camera``).
    The model's camera reports where the rendered subject is at least 80 % visible and the visual
    update is not dropped, and wherever one of the case's trackers took a visual update (the
    most information any of them had, so the bound holds for each)."""
    scene, roles, drop = MODELS[name]
    sc = tr[tr["scene"] == scene]
    updated = (
        sc[sc["method"].isin(list(roles.values()))]
        .assign(up=lambda d: d["reason"] == "visible")
        .groupby(["run", "frame"])["up"]
        .any()
    )
    out = []
    for role, method in {**roles, "B1": roles["J"]}.items():
        g = sc[sc["method"] == method]
        up = updated.loc[list(zip(g["run"], g["frame"]))].to_numpy(bool)
        camera = (~_flag(g["occluded_true"]) & ~(drop & _flag(g["dropped"]))).to_numpy() | up
        out.append(
            pd.DataFrame(
                {
                    "case": name,
                    "method": role,
                    "run": g["run"].to_numpy(int),
                    "step": g["frame"].to_numpy(int),
                    "err": (g["b1_err_m" if role == "B1" else "err_m"]).to_numpy(float),
                    "camera": camera,
                    "time": g["time"].to_numpy(float),
                    "true_x": g["true_x"].to_numpy(float),
                    "true_y": g["true_y"].to_numpy(float),
                }
            )
        )
    rows = pd.concat(out, ignore_index=True).rename(columns={"step": "frame"})
    j = rows[rows["method"] == "J"]
    window: Array = ~np.all(_grid(j, "camera").astype(bool), axis=0)  # (T,): none in some run
    return rows.assign(occluded=window[rows["frame"].to_numpy()]).rename(columns={"frame": "step"})


def truths(j: pd.DataFrame, height: float = 1.75, width: float = 0.5) -> Array:
    """``(R, T, 6)`` true states from one case's J rows: the rendered foot path, its central
    difference velocity, the rendered height and width."""
    j = j.rename(columns={"step": "frame"})
    xy = np.stack([_grid(j, "true_x"), _grid(j, "true_y")], axis=-1)
    t = _grid(j, "time")[0]
    v = np.gradient(xy, t, axis=1)
    hw = np.broadcast_to([height, width], (*xy.shape[:2], 2))
    return np.concatenate([xy, hw, v], axis=-1)


def report_mask(j: pd.DataFrame, tag_every: int) -> Array:
    """``(R, T, 2)``: the tag (every ``tag_every``-th frame from 0) and the camera report."""
    camera = _grid(j.rename(columns={"step": "frame"}), "camera").astype(bool)
    tag = np.broadcast_to(np.arange(camera.shape[1]) % tag_every == 0, camera.shape)
    return np.stack([tag, camera], axis=-1)


def estimate(
    df: pd.DataFrame,
    tracker: Any,
    dt: float,
    tag_every: int,
    cases: Sequence[str] = tuple(MODELS),
) -> dict[str, CaseBound]:
    """:class:`~.best_possible.CaseBound` of ``cases`` (of :data:`MODELS`), the PCRB of
    ``tracker``'s model (its ``motion``, ``tag`` and ``camera``) at frame interval ``dt``."""
    tr = df[df["part"] == "track"]
    out: dict[str, CaseBound] = {}
    for name in cases:
        rows = case_rows(tr, name)
        j = rows[rows["method"] == "J"]
        pos = pcrb_positions(
            tracker.motion,
            [tracker.tag, tracker.camera],
            truths(j),
            dt,
            report_mask(j, tag_every),
            PRIOR_COV,
        )
        window = j[j["run"] == j["run"].min()].sort_values("step")["occluded"].to_numpy(bool)
        spans = {"run": np.ones(len(window), bool)}
        if window.any():
            spans["window"] = window
        bound = ModelBound(*span_bounds(pos, spans), float("nan"))
        out[name] = case_bound(name, bound, tracker_errors(rows, 0))
    return out


def claims(kinds: ClaimKinds, bounds: Mapping[str, CaseBound]) -> list[Claim]:
    """Diagnostic per case: the joint tracker's RMS error is not below the bound."""
    return above_claims(kinds, bounds, SPANS, MODEL)


def noise_sensitivity(
    df: pd.DataFrame, trackers: Mapping[str, Any], dt: float, tag_every: int
) -> pd.DataFrame:
    """The single-person bound with the camera's pixel noise of each of ``trackers`` (labelled
    readings of the noise): how much of the gap to the trackers the assumed 1 px explains."""
    rows = []
    for label, tracker in trackers.items():
        cb = estimate(df, tracker, dt, tag_every, ("single",))["single"]
        rms = cb.bound.rms["run"]
        rows.append(
            {
                "foot-point noise": label,
                "sigma (px)": tracker.cfg.sigma_px,
                "PCRB RMS (m)": rms,
                "J RMS (m)": cb.rms["run"]["J"][0],
                "J / PCRB": cb.rms["run"]["J"][0] / rms,
            }
        )
    return pd.DataFrame(rows)


def mean_table(bounds: Mapping[str, CaseBound]) -> pd.DataFrame:
    """Per case and span: every method's mean error beside the Gaussian mean-error bound."""
    rows = []
    for name, cb in bounds.items():
        for span in cb.spans:
            rows.append(
                {
                    "case": f"{name} ({SPANS[span]})",
                    "mean-error bound (m)": cb.bound.mean[span],
                    **{f"{m} mean (m)": v for m, v in cb.mean[span].items()},
                }
            )
    return pd.DataFrame(rows)


def report(bounds: Mapping[str, CaseBound], runs: int, sensitivity: pd.DataFrame) -> str:
    """Report text: the bound per case beside the trackers' RMS and mean errors, and the
    single-person bound under other readings of the pixel noise (:func:`noise_sensitivity`)."""
    return f"""
## The best possible on the trackers' model

What no tracker can beat (issue 19): the posterior Cramér-Rao bound (PCRB, Tichavský et al.
1998, covariance form) of the model the trackers assume, along the {runs} rendering(s)' own
truth: the trackers' walking-person motion (q_a = 2 m/s^2) as the prior over walks, the tag as
a Gaussian fix with the trackers' covariance on its 5 Hz frames, the foot point as a Gaussian
1 px measurement (the trackers' sigma) on every frame where the subject is at least 80 %
visible in the rendering and the visual update is not dropped or where a tracker of the case
took a visual update, prior N(true start, P0) with the
trackers' P0. It is the bound of that idealised Gaussian model, not of the background-
subtraction chain: the blob's foot point is better than 1 px while the subject is clear (the
camera section below) and worse while it is partly hidden, and the rendered walks are smooth
curves rather than draws of the prior, so a tracker may beat it; `BP_J_above_bound_*` check
that the joint tracker does not (more than {MARGIN_SE:g} standard errors below, none with one
run). Cases: the single-person video (J, B4), the same with the visual updates dropped on
frames 22-53 (J = J-drop, B4 = B4-drop), the crossing and the walk behind the wall; B1 is the
raw tag held between fixes, the trivial estimator; "camera-less frames" are those where the
model's camera does not report (occluded or dropped). RMS: root of the mean over runs of each
run's mean square error over the frames (± s.e.), against sqrt(mean over the frames of the
trace of the bound's position block); "best" is the lowest RMS among J, B4 and B1.

{best_table_md(table(bounds, SPANS))}

Mean errors (the tables above report means) beside the mean-error bound (mean over the frames of
E|N(0, B_k)|, valid if each frame's error is centred Gaussian with covariance at least the bound):

{best_table_md(mean_table(bounds))}

How much of the gap on the single-person video the assumed 1 px explains: the same bound with
the foot point's noise as the camera section below measures it (the standing subject's std,
root mean square over u and v; the walking subject's median distance of the blob's bottom
point from the true foot), not a claim:

{best_table_md(sensitivity)}

The thesis prints no tracking error for Sec. 5.2 (its results are plots; Table 5.1 is the raw
tag's accuracy at calibration points, not a tracker's), so no paper number is judged here.

"""


__all__ = [
    "MODELS",
    "SPANS",
    "case_rows",
    "claims",
    "estimate",
    "mean_table",
    "noise_sensitivity",
    "report",
    "report_mask",
    "truths",
]
