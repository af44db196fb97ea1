"""Every figure of fusetrack is drawn here (issue 20): figures and their saving, curves in
distinguishable styles (error bars, reference lines, shaded outage / occlusion intervals), bar
charts, histograms, colour maps and images, tracks, beliefs (particles, grids, covariance
ellipses), scenes (room, occluders, cameras, sensors) and animations. Experiments and tools
compose their panels from these helpers and never import Matplotlib themselves
(``tests/evaluation/test_drawing_only_here.py``). Positions are in metres."""

from __future__ import annotations

import shutil
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, Literal

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.animation import FFMpegWriter, FuncAnimation, PillowWriter
from matplotlib.axes import Axes
from matplotlib.colors import LogNorm
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Ellipse, Polygon, Rectangle, Wedge
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
from numpy.typing import ArrayLike

from ..core import ConfigError, GridBelief, Particles, ShapeError, Track, invalid

_LINESTYLES = ("-", "--", "-.", ":")
_MARKERS = ("o", "s", "^", "D", "v", "x", "P", "*")
_HATCHES = ("", "//", "..", "xx", "\\\\", "--", "++", "oo")
LEGEND = {"fontsize": 8, "framealpha": 0.7}
Share = bool | Literal["none", "all", "row", "col"]  # axes sharing, as Matplotlib takes it

# --- figures -------------------------------------------------------------------------------


def figure(
    rows: int = 1,
    cols: int = 1,
    *,
    size: tuple[float, float] | None = None,
    sharex: Share = False,
    sharey: Share = False,
    projection: str | None = None,
) -> tuple[Figure, np.ndarray]:
    """A figure with a ``rows`` x ``cols`` grid of axes (always a 2-D array) in the common
    style: light grid (``projection`` e.g. ``"polar"`` or ``"3d"`` for every panel)."""
    for field, n in (("rows", rows), ("cols", cols)):
        if int(n) != n or n < 1:
            raise ConfigError(invalid(field, n, "a positive integer"))
    fig, axes = plt.subplots(
        rows, cols, figsize=size or (5.2 * cols, 4.2 * rows), squeeze=False,
        sharex=sharex, sharey=sharey, subplot_kw={"projection": projection} if projection else None,
    )  # fmt: skip
    for ax in axes.flat:
        ax.grid(alpha=0.3)
    return fig, axes


def panel(
    *, size: tuple[float, float] | None = None, projection: str | None = None
) -> tuple[Figure, Axes]:
    """A figure with one axes (:func:`figure` 1 x 1)."""
    fig, axes = figure(1, 1, size=size, projection=projection)
    return fig, axes[0, 0]


def panels(
    n: int,
    *,
    size: tuple[float, float] | None = None,
    sharex: Share = False,
    sharey: Share = False,
) -> tuple[Figure, np.ndarray]:
    """A figure with ``n`` axes side by side (a 1-D array)."""
    fig, axes = figure(1, n, size=size, sharex=sharex, sharey=sharey)
    return fig, axes[0]


def save(fig: Figure, path: Path, *, dpi: int = 110) -> Path:
    """Lay out, write (PNG by the suffix) and close ``fig``; returns ``path``."""
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def close(fig: Figure) -> None:
    """Discard a figure without saving it."""
    plt.close(fig)


def write_animation(
    fig: Figure,
    draw: Callable[[Any], Sequence[Any]],
    frames: Sequence[Any],
    path: Path,
    *,
    fps: int,
    mp4: bool = False,
) -> Path:
    """Call ``draw(frame)`` for each frame and write the result: an MP4 when ``mp4`` and
    ffmpeg exists, else a GIF (Pillow) with ``path``'s stem. Closes ``fig``; returns the file."""
    anim = FuncAnimation(fig, draw, frames=list(frames), blit=False)
    if mp4 and shutil.which("ffmpeg"):
        out = path.with_suffix(".mp4")
        anim.save(str(out), writer=FFMpegWriter(fps=fps), dpi=80)
    else:
        out = path.with_suffix(".gif")
        anim.save(str(out), writer=PillowWriter(fps=fps), dpi=80)
    plt.close(fig)
    return out


