"""``multitarget-bearings``: tracking several targets from unlabelled bearings of 2 or 3 arrays
(beyond the papers; fusetrack issue 17).

One run (:func:`run_once`) simulates a scene (:mod:`.scenario`), triangulates every pair of
bearings of two arrays (:mod:`.triangulation`, ghosts included), runs the five trackers of
:mod:`.methods` on the same data and scores them (:mod:`.scoring`). :func:`run` repeats it for
2 and 3 arrays, then builds the claims (:mod:`.claims`), figures (:mod:`.figures`) and text
(:mod:`.text`); beside the table, what no tracker can beat (:mod:`.best_possible`: the oracle
floor of :mod:`.gospa_floor` and the clairvoyant filter of :mod:`.clairvoyant`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from pydantic import Field

from ...core import Track
from ...evaluation import ExperimentOptions, Outcome, RunContext, run_seed
from . import methods
from .best_possible import best_claims, best_possible_columns, best_text
from .claims import claim_kinds, make_claims, summary_table
from .figures import gospa_figure, scene_figure
from .scenario import Scene, Truth, make_scene, simulate_scans, simulate_truth
from .scoring import score
from .text import report_text
from .triangulation import Candidate, candidate_counts, scan_candidates

__all__ = ["Options", "RunResult", "run", "run_once", "simulate_run"]

ARRAY_COUNTS = (2, 3)


class Options(ExperimentOptions):
    """``--set`` keys of ``multitarget-bearings`` (validated before any work)."""

    targets: int = Field(3, ge=2, le=4, description="number of targets (2-4)")
    duration: float = Field(
        14.0, gt=2.0, le=60.0, description="scenario length (s); quick: at most 6"
    )
    sigma_deg: float = Field(2.0, gt=0.0, le=10.0, description="bearing noise std (degrees)")
    p_detect: float = Field(0.9, gt=0.0, le=1.0, description="per-array detection probability")
    clutter: float = Field(0.5, ge=0.0, le=5.0, description="clutter bearings per array per scan")
    n_mc: int = Field(
        400, ge=10, le=5000, description="MCMCDA iterations per scan; quick: at most 80"
    )
    gospa_c: float = Field(3.0, gt=0.0, description="GOSPA / OSPA(2) cut-off c (m)")
    mot_threshold: float = Field(2.0, gt=0.0, description="CLEAR MOT match distance (m)")


@dataclass(frozen=True)
class RunResult:
    """One run of one configuration: the world, the data and every method's tracks."""

    scene: Scene
    truth: Truth
    scans: list[dict[str, Any]]
    candidates: list[list[Candidate]]
    tracks: dict[str, list[Track]]


def simulate_run(config: Mapping[str, Any], seed: int) -> RunResult:
    """Simulate one scene and run every method on it (draws in a fixed order from ``seed``)."""
    opts = Options.model_validate(config["options"])
    scene = make_scene(int(config["arrays"]), opts.sigma_deg, opts.p_detect, opts.clutter)
    rng = np.random.default_rng(seed)
    truth = simulate_truth(scene, opts.targets, float(config["duration"]), rng)
    scans = simulate_scans(scene, truth, rng)
    candidates = [scan_candidates(scene, s) for s in scans]
    tracks = methods.candidate_trackers(scene, truth, candidates, np.random.default_rng(seed + 1))
    tracks["MCMCDA"] = methods.mcmcda_tracks(
        scene, truth, candidates, int(config["n_mc"]), opts.targets, np.random.default_rng(seed + 2)
    )
    tracks["grid+JPDA"] = methods.grid_tracks(scene, truth, scans, np.random.default_rng(seed + 3))
    tracks["direct"] = methods.direct_tracks(
        scene, truth, scans, candidates, np.random.default_rng(seed + 4)
    )
    return RunResult(scene, truth, scans, candidates, tracks)


def run_once(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    """One row per method: its scores, and the run's candidate counts."""
    opts = Options.model_validate(config["options"])
    res = simulate_run(config, seed)
    true_c, ghost_c = candidate_counts(res.scene, res.truth, res.candidates, opts.mot_threshold)
    best = best_possible_columns(
        res.scene,
        res.truth,
        opts.gospa_c,
        float(config["duration"]),
        np.random.default_rng(seed + 5),
    )
    return [
        {
            "arrays": int(config["arrays"]),
            "method": name,
            "true_candidates": true_c,
            "ghost_candidates": ghost_c,
            **score(res.tracks[name], res.truth, opts.gospa_c, opts.mot_threshold),
            **best,
        }
        for name in methods.METHODS
    ]


def run(ctx: RunContext) -> Outcome:
    """2 and 3 arrays, five methods, ``runs`` scenes each."""
    opts = Options.of(ctx)
    runs = ctx.n_runs(full=16, quick=2)
    duration = min(opts.duration, 6.0) if ctx.quick else opts.duration
    n_mc = min(opts.n_mc, 80) if ctx.quick else opts.n_mc
    base = {"options": opts.model_dump(), "duration": duration, "n_mc": n_mc}
    configs = [{**base, "arrays": n} for n in ARRAY_COUNTS]
    df = ctx.monte_carlo(run_once, configs, runs, desc="scenes")
    df = df.drop(columns=["options"], errors="ignore")
    table = summary_table(df)
    hypotheses = make_claims(df, ctx.quick)
    best = best_claims(df)
    example = {n: simulate_run({**base, "arrays": n}, run_seed(ctx.seed, 0)) for n in ARRAY_COUNTS}
    figs = [scene_figure(ctx, example[n], n) for n in ARRAY_COUNTS]
    figs.append(gospa_figure(ctx, df, example[2].truth.times))
    best_section = best_text(df, best, opts.gospa_c)
    body = report_text(df, table, hypotheses, figs, runs, duration, n_mc, opts, best_section)
    claims = [*hypotheses, *best]
    return Outcome(df, claims, body, runs, beyond_the_paper={"claim_kinds": claim_kinds(claims)})
