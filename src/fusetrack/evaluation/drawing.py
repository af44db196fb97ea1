"""Drawing on a given Matplotlib axes: tracks, beliefs (particles, grids, covariance ellipses)
and scenes (room, occluders, cameras, sensors), so experiments compose panels from one place
and every figure shares the same style (issue 20). Positions are in metres."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Circle, Ellipse, Polygon, Wedge
from numpy.typing import ArrayLike

from ..core import GridBelief, Particles, ShapeError, Track, invalid

_LINESTYLES = ("-", "--", "-.", ":")
_MARKERS = ("o", "s", "^", "D", "v", "x", "P", "*")


def distinct_style(index: int, n_points: int) -> dict[str, Any]:
    """Colour, line style and sparse markers of the ``index``-th curve: curves that lie on top
    of each other (filters that agree) stay distinguishable, also in grey-scale print."""
    return {
        "color": f"C{index % 10}",
        "linestyle": _LINESTYLES[index % len(_LINESTYLES)],
        "marker": _MARKERS[index % len(_MARKERS)],
        "markevery": max(1, n_points // 12) + index,  # offset so the markers do not coincide
        "markersize": 4,
    }


def figure(
    rows: int = 1, cols: int = 1, *, size: tuple[float, float] | None = None
) -> tuple[plt.Figure, np.ndarray]:
    """A figure with a ``rows`` x ``cols`` grid of axes (always a 2-D array) in the common
    style: light grid, small legend font."""
    fig, axes = plt.subplots(rows, cols, figsize=size or (5.2 * cols, 4.2 * rows), squeeze=False)
    for ax in axes.flat:
        ax.grid(alpha=0.3)
    return fig, axes


def label_axes(ax: plt.Axes, x: str = "x (m)", y: str = "y (m)", title: str = "") -> None:
    """Axis labels with units (and an optional title)."""
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    if title:
        ax.set_title(title)


def _xy(points: ArrayLike, field: str) -> np.ndarray:
    p = np.asarray(points, float)
    if p.ndim != 2 or p.shape[1] < 2:
        raise ShapeError(invalid(field, p.shape, "(n, d) with d >= 2 (x, y first)"))
    return p


def draw_tracks(
    ax: plt.Axes,
    tracks: Sequence[Track],
    truth: ArrayLike | Sequence[ArrayLike] | None = None,
    *,
    dims: tuple[int, int] = (0, 1),
) -> None:
    """Tracks' positions (state components ``dims``) in distinct styles, each labelled by its
    id (or its label); ``truth`` (one ``(n, d)`` path or a list of them) in solid black."""
    if truth is not None:
        arr = np.asarray(truth, float) if not isinstance(truth, list) else None
        paths = [arr] if arr is not None and arr.ndim == 2 else list(truth)  # type: ignore[arg-type]
        for k, path in enumerate(paths):
            p = _xy(path, "truth")
            ax.plot(p[:, dims[0]], p[:, dims[1]], "k-", lw=2, alpha=0.6,
                    label="truth" if k == 0 else None)  # fmt: skip
    for k, track in enumerate(tracks):
        m = _xy(track.means, "track.means")
        name = f"track {track.id}" if track.id is not None else (track.label or f"track {k}")
        ax.plot(m[:, dims[0]], m[:, dims[1]], lw=1.1, label=name, **distinct_style(k, len(m)))
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize=8)


def draw_particles(
    ax: plt.Axes,
    particles: Particles | ArrayLike,
    weights: ArrayLike | None = None,
    *,
    dims: tuple[int, int] = (0, 1),
    label: str = "particles",
    color: str = "C0",
) -> None:
    """Particle positions as dots whose size grows with weight (a :class:`Particles` belief
    carries its own weights; plain ``(N, d)`` states take ``weights`` or equal weights)."""
    if isinstance(particles, Particles):
        states = particles.states
        w = np.exp(particles.log_weights - particles.log_weights.max())
    else:
        states = np.asarray(particles, float)
        w = np.ones(len(states)) if weights is None else np.asarray(weights, float)
    states = _xy(states, "particles.states")
    if w.shape != (len(states),):
        raise ShapeError(invalid("weights.shape", w.shape, f"({len(states)},)"))
    size = 2.0 + 30.0 * w / max(float(w.max()), 1e-300)
    ax.scatter(states[:, dims[0]], states[:, dims[1]], s=size, alpha=0.4, lw=0, color=color,
               label=label)  # fmt: skip


def draw_grid_belief(ax: plt.Axes, grid: GridBelief, *, label: str = "probability") -> Any:
    """A 2-D grid belief as an image over its extent in metres, with a colour bar."""
    if grid.dim != 2:
        raise ShapeError(invalid("grid.dim", grid.dim, "2 (an x-y grid)"))
    xs, ys = grid.axes
    dx = (xs[1] - xs[0]) / 2 if xs.size > 1 else 0.5
    dy = (ys[1] - ys[0]) / 2 if ys.size > 1 else 0.5
    extent = (xs[0] - dx, xs[-1] + dx, ys[0] - dy, ys[-1] + dy)
    im = ax.imshow(grid.prob.T, origin="lower", extent=extent, cmap="viridis", aspect="equal")
    ax.figure.colorbar(im, ax=ax, label=label)
    return im


def draw_covariance_ellipse(
    ax: plt.Axes,
    mean: ArrayLike,
    cov: ArrayLike,
    nsigma: float = 2.0,
    *,
    dims: tuple[int, int] = (0, 1),
    label: str | None = None,
    color: str = "C3",
) -> Ellipse:
    """The ``nsigma`` contour of N(mean, cov) in components ``dims``: semi-axes
    ``nsigma * sqrt(eigenvalue)`` along the eigenvectors (Bar-Shalom 2001, Sec. 3.6.2)."""
    m = np.asarray(mean, float)
    c = np.asarray(cov, float)
    i, j = dims
    if c.ndim != 2 or c.shape[0] != c.shape[1] or c.shape[0] <= max(i, j):
        raise ShapeError(invalid("cov.shape", c.shape, f"square, at least {max(i, j) + 1} wide"))
    block = c[np.ix_([i, j], [i, j])]
    vals, vecs = np.linalg.eigh(block)  # ascending
    if vals[0] < -1e-12 * max(1.0, abs(vals[1])):
        raise ShapeError(invalid("cov", block.tolist(), "positive semi-definite"))
    width, height = 2 * nsigma * np.sqrt(np.clip(vals[::-1], 0, None))
    angle = float(np.degrees(np.arctan2(vecs[1, 1], vecs[0, 1])))
    e = Ellipse((float(m[i]), float(m[j])), float(width), float(height), angle=angle,
                fill=False, color=color, lw=1.3, label=label)  # fmt: skip
    ax.add_patch(e)
    return e


def _camera_fields(cameras: Any) -> list[tuple[np.ndarray, float, float]]:
    """(position, yaw, fov) in radians from an object with positions/yaws/fovs arrays (a
    world camera set) or a sequence of such triples."""
    if hasattr(cameras, "positions"):
        return [
            (np.asarray(cameras.positions[k], float)[:2], float(cameras.yaws[k]),
             float(cameras.fovs[k]))
            for k in range(len(cameras.positions))
        ]  # fmt: skip
    return [(np.asarray(p, float)[:2], float(yaw), float(fov)) for p, yaw, fov in cameras]


def draw_scene(
    ax: plt.Axes,
    room: Any = None,
    occluders: Sequence[Any] = (),  # polygons (k, 2) or (centre, radius) discs
    cameras: Any = (),
    sensors: Sequence[tuple[str, ArrayLike]] = (),
    *,
    fov_length: float | None = None,
) -> None:
    """Top view of a scene: walls (a world ``Room``, whose static occluders are filled black,
    or a boundary polygon), ``occluders`` (polygons, or ``(centre, radius)`` discs in grey),
    numbered cameras with field-of-view wedges (``(position, yaw, fov)`` radians, or a camera
    set), and sensors as labelled triangles."""
    extent: list[float] = []
    if room is not None:
        boundary = room.boundary if hasattr(room, "boundary") else _xy(room, "room")
        ax.add_patch(Polygon(boundary, closed=True, fill=False, lw=2, label="walls"))
        for o in getattr(room, "static_occluders", ()):
            ax.add_patch(Polygon(o, closed=True, color="k"))
        b = np.asarray(boundary, float)
        extent = [b[:, 0].min(), b[:, 0].max(), b[:, 1].min(), b[:, 1].max()]
    for k, occ in enumerate(occluders):
        lab = "occluder" if k == 0 else None
        if isinstance(occ, tuple) and len(occ) == 2 and np.ndim(occ[1]) == 0:
            centre = np.asarray(occ[0], float)[:2]
            ax.add_patch(
                Circle(tuple(centre), float(occ[1]), color="tab:gray", alpha=0.8, label=lab)
            )
        else:
            ax.add_patch(Polygon(_xy(occ, "occluder"), closed=True, color="tab:gray", label=lab))
    span = max(extent[1] - extent[0], extent[3] - extent[2]) if extent else 1.0
    reach = fov_length or 0.18 * span
    for k, (c, yaw, fov) in enumerate(_camera_fields(cameras)):
        yd, half = np.degrees(yaw), np.degrees(fov) / 2
        ax.add_patch(Wedge(tuple(c), reach, yd - half, yd + half, alpha=0.12, color="tab:blue"))
        ax.plot(*c, "s", color="tab:blue", ms=6, label="camera" if k == 0 else None)
        ax.annotate(str(k + 1), tuple(c), textcoords="offset points", xytext=(4, 4), fontsize=9)
    for k, (name, pos) in enumerate(sensors):
        p = np.asarray(pos, float)
        ax.plot(p[0], p[1], "^", color="tab:purple", ms=8, label="sensor" if k == 0 else None)
        ax.annotate(name, (float(p[0]), float(p[1])), textcoords="offset points", xytext=(4, 4),
                    fontsize=8)  # fmt: skip
    if extent:
        pad = 0.05 * span
        ax.set_xlim(extent[0] - pad, extent[1] + pad)
        ax.set_ylim(extent[2] - pad, extent[3] + pad)
    ax.set_aspect("equal")