# --- axes ----------------------------------------------------------------------------------


def label_axes(ax: Axes, x: str = "x (m)", y: str = "y (m)", title: str = "") -> None:
    """Axis labels with units (and an optional title)."""
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    if title:
        ax.set_title(title, fontsize=10)


def legend(ax: Axes, **kwargs: Any) -> None:
    """The legend in the common style (``kwargs`` e.g. ``loc`` override it)."""
    ax.legend(**{**LEGEND, **kwargs})


def log_axis(ax: Axes, axis: str = "x", *, subs: Sequence[float] = (1.0, 2.0, 5.0)) -> None:
    """A logarithmic ``axis`` with plain-number ticks at 1, 2, 5 x 10^k (not 10^k labels)."""
    if axis not in ("x", "y"):
        raise ConfigError(invalid("axis", axis, "'x' or 'y'"))
    getattr(ax, f"set_{axis}scale")("log")
    which = ax.xaxis if axis == "x" else ax.yaxis
    which.set_major_locator(LogLocator(base=10.0, subs=tuple(subs)))
    which.set_major_formatter(FuncFormatter(lambda v, _: f"{v:.2g}"))
    which.set_minor_formatter(NullFormatter())


def hide_unused(axes: np.ndarray, used: int) -> None:
    """Hide the panels after the first ``used`` (a grid with more cells than panels)."""
    for ax in np.asarray(axes).flat[used:]:
        ax.set_visible(False)


# --- curves --------------------------------------------------------------------------------


