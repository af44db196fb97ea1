"""Figures: one run's scene (candidates, ghosts, every method's tracks) and GOSPA over time."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from ...evaluation import RunContext, plots
from .methods import METHODS
from .triangulation import count_ghosts

if TYPE_CHECKING:
    from .experiment import RunResult


def _draw_world(ax: Any, res: RunResult) -> None:
    g = res.scene.grid
    plots.draw_truth(ax, [res.truth.positions[:, i] for i in range(res.truth.positions.shape[1])])
    plots.draw_sensors(ax, [(sid, (x, y)) for sid, x, y in res.scene.arrays], label="array")
    ax.set_xlim(g.x0, g.x1)
    ax.set_ylim(g.y0, g.y1)
    ax.set_aspect("equal")
    plots.label_axes(ax)


def _draw_candidates(ax: Any, res: RunResult, radius: float) -> None:
    """All candidates of the run, true ones grey, ghosts red."""
    true_pts: list[np.ndarray] = []
    ghosts: list[np.ndarray] = []
    for k, cs in enumerate(res.candidates):
        present = res.truth.present(k)
        for c in cs:
            (ghosts if count_ghosts(c.point, present, radius) else true_pts).append(c.point)
    for pts, style, label in ((true_pts, "o", "near a target"), (ghosts, "x", "ghost / clutter")):
        a = np.array(pts).reshape(-1, 2)
        colour = "0.5" if style == "o" else "C3"
        ax.plot(a[:, 0], a[:, 1], style, ms=2.5, color=colour, alpha=0.5, label=label)
    plots.legend(ax, fontsize=7, loc="upper right")
    ax.set_title("triangulated candidates (all scans)", fontsize=9)


def scene_figure(ctx: RunContext, res: RunResult, n_arrays: int, radius: float = 2.0) -> Path:
    """Candidates and every method's confirmed tracks in one run (truth in black)."""
    fig, axes = plots.figure(2, 3, size=(13, 6.2))
    panels = axes.ravel()
    _draw_world(panels[0], res)
    _draw_candidates(panels[0], res, radius)
    for ax, name in zip(panels[1:], METHODS):
        _draw_world(ax, res)
        plots.draw_paths(ax, [tr.means for tr in res.tracks[name]], label="tracks (dot: start)",
                         mark_start=True)  # fmt: skip
        ax.set_title(f"{name}: {len(res.tracks[name])} tracks", fontsize=9)
    plots.legend(panels[1], fontsize=7, loc="upper right")
    fig.suptitle(f"One run, {n_arrays} arrays (truth black, arrays ▲)", fontsize=10)
    return plots.save(fig, ctx.figure_path(f"scene_{n_arrays}_arrays"))


def gospa_figure(ctx: RunContext, df: pd.DataFrame, times: np.ndarray) -> Path:
    """Mean GOSPA over runs at every scan, per method, for 2 and 3 arrays."""
    fig, axes = plots.panels(2, size=(11, 3.8), sharey=True)
    for ax, n in zip(axes, (2, 3)):
        for j, name in enumerate(METHODS):
            sel = df[(df.arrays == n) & (df.method == name)]["gospa_t"]
            series = np.array([np.asarray(s, float) for s in sel])
            plots.curve(ax, times[: series.shape[1]], series.mean(axis=0), index=j, label=name)
        ax.set_title(f"{n} arrays", fontsize=10)
        plots.label_axes(ax, "time (s)", "GOSPA (m), mean over runs" if n == 2 else "")
    plots.legend(axes[0])
    return plots.save(fig, ctx.figure_path("gospa_over_time"))
