"""Matplotlib figures used by the reports (Agg backend: no screen needed)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import ArrayLike

from .drawing import (
    distinct_style,
    draw_covariance_ellipse,
    draw_grid_belief,
    draw_particles,
    draw_scene,
    draw_tracks,
    figure,
    label_axes,
)

__all__ = [
    "distinct_style",
    "draw_covariance_ellipse",
    "draw_grid_belief",
    "draw_particles",
    "draw_scene",
    "draw_tracks",
    "figure",
    "label_axes",
    "plot_series",
    "plot_trajectories",
    "save",
    "shade_intervals",
]


def save(fig: plt.Figure, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def shade_intervals(
    ax: plt.Axes, intervals: Sequence[tuple[float, float]], label: str, color: str = "0.6"
) -> None:
    """Grey bands over the x intervals (e.g. a sensor's outages), one legend entry."""
    for k, (a, b) in enumerate(intervals):
        ax.axvspan(a, b, color=color, alpha=0.2, lw=0, label=label if k == 0 else None)


def plot_series(
    path: Path,
    x: ArrayLike,
    series: Mapping[str, ArrayLike],
    *,
    xlabel: str,
    ylabel: str,
    title: str = "",
    logy: bool = False,
    styles: Mapping[str, str] | None = None,
    shade: Sequence[tuple[float, float]] = (),
    shade_label: str = "",
) -> Path:
    """Several curves over a shared x axis (e.g. RMSE versus time beside a bound). Curves
    without an entry in ``styles`` (a Matplotlib format string) get :func:`distinct_style`;
    ``shade`` marks x intervals (e.g. outages) as grey bands labelled ``shade_label``."""
    fig, ax = plt.subplots(figsize=(7, 4))
    xs = np.asarray(x)
    if shade:
        shade_intervals(ax, shade, shade_label or "shaded")
    k = 0
    for name, y in series.items():
        fmt = (styles or {}).get(name)
        if fmt is None:
            ax.plot(xs, np.asarray(y), label=name, lw=1.4, **distinct_style(k, len(xs)))
            k += 1
        else:
            ax.plot(xs, np.asarray(y), fmt, label=name, lw=1.4)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if logy:
        ax.set_yscale("log")
    if title:
        ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, framealpha=0.6)
    return save(fig, path)


def plot_trajectories(
    path: Path,
    truth: ArrayLike,
    estimates: Mapping[str, ArrayLike],
    *,
    sensors: Sequence[tuple[str, ArrayLike]] = (),
    area: tuple[float, float, float, float] | None = None,
    title: str = "",
    truth_marked: ArrayLike | None = None,
    marked_label: str = "",
) -> Path:
    """Top view: true path, estimated paths (:func:`distinct_style`) and sensor positions
    (metres); ``truth_marked`` (booleans per truth point) highlights part of the true path,
    e.g. where a sensor could not see the target, labelled ``marked_label``."""
    fig, ax = plt.subplots(figsize=(7, 4.8))
    t = np.asarray(truth)
    if truth_marked is not None:
        hidden = np.where(np.asarray(truth_marked, bool), 1.0, np.nan)
        ax.plot(t[:, 0] * hidden, t[:, 1] * hidden, "-", color="0.6", lw=7, alpha=0.5,
                solid_capstyle="round", label=marked_label or "marked")  # fmt: skip
    ax.plot(t[:, 0], t[:, 1], "k-", lw=2, label="truth")
    ax.plot(t[0, 0], t[0, 1], "ko", label="start")
    for k, (name, est) in enumerate(estimates.items()):
        e = np.asarray(est)
        ax.plot(e[:, 0], e[:, 1], lw=1.1, label=name, **distinct_style(k, len(e)))
    for name, pos in sensors:
        p = np.asarray(pos)
        ax.plot(p[0], p[1], "^", ms=9)
        ax.annotate(
            name, (float(p[0]), float(p[1])), textcoords="offset points", xytext=(4, 4), fontsize=8
        )
    if area is not None:
        ax.set_xlim(area[0], area[1])
        ax.set_ylim(area[2], area[3])
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if title:
        ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return save(fig, path)