def distinct_style(index: int, n_points: int) -> dict[str, Any]:
    """Colour, line style and markers of the ``index``-th curve: curves that lie on top of
    each other (filters that agree) stay distinguishable, also in grey-scale print. Long curves
    carry about 12 markers, offset per curve so they do not coincide; short ones one per point,
    the later curves' markers smaller so that coinciding ones nest instead of hiding."""
    step = max(1, n_points // 12)
    return {
        "color": f"C{index % 10}",
        "linestyle": _LINESTYLES[index % len(_LINESTYLES)],
        "marker": _MARKERS[index % len(_MARKERS)],
        "markevery": (index % step, step),
        "markersize": 6.0 - index % 4,
    }


def _series(y: ArrayLike, n: int, field: str) -> np.ndarray:
    arr = np.asarray(y, float)
    if arr.shape != (n,):
        raise ShapeError(invalid(field, arr.shape, f"({n},), one value per x"))
    return arr


def curve(
    ax: Axes,
    x: ArrayLike,
    y: ArrayLike,
    *,
    index: int,
    label: str,
    yerr: ArrayLike | None = None,
    fmt: str | None = None,
    **overrides: Any,
) -> Any:
    """One labelled curve in :func:`distinct_style` ``index`` (or the Matplotlib format string
    ``fmt``), with +- ``yerr`` error bars when given; ``overrides`` e.g. ``lw``, ``color``."""
    xs = np.asarray(x, float)
    ys = _series(y, xs.size, f"{label}: y.shape")
    style: dict[str, Any] = {} if fmt else distinct_style(index, xs.size)
    style.update({"lw": 1.4, **overrides})
    args = (xs, ys, fmt) if fmt else (xs, ys)
    if yerr is None:
        return ax.plot(*args, label=label, **style)[0]
    err = _series(yerr, xs.size, f"{label}: yerr.shape")
    style.pop("markevery", None)
    return ax.errorbar(xs, ys, yerr=err, fmt=fmt or "", capsize=3, label=label, **style)


def curves(
    ax: Axes,
    x: ArrayLike,
    series: Mapping[str, ArrayLike],
    *,
    styles: Mapping[str, str] | None = None,
    errors: Mapping[str, ArrayLike] | None = None,
    spread: float = 0.0,
    start: int = 0,
) -> None:
    """Several labelled curves over a shared ``x``: a name in ``styles`` (a Matplotlib format
    string, e.g. ``"k--"`` for a bound) keeps its style, the others get distinct styles from
    ``start`` on; ``errors`` adds error bars, shifted sideways by ``spread`` of the x span each
    so that they do not hide one another (the paper's error-bar plots)."""
    xs = np.asarray(x, float)
    span = float(np.ptp(xs)) if xs.size else 0.0
    k = start
    for i, (name, y) in enumerate(series.items()):
        shift = (i - (len(series) - 1) / 2) * spread * span
        err = (errors or {}).get(name)
        curve(ax, xs + shift, y, index=k, label=name, yerr=err, fmt=(styles or {}).get(name))
        k += name not in (styles or {})


def spread_band(
    ax: Axes, x: ArrayLike, low: ArrayLike, high: ArrayLike, *, index: int, label: str | None = None
) -> None:
    """A translucent band between ``low`` and ``high`` (e.g. the inter-quartile range over runs)
    in the colour of :func:`distinct_style` ``index``, so it goes with that curve."""
    xs = np.asarray(x, float)
    lo = _series(low, xs.size, "low.shape")
    hi = _series(high, xs.size, "high.shape")
    ax.fill_between(xs, lo, hi, color=f"C{index % 10}", alpha=0.18, lw=0, label=label)


def reference_line(
    ax: Axes,
    value: float,
    label: str,
    *,
    axis: str = "y",
    color: str = "k",
    linestyle: str | tuple[float, tuple[float, ...]] = ":",
    lw: float = 1.0,
) -> None:
    """A labelled horizontal (``axis="y"``) or vertical (``"x"``) line, e.g. a bound or a
    paper's value."""
    if axis not in ("x", "y"):
        raise ConfigError(invalid("axis", axis, "'x' or 'y'"))
    draw = ax.axhline if axis == "y" else ax.axvline
    draw(value, ls=linestyle, color=color, lw=lw, label=label)


def shade_intervals(
    ax: Axes, intervals: Sequence[tuple[float, float]], label: str, color: str = "0.6"
) -> None:
    """Grey bands over the x intervals ``(start, end)`` (e.g. a sensor's outages or an
    occlusion), one legend entry ``label``."""
    for k, iv in enumerate(intervals):
        if len(iv) != 2 or not iv[0] <= iv[1]:
            raise ConfigError(invalid(f"intervals[{k}]", tuple(iv), "(start, end), start <= end"))
        ax.axvspan(iv[0], iv[1], color=color, alpha=0.25, lw=0, label=label if k == 0 else None)


def runs_of(mask: ArrayLike, x: ArrayLike) -> list[tuple[float, float]]:
    """The ``(first, last)`` x of each run of True in ``mask``, widened by half a step, for
    :func:`shade_intervals` (e.g. the steps a target was occluded)."""
    m = np.asarray(mask, bool)
    xs = np.asarray(x, float)
    if m.shape != xs.shape or m.ndim != 1:
        raise ShapeError(invalid("mask.shape", m.shape, f"{xs.shape}, one flag per x"))
    half = 0.5 * float(np.median(np.diff(xs))) if xs.size > 1 else 0.5
    edges = np.flatnonzero(np.diff(np.r_[0, m.astype(int), 0]))
    return [(xs[a] - half, xs[b - 1] + half) for a, b in zip(edges[::2], edges[1::2])]


def bars(
    ax: Axes,
    groups: Sequence[str],
    values: Mapping[str, ArrayLike],
    *,
    errors: Mapping[str, ArrayLike] | None = None,
    width: float = 0.8,
    rotation: float = 0.0,
) -> None:
    """Grouped bar chart: for each of ``groups`` (x tick labels, turned by ``rotation``
    degrees) one bar per series of ``values`` (e.g. methods), each series labelled and told
    apart by colour and hatch."""
    n = len(groups)
    xs = np.arange(n)
    w = width / max(1, len(values))
    for k, (name, v) in enumerate(values.items()):
        y = _series(v, n, f"{name}: values.shape")
        err = (errors or {}).get(name)
        e = None if err is None else _series(err, n, f"{name}: errors.shape")
        ax.bar(xs + (k - (len(values) - 1) / 2) * w, y, w, yerr=e, capsize=3, label=name,
               color=f"C{k % 10}", hatch=_HATCHES[k % len(_HATCHES)], edgecolor="k", lw=0.5)  # fmt: skip
    ax.set_xticks(xs, list(groups), rotation=rotation, ha="right" if rotation else "center")
    ax.margins(y=0.15)  # headroom for the legend


def histogram(
    ax: Axes, values: ArrayLike, *, label: str, bins: Any = 30, index: int = 0, **kw: Any
) -> None:
    """A labelled, density-normalised histogram of ``values`` in colour and (for outlines,
    ``histtype="step"``) line style ``index``; non-finite values are dropped."""
    v = np.asarray(values, float).ravel()
    v = v[np.isfinite(v)]
    opts = {"density": True, "alpha": 0.55, "color": f"C{index % 10}",
            "linestyle": _LINESTYLES[index % len(_LINESTYLES)], **kw}  # fmt: skip
    ax.hist(v, bins=bins, label=label, **opts)


# --- maps and images -----------------------------------------------------------------------


def colour_map(
    ax: Axes,
    z: ArrayLike,
    *,
    label: str,
    x: ArrayLike | None = None,
    y: ArrayLike | None = None,
    extent: tuple[float, float, float, float] | None = None,
    log: bool = False,
    filled_levels: int = 0,
    cmap: str = "viridis",
    **kw: Any,
) -> Any:
    """``z`` (rows along y) as an image over ``extent`` or, with ``x``, ``y`` and
    ``filled_levels``, as filled contours; a colour bar titled ``label`` (with units)."""
    zz = np.asarray(z, float)
    if zz.ndim != 2:
        raise ShapeError(invalid("z.shape", zz.shape, "(rows, cols)"))
    norm = LogNorm() if log else None
    if filled_levels:
        if x is None or y is None:
            raise ConfigError(invalid("x, y", None, "the grid's coordinates for contours"))
        lo = max(float(np.nanmin(zz)), 1e-3) if log else float(np.nanmin(zz))
        hi = float(np.nanmax(zz))
        levels = np.geomspace(lo, hi, filled_levels) if log else np.linspace(lo, hi, filled_levels)
        art: Any = ax.contourf(x, y, zz, levels=levels, norm=norm, cmap=cmap, **kw)
    else:
        art = ax.imshow(zz, origin="lower", extent=extent, norm=norm, cmap=cmap,
                        aspect="auto", **kw)  # fmt: skip
    ax.figure.colorbar(art, ax=ax, label=label, format="%.2g" if log else None)
    return art


def contour_lines(
    ax: Axes, x: ArrayLike, y: ArrayLike, z: ArrayLike, levels: Sequence[float], colors: Any
) -> None:
    """Labelled iso-lines of ``z`` at ``levels``."""
    lines = ax.contour(x, y, np.asarray(z, float), levels=sorted(levels), colors=colors)
    ax.clabel(lines, fmt="%.2f", fontsize=8)


def show_image(
    ax: Axes, image: ArrayLike, *, title: str = "", cmap: str | None = None, **kw: Any
) -> None:
    """A camera frame or mask without axes (pixel coordinates, row 0 on top); ``kw`` e.g.
    ``vmin``, ``vmax``, ``extent``."""
    ax.imshow(np.asarray(image), cmap=cmap, **kw)
    ax.axis("off")
    if title:
        ax.set_title(title, fontsize=9)


def outline_box(
    ax: Axes,
    box: Sequence[float],
    *,
    color: str = "r",
    label: str | None = None,
    lw: float = 1.0,
) -> None:
    """The outline of the rectangle ``(x0, y0, x1, y1)`` (e.g. a blob's box in pixels)."""
    if len(box) != 4:
        raise ShapeError(invalid("box", tuple(box), "(x0, y0, x1, y1)"))
    x0, y0, x1, y1 = (float(v) for v in box)
    ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, color=color, lw=lw,
                           label=label))  # fmt: skip


