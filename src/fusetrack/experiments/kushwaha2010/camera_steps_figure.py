"""The error along the steps of a Ch. V camera run with one event in it (Fig. 53 analogue): per
tracker the median 3-D error over runs with its inter-quartile band, the event (a one-camera gap,
an occlusion) shaded, the before / after windows the claims compare marked, and optionally a
per-step count (cameras that can use the target) on a second axis. Shared by
``kushwaha2010-cameras-gap`` and ``kushwaha2010-cameras-occlusion``."""

from __future__ import annotations

from collections.abc import Sequence

import pandas as pd

from ...evaluation import RunContext, plots


def error_along_steps(
    ctx: RunContext,
    df: pd.DataFrame,
    trackers: Sequence[str],
    event: tuple[int, int],
    event_label: str,
    windows: tuple[tuple[int, int], tuple[int, int]],
    title: str,
    stem: str,
    count: pd.Series | None = None,
) -> str:
    """Draw the figure from the rows of :func:`.cameras.error_rows` (``tracker``, ``t``,
    ``err3d``; ``count`` indexed by step) into ``stem``.png; its file name."""
    fig, ax = plots.panel(size=(7.5, 3.8))
    for k, name in enumerate(trackers):
        q = df[df.tracker == name].groupby("t")["err3d"].quantile([0.25, 0.5, 0.75]).unstack()
        plots.curve(ax, q.index, q[0.5], index=k, label=f"{name}: median over runs")
        plots.spread_band(ax, q.index, q[0.25], q[0.75], index=k, label=f"{name}: quartiles")
    plots.shade_intervals(ax, [(event[0] - 0.5, event[1] + 0.5)], event_label)
    for w, (lo, hi) in enumerate(windows):
        for edge, x in enumerate((lo - 0.5, hi + 0.5)):
            label = "windows the claims compare" if w == edge == 0 else "_windows"
            plots.reference_line(ax, x, label, axis="x", color="0.4", lw=0.8)
    ax.set_yscale("log")
    plots.label_axes(ax, "time step", "3-D error (m)", title)
    handles = ax.get_legend_handles_labels()
    if count is not None:
        ax2 = ax.twinx()
        ax2.step(count.index, count.to_numpy(), "k--", where="mid", alpha=0.5, lw=1.0)
        ax2.set_ylabel("cameras that can use it (median)")
        ax2.set_ylim(0, max(float(count.max()), 1.0) + 1)
        handles = (
            [*handles[0], *ax2.get_lines()],
            [*handles[1], "cameras that can use it (median)"],
        )
    ax.legend(*handles, fontsize=7, ncol=2, loc="upper left")
    return plots.save(fig, ctx.figure_path(stem)).name


__all__ = ["error_along_steps"]
