"""Matplotlib figures used by the reports (Agg backend: no screen needed)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import ArrayLike


def save(fig: plt.Figure, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


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
) -> Path:
    """Several curves over a shared x axis (e.g. RMSE versus time beside a bound)."""
    fig, ax = plt.subplots(figsize=(7, 4))
    for name, y in series.items():
        ax.plot(np.asarray(x), np.asarray(y), (styles or {}).get(name, "-"), label=name, lw=1.4)
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
) -> Path:
    """Top view: true path, estimated paths and sensor positions (metres)."""
    fig, ax = plt.subplots(figsize=(7, 4.8))
    t = np.asarray(truth)
    ax.plot(t[:, 0], t[:, 1], "k-", lw=2, label="truth")
    ax.plot(t[0, 0], t[0, 1], "ko")
    for name, est in estimates.items():
        e = np.asarray(est)
        ax.plot(e[:, 0], e[:, 1], "-", lw=1, label=name)
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