def outline_circle(
    ax: Axes,
    centre: ArrayLike,
    radius: float,
    *,
    color: str = "k",
    label: str | None = None,
    lw: float = 0.8,
    **kw: Any,
) -> None:
    """The outline of a circle (e.g. a sensor's range), in metres."""
    c = np.asarray(centre, float)[:2]
    ax.add_patch(Circle((float(c[0]), float(c[1])), float(radius), fill=False, color=color,
                        lw=lw, label=label, **kw))  # fmt: skip


# --- tracks, beliefs and scenes --------------------------------------------------------------


def _xy(points: ArrayLike, field: str) -> np.ndarray:
    p = np.asarray(points, float)
    if p.ndim != 2 or p.shape[1] < 2:
        raise ShapeError(invalid(field, p.shape, "(n, d) with d >= 2 (x, y first)"))
    return p


def draw_paths(
    ax: Axes,
    paths: Sequence[ArrayLike],
    *,
    label: str | None = None,
    labels: Sequence[str] | None = None,
    start: int = 0,
    mark_start: bool = False,
) -> None:
    """Several x-y paths (``(n, d)``, x and y first) in distinct styles: labelled one by one
    by ``labels``, or all under one legend entry ``label`` (e.g. many tracks of a method)."""
    for k, path in enumerate(paths):
        p = _xy(path, f"paths[{k}]")
        name = labels[k] if labels is not None else (label if k == 0 else None)
        line = ax.plot(p[:, 0], p[:, 1], lw=1.2, label=name,
                       **distinct_style(start + k, len(p)))[0]  # fmt: skip
        if mark_start:
            ax.plot(p[0, 0], p[0, 1], "o", color=line.get_color(), ms=4)


