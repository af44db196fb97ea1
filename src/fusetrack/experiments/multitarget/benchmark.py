"""``multitarget-benchmark``: every multi-target tracker of the library on 2-D constant-velocity
targets born and dying, seen by a position sensor and a range-bearing radar with ``P_D`` < 1 and
Poisson clutter (beyond the papers; fusetrack issue 17).

One run (:func:`run_once`) simulates one configuration's world and reports
(:mod:`.benchmark_scenario`), runs the trackers of :mod:`.benchmark_trackers` on the same reports
and scores them (:mod:`.benchmark_scoring`, reusing ``multitarget-bearings``' scoring). The
configurations: births and deaths in ``sparse`` and ``dense`` clutter, and a ``crossing`` of
target pairs at a shallow angle (sparse clutter). A run's seed draws the targets first, so the
sparse and dense runs of one seed share their world and differ only in the reports (common
random numbers: the clutter comparison is paired). :func:`run` repeats them, then builds the
claims (:mod:`.benchmark_claims`), figures (:mod:`.benchmark_figures`) and text
(:mod:`.benchmark_text`); beside the table, what no tracker can beat (:mod:`.benchmark_best`: the
oracle floor of :mod:`.gospa_floor` and the clairvoyant filter of :mod:`.clairvoyant`, compared
by :mod:`.best_possible`, as in ``multitarget-bearings``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from pydantic import Field

from ...core import Track
from ...evaluation import ExperimentOptions, Outcome, RunContext, run_seed
from .benchmark_best import DATA, LAYOUT, UNBOUNDED, benchmark_floor_columns, oracle_text
from .benchmark_claims import claim_kinds, make_claims, summary_table
from .benchmark_figures import cardinality_figure, gospa_figure, tracks_figure
from .benchmark_scenario import (
    SCENARIOS,
    Scans,
    Setting,
    World,
    scenario_stats,
    simulate_births_and_deaths,
    simulate_crossing,
    simulate_scans,
)
from .benchmark_scoring import benchmark_score, count_bias
from .benchmark_text import report_text
from .benchmark_trackers import TRACKERS, TrackerParams, run_trackers
from .best_possible import best_claims, best_text

__all__ = ["SCENARIOS", "Options", "RunResult", "run", "run_once", "simulate_run"]

QUICK_SCANS = 15
QUICK_N_MC = 150


class Options(ExperimentOptions):
    """``--set`` keys of ``multitarget-benchmark`` (validated before any work)."""

    scans: int = Field(
        60, ge=10, le=300, description="scans per run (1 s apart); quick: at most 15"
    )
    p_detect: float = Field(0.9, gt=0.0, le=1.0, description="detection probability per sensor")
    sparse_clutter: float = Field(
        5.0, ge=0.0, le=200.0, description="false reports per sensor per scan, sparse"
    )
    dense_clutter: float = Field(
        40.0, ge=0.0, le=200.0, description="false reports per sensor per scan, dense"
    )
    birth_rate: float = Field(
        0.1, gt=0.0, le=2.0, description="target births per scan (Poisson mean)"
    )
    p_survive: float = Field(
        0.98, gt=0.0, lt=1.0, description="probability a target survives a scan"
    )
    crossing_pairs: int = Field(4, ge=1, le=4, description="crossing pairs of targets (1-4)")
    crossing_half_angle: float = Field(
        10.0, gt=0.0, le=45.0, description="half the crossing angle (degrees)"
    )
    mht_n_scan: int = Field(3, ge=0, le=10, description="MHT: scans of deferred decisions")
    mht_max_hypotheses: int = Field(10, ge=1, le=100, description="MHT: leaves per track")
    mcmcda_n_mc: int = Field(
        1000, ge=10, le=20000, description="MCMCDA moves per scan; quick: at most 150"
    )
    mcmcda_window: int = Field(10, ge=2, le=30, description="MCMCDA window (scans)")
    gospa_c: float = Field(40.0, gt=0.0, description="GOSPA / OSPA(2) cut-off c (m)")
    mot_threshold: float = Field(30.0, gt=0.0, description="CLEAR MOT match distance (m)")
    settle: int = Field(
        5, ge=0, le=50, description="scans left out before the count bias is averaged"
    )


@dataclass(frozen=True)
class RunResult:
    """One run of one configuration: the world, the reports, every tracker's tracks, the
    PHD's expected number of targets per scan."""

    world: World
    scans: Scans
    tracks: dict[str, list[Track]]
    phd_count: list[float]


