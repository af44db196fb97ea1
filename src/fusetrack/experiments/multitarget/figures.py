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
    for i in range(res.truth.positions.shape[1]):
        p = res.truth.positions[:, i]
        ax.plot(p[:, 0], p[:, 1], "k-", lw=2.2, alpha=0.6)
    for sid, x, y in res.scene.arrays:
        ax.plot(x, y, "k^", ms=9)
        ax.annotate(sid, (x, y), textcoords="offset points", xytext=(4, 4), fontsize=8)
    ax.set_xlim(g.x0, g.x1)
    ax.set_ylim(g.y0, g.y1)
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)


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
    ax.legend(fontsize=7, loc="upper right")
    ax.set_title("triangulated candidates (all scans)", fontsize=9)


def scene_figure(ctx: RunContext, res: RunResult, n_arrays: int, radius: float = 2.0) -> Path:
    """Candidates and every method's confirmed tracks in one run (truth in black)."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(13, 6.2))
    panels = axes.ravel()
    _draw_world(panels[0], res)
    _draw_candidates(panels[0], res, radius)
    for ax, name in zip(panels[1:], METHODS):
        _draw_world(ax, res)
        for j, tr in enumerate(res.tracks[name]):
            ax.plot(tr.means[:, 0], tr.means[:, 1], "-", lw=1.2, color=f"C{j % 10}")
            ax.plot(tr.means[0, 0], tr.means[0, 1], ".", color=f"C{j % 10}")
        ax.set_title(f"{name}: {len(res.tracks[name])} tracks", fontsize=9)
    fig.suptitle(f"One run, {n_arrays} arrays (truth black, arrays ▲)", fontsize=10)
    return plots.save(fig, ctx.figure_path(f"scene_{n_arrays}_arrays"))


def gospa_figure(ctx: RunContext, df: pd.DataFrame, times: np.ndarray) -> Path:
    """Mean GOSPA over runs at every scan, per method, for 2 and 3 arrays."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8), sharey=True)
    for ax, n in zip(axes, (2, 3)):
        for j, name in enumerate(METHODS):
            sel = df[(df.arrays == n) & (df.method == name)]["gospa_t"]
            series = np.array([np.asarray(s, float) for s in sel])
            ax.plot(
                times[: series.shape[1]], series.mean(axis=0), lw=1.3, color=f"C{j}", label=name
            )
        ax.set_title(f"{n} arrays", fontsize=10)
        ax.set_xlabel("time (s)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("GOSPA (m), mean over runs")
    axes[0].legend(fontsize=8)
    return plots.save(fig, ctx.figure_path("gospa_over_time"))