def draw_truth(ax: Axes, paths: Sequence[ArrayLike], *, label: str = "truth") -> None:
    """True paths in thick translucent black, one legend entry."""
    for k, path in enumerate(paths):
        p = _xy(path, f"truth[{k}]")
        ax.plot(p[:, 0], p[:, 1], "k-", lw=2.2, alpha=0.55, label=label if k == 0 else None)


def draw_tracks(
    ax: Axes,
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
        draw_truth(ax, [_xy(p, "truth")[:, list(dims)] for p in paths])
    for k, track in enumerate(tracks):
        m = _xy(track.means, "track.means")
        name = f"track {track.id}" if track.id is not None else (track.label or f"track {k}")
        ax.plot(m[:, dims[0]], m[:, dims[1]], lw=1.1, label=name, **distinct_style(k, len(m)))
    ax.set_aspect("equal", adjustable="datalim")
    legend(ax)


def draw_particles(
    ax: Axes,
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


def draw_grid_belief(ax: Axes, grid: GridBelief, *, label: str = "probability") -> Any:
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
    ax: Axes,
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


def draw_sensors(
    ax: Axes, sensors: Sequence[tuple[str, ArrayLike]], *, marker: str = "^", label: str = "sensor"
) -> None:
    """Sensors as named markers (one legend entry ``label``)."""
    for k, (name, pos) in enumerate(sensors):
        p = np.asarray(pos, float)
        ax.plot(p[0], p[1], marker, color="tab:purple", ms=8, mfc="none",
                label=label if k == 0 else None)  # fmt: skip
        ax.annotate(name, (float(p[0]), float(p[1])), textcoords="offset points", xytext=(4, 4),
                    fontsize=8)  # fmt: skip


def _draw_occluders(ax: Axes, occluders: Sequence[Any]) -> None:
    for k, occ in enumerate(occluders):
        lab = "occluder" if k == 0 else None
        if isinstance(occ, tuple) and len(occ) == 2 and np.ndim(occ[1]) == 0:
            centre = np.asarray(occ[0], float)[:2]
            ax.add_patch(
                Circle(tuple(centre), float(occ[1]), color="tab:gray", alpha=0.8, label=lab)
            )
        else:
            ax.add_patch(Polygon(_xy(occ, "occluder"), closed=True, color="tab:gray", label=lab))


def draw_scene(
    ax: Axes,
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
    _draw_occluders(ax, occluders)
    span = max(extent[1] - extent[0], extent[3] - extent[2]) if extent else 1.0
    reach = fov_length or 0.18 * span
    for k, (c, yaw, fov) in enumerate(_camera_fields(cameras)):
        yd, half = np.degrees(yaw), np.degrees(fov) / 2
        ax.add_patch(Wedge(tuple(c), reach, yd - half, yd + half, alpha=0.12, color="tab:blue"))
        ax.plot(*c, "s", color="tab:blue", ms=6, label="camera" if k == 0 else None)
        ax.annotate(str(k + 1), tuple(c), textcoords="offset points", xytext=(4, 4), fontsize=9)
    draw_sensors(ax, sensors)
    if extent:
        pad = 0.05 * span
        ax.set_xlim(extent[0] - pad, extent[1] + pad)
        ax.set_ylim(extent[2] - pad, extent[3] + pad)
    ax.set_aspect("equal")


# --- whole figures -------------------------------------------------------------------------


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
    """Several curves over a shared x axis (e.g. RMSE versus time beside a bound), see
    :func:`curves`; ``shade`` marks x intervals (e.g. outages) as grey bands ``shade_label``."""
    fig, ax = panel(size=(7, 4))
    if shade:
        shade_intervals(ax, shade, shade_label or "shaded")
    curves(ax, x, series, styles=styles)
    label_axes(ax, xlabel, ylabel, title)
    if logy:
        ax.set_yscale("log")
    legend(ax)
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
    fig, ax = panel(size=(7, 4.8))
    t = _xy(truth, "truth")
    if truth_marked is not None:
        hidden = np.where(np.asarray(truth_marked, bool), 1.0, np.nan)
        ax.plot(t[:, 0] * hidden, t[:, 1] * hidden, "-", color="0.6", lw=7, alpha=0.5,
                solid_capstyle="round", label=marked_label or "marked")  # fmt: skip
    ax.plot(t[:, 0], t[:, 1], "k-", lw=2, label="truth")
    ax.plot(t[0, 0], t[0, 1], "ko", label="start")
    draw_paths(ax, list(estimates.values()), labels=list(estimates))
    draw_sensors(ax, sensors)
    if area is not None:
        ax.set_xlim(area[0], area[1])
        ax.set_ylim(area[2], area[3])
    ax.set_aspect("equal")
    label_axes(ax, title=title)
    legend(ax)
    return save(fig, path)


def labelled(ax: Axes) -> list[str]:
    """The legend entries ``ax`` would show (labels not starting with ``_``), for checks."""
    return [h for h in ax.get_legend_handles_labels()[1] if not h.startswith("_")]


__all__ = [
    "LEGEND",
    "bars",
    "close",
    "colour_map",
    "contour_lines",
    "curve",
    "curves",
    "distinct_style",
    "draw_covariance_ellipse",
    "draw_grid_belief",
    "draw_particles",
    "draw_paths",
    "draw_scene",
    "draw_sensors",
    "draw_tracks",
    "draw_truth",
    "figure",
    "hide_unused",
    "histogram",
    "label_axes",
    "labelled",
    "legend",
    "log_axis",
    "outline_box",
    "outline_circle",
    "panel",
    "panels",
    "plot_series",
    "plot_trajectories",
    "reference_line",
    "runs_of",
    "save",
    "shade_intervals",
    "show_image",
    "spread_band",
    "write_animation",
]