def _setting(config: Mapping[str, Any], opts: Options) -> Setting:
    clutter = opts.dense_clutter if config["scenario"] == "dense" else opts.sparse_clutter
    return Setting(opts.p_detect, clutter, opts.p_survive, opts.birth_rate)


def simulate_run(config: Mapping[str, Any], seed: int) -> RunResult:
    """Simulate one configuration and run every tracker on it (draws in a fixed order)."""
    opts = Options.model_validate(config["options"])
    setting = _setting(config, opts)
    rng = np.random.default_rng(seed)
    if config["scenario"] == "crossing":
        world = simulate_crossing(
            opts.crossing_pairs, int(config["scans"]), opts.crossing_half_angle
        )
    else:
        world = simulate_births_and_deaths(setting, int(config["scans"]), rng)
    scans = simulate_scans(world, setting, rng)
    params = TrackerParams(
        opts.mht_n_scan, opts.mht_max_hypotheses, int(config["n_mc"]), opts.mcmcda_window
    )
    tracks, phd_count = run_trackers(setting, params, scans.measurements, world.times, seed + 1)
    return RunResult(world, scans, tracks, phd_count)


def run_once(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    """One row per tracker: its scores, the true and estimated counts, the run's statistics."""
    opts = Options.model_validate(config["options"])
    res = simulate_run(config, seed)
    truth, true_count = res.world.truth, res.world.counts
    stats = scenario_stats(res.world, res.scans)
    best = benchmark_floor_columns(
        config["scenario"], res.world, opts.p_detect, opts.gospa_c, np.random.default_rng(seed + 7)
    )
    rows = []
    for name in TRACKERS:
        s = benchmark_score(res.tracks[name], truth, opts.gospa_c, opts.mot_threshold)
        estimated = res.phd_count if name == "GM-PHD" else s["count_t"]
        rows.append(
            {
                "scenario": config["scenario"],
                "tracker": name,
                **stats,
                **s,
                "true_count_t": true_count.tolist(),
                "estimated_count_t": list(map(float, estimated)),
                "count_bias": count_bias(estimated, true_count, opts.settle),
                **best,
            }
        )
    return rows


def run(ctx: RunContext) -> Outcome:
    """Three configurations, five trackers, ``runs`` runs each."""
    opts = Options.of(ctx)
    runs = ctx.n_runs(full=20, quick=2)
    scans = min(opts.scans, QUICK_SCANS) if ctx.quick else opts.scans
    n_mc = min(opts.mcmcda_n_mc, QUICK_N_MC) if ctx.quick else opts.mcmcda_n_mc
    base = {"options": opts.model_dump(), "scans": scans, "n_mc": n_mc}
    configs = [{**base, "scenario": s} for s in SCENARIOS]
    df = ctx.monte_carlo(run_once, configs, runs, desc="runs")
    df = df.drop(columns=["options"], errors="ignore")
    hypotheses = make_claims(df, opts, ctx.quick)
    best = best_claims(df, LAYOUT)
    claims = [*hypotheses, *best]
    example = simulate_run({**base, "scenario": "sparse"}, run_seed(ctx.seed, 0))
    figs = [
        gospa_figure(ctx, df),
        cardinality_figure(ctx, df),
        tracks_figure(ctx, example, "sparse"),
    ]
    best_section = best_text(
        df, best, opts.gospa_c, LAYOUT, oracle_text(opts.p_detect), DATA, UNBOUNDED
    )
    body = report_text(
        df, summary_table(df), hypotheses, figs, runs, scans, n_mc, opts, best_section
    )
    return Outcome(df, claims, body, runs, beyond_the_paper={"claim_kinds": claim_kinds(claims)})
