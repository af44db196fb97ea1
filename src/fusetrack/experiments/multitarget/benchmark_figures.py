"""Figures of ``multitarget-benchmark``: GOSPA and its parts over time, the number of targets
over time, and one run's tracks over the truth (drawn with :mod:`fusetrack.evaluation.drawing`)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from ...evaluation import RunContext, plots
from .benchmark_scenario import HALF, RADAR_SITE
from .benchmark_trackers import TRACKERS

if TYPE_CHECKING:
    from .benchmark import RunResult

SCENARIO_ORDER = ("sparse", "dense", "crossing")


def _mean_series(df: pd.DataFrame, scenario: str, tracker: str, column: str) -> np.ndarray:
    sel = df[(df.scenario == scenario) & (df.tracker == tracker)][column]
    return np.array([np.asarray(s, float) for s in sel]).mean(axis=0)


def gospa_figure(ctx: RunContext, df: pd.DataFrame) -> Path:
    """Mean over runs at every scan: GOSPA (m) and its localisation, missed and false parts
    (m^2), per tracker, one column per scenario."""
    rows = (
        ("gospa_t", "GOSPA (m)"),
        ("localisation_t", "localisation (m²)"),
        ("missed_t", "missed (m²)"),
        ("false_t", "false (m²)"),
    )
    fig, axes = plots.figure(len(rows), 3, size=(13, 10), sharex="col")
    for j, scenario in enumerate(SCENARIO_ORDER):
        for i, (col, label) in enumerate(rows):
            ax = axes[i, j]
            for c, name in enumerate(TRACKERS):
                y = _mean_series(df, scenario, name, col)
                plots.curve(ax, np.arange(y.size), y, index=c, label=name, lw=1.2)
            if j == 0:
                ax.set_ylabel(label)
        axes[0, j].set_title(scenario, fontsize=10)
        axes[-1, j].set_xlabel("scan (s)")
    plots.legend(axes[0, 0])
    return plots.save(fig, ctx.figure_path("gospa_over_time"))


def cardinality_figure(ctx: RunContext, df: pd.DataFrame) -> Path:
    """Mean over runs of the true number of targets and of each tracker's number of tracks
    (the GM-PHD: its intensity's mass) at every scan."""
    fig, axes = plots.panels(3, size=(13, 3.8))
    for ax, scenario in zip(axes, SCENARIO_ORDER):
        truth = _mean_series(df, scenario, "GNN", "true_count_t")
        ax.plot(np.arange(truth.size), truth, "k-", lw=2.2, alpha=0.55, label="truth")
        for c, name in enumerate(TRACKERS):
            y = _mean_series(df, scenario, name, "estimated_count_t")
            label = "GM-PHD (mass)" if name == "GM-PHD" else name
            plots.curve(ax, np.arange(y.size), y, index=c, label=label, lw=1.2)
        ax.set_title(scenario, fontsize=10)
        plots.label_axes(ax, "scan (s)", "number of targets / tracks" if ax is axes[0] else "")
    plots.legend(axes[0])
    return plots.save(fig, ctx.figure_path("cardinality_over_time"))


def _draw_truth(ax: Any, res: RunResult) -> None:
    pos = res.world.states[..., :2]
    plots.draw_truth(ax, [pos[:, i] for i in range(pos.shape[1])])
    plots.draw_sensors(ax, [("radar", RADAR_SITE)], label="radar")
    ax.set_xlim(RADAR_SITE[0] - 50, HALF + 50)
    ax.set_ylim(RADAR_SITE[1] - 50, HALF + 50)
    ax.set_aspect("equal")
    plots.label_axes(ax)


def tracks_figure(ctx: RunContext, res: RunResult, scenario: str) -> Path:
    """One run: the position reports (grey: target, red: clutter) and every tracker's tracks
    over the truth (black; the radar ▲)."""
    cols = (len(TRACKERS) + 2) // 2  # the reports' panel and one per tracker, two rows
    fig, axes = plots.figure(2, cols, size=(4.3 * cols, 8.6))
    panels = axes.ravel()
    plots.hide_unused(panels, len(TRACKERS) + 1)
    _draw_truth(panels[0], res)
    pos = [
        (m.value, o)
        for m, o in zip(res.scans.measurements, res.scans.origins)
        if m.sensor_id == "pos"
    ]
    for clutter, colour in ((False, "0.5"), (True, "C3")):
        pts = np.array([v for v, o in pos if (o < 0) == clutter]).reshape(-1, 2)
        label = "clutter" if clutter else "target reports"
        panels[0].plot(pts[:, 0], pts[:, 1], ".", ms=2, color=colour, alpha=0.5, label=label)
    plots.legend(panels[0], fontsize=7, loc="upper left")
    panels[0].set_title("position reports (all scans)", fontsize=9)
    for ax, name in zip(panels[1:], TRACKERS):
        _draw_truth(ax, res)
        plots.draw_paths(ax, [tr.means for tr in res.tracks[name]], label="tracks (dot: start)",
                         mark_start=True)  # fmt: skip
        ax.set_title(f"{name}: {len(res.tracks[name])} tracks", fontsize=9)
    plots.legend(panels[1], fontsize=7, loc="upper left")
    fig.suptitle(f"One run, {scenario} clutter (truth black)", fontsize=10)
    return plots.save(fig, ctx.figure_path(f"tracks_{scenario}"))
