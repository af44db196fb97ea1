"""The report of ``fusetrack track``: position errors against ground truth, figures, animation."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..evaluation import plots
from ..service import NetworkConfig
from .recordings import SensorReadings, VideoClock
from .scene import Animation, Scene

MARKERS = {"bearing": "^", "doa": "^", "range": "s", "range_bearing": "D", "image_position": "v"}


def position_errors(tracks: pd.DataFrame, truth: pd.DataFrame) -> pd.DataFrame:
    """Per track state inside the truth's time span: the distance (m) to the truth target the
    track follows (the one nearest on average), truth interpolated linearly in time."""
    rows = []
    for tid, tr in tracks.groupby("track"):
        best: tuple[float, Any, np.ndarray, np.ndarray] | None = None
        for target, g in truth.groupby("target"):
            inside = (tr["time"] >= g["time"].min()) & (tr["time"] <= g["time"].max())
            if not inside.any():
                continue
            t = tr.loc[inside, "time"].to_numpy()
            dx = tr.loc[inside, "x"].to_numpy() - np.interp(t, g["time"], g["x"])
            dy = tr.loc[inside, "y"].to_numpy() - np.interp(t, g["time"], g["y"])
            err = np.hypot(dx, dy)
            if best is None or err.mean() < best[0]:
                best = (float(err.mean()), target, t, err)
        if best is not None:
            rows += [
                {"track": tid, "target": best[1], "time": t, "error": e}
                for t, e in zip(best[2], best[3], strict=True)
            ]
    return pd.DataFrame(rows, columns=["track", "target", "time", "error"])


def _axes_scene(ax: Any, scene: Scene, net: NetworkConfig, truth: pd.DataFrame | None) -> None:
    x0, x1, y0, y1 = scene.area
    plots.outline_box(ax, (x0, y0, x1, y1), color="0.6", label="area")
    for kind in sorted({s.kind for s in net.sensors if s.position is not None}):
        placed = [
            (s.id, s.position[:2]) for s in net.sensors if s.kind == kind and s.position is not None
        ]
        plots.draw_sensors(ax, placed, marker=MARKERS.get(kind, "o"), label=f"{kind} sensor")
    if truth is not None:
        plots.draw_truth(ax, [g[["x", "y"]].to_numpy() for _, g in truth.groupby("target")],
                         label="ground truth")  # fmt: skip
    ax.set_xlim(x0 - 0.5, x1 + 0.5)
    ax.set_ylim(y0 - 0.5, y1 + 0.5)
    ax.set_aspect("equal")
    plots.label_axes(ax)


def _fixes(readings: list[SensorReadings]) -> list[SensorReadings]:
    return [r for r in readings if r.kind == "position_fix"]


def scene_figure(
    path: Path,
    scene: Scene,
    net: NetworkConfig,
    readings: list[SensorReadings],
    tracks: pd.DataFrame,
    truth: pd.DataFrame | None,
) -> None:
    """Tracks (one style per id), position fixes, sensors and truth over the scene's area."""
    fig, ax = plots.panel(size=(6, 6))
    _axes_scene(ax, scene, net, truth)
    for r in _fixes(readings):
        ax.plot(r.values[:, 0], r.values[:, 1], ".", color="0.45", ms=4, label=f"{r.sensor} fixes")
    groups = list(tracks.groupby("track")) if not tracks.empty else []
    plots.draw_paths(ax, [g[["x", "y"]].to_numpy() for _, g in groups],
                     labels=[f"track {tid}" for tid, _ in groups])  # fmt: skip
    ax.set_title(scene.name, fontsize=9)
    plots.legend(ax, loc="best")
    plots.save(fig, path)


def error_figure(path: Path, errors: pd.DataFrame) -> None:
    """Position error against time, per track."""
    fig, ax = plots.panel(size=(7, 3.2))
    for i, (tid, g) in enumerate(errors.groupby("track")):
        plots.curve(ax, g["time"], g["error"], index=i, label=f"track {tid}")
    plots.label_axes(ax, "time (s)", "position error (m)")
    plots.legend(ax)
    plots.save(fig, path)


def animate(
    path: Path, scene: Scene, net: NetworkConfig, tracks: pd.DataFrame, truth: pd.DataFrame | None
) -> Path:
    """Tracks growing over the scene, one frame per tick (at most ``animation.max_frames``):
    a GIF (Pillow), or an MP4 when asked for and ffmpeg exists. Returns the file written."""
    opts = scene.animation
    times = np.unique(tracks["time"].to_numpy()) if not tracks.empty else np.zeros(1)
    frames = times[
        np.unique(
            np.linspace(0, len(times) - 1, min(len(times), opts.max_frames)).round().astype(int)
        )
    ]
    fig, ax = plots.panel(size=(4.5, 4.5))
    _axes_scene(ax, scene, net, truth)
    ids = sorted(tracks["track"].unique()) if not tracks.empty else []
    trails = {
        tid: plots.curve(ax, [], [], index=i, label=f"track {tid}", marker=None)
        for i, tid in enumerate(ids)
    }
    heads = {tid: ax.plot([], [], "o", color=trails[tid].get_color(), ms=5)[0] for tid in ids}
    (true_dot,) = ax.plot([], [], "kx", ms=7, label="truth now" if truth is not None else None)
    title = ax.set_title("", fontsize=9)
    if ids:
        plots.legend(ax, fontsize=7, loc="upper right")

    def draw(t: float) -> list[Any]:
        for tid in ids:
            g = tracks[(tracks["track"] == tid) & (tracks["time"] <= t + 1e-9)]
            trails[tid].set_data(g["x"], g["y"])
            now = g[g["time"] > t - 1e-9]
            heads[tid].set_data(now["x"], now["y"])
        if truth is not None:
            pts = [
                (np.interp(t, g["time"], g["x"]), np.interp(t, g["time"], g["y"]))
                for _, g in truth.groupby("target")
                if g["time"].min() <= t <= g["time"].max()
            ]
            true_dot.set_data([p[0] for p in pts], [p[1] for p in pts])
        title.set_text(f"{scene.name[:40]}  t = {t:.2f} s")
        return [*trails.values(), *heads.values(), true_dot, title]

    return plots.write_animation(fig, draw, frames, path, fps=opts.fps, mp4=opts.format == "mp4")


def _markdown(
    scene: Scene,
    net: NetworkConfig,
    readings: list[SensorReadings],
    tracks: pd.DataFrame,
    errors: pd.DataFrame | None,
    gif: Path | None,
    camera_gifs: tuple[Path, ...] = (),
) -> str:
    t = net.tracker
    lines = [
        f"# fusetrack track: {scene.name}",
        "",
        "## Sensors and readings",
        "",
        "| sensor | kind | recording | readings | from (s) | to (s) |",
        "|---|---|---|---|---|---|",
    ]
    for s, r in zip(scene.sensors, readings, strict=True):
        span = (f"{r.times.min():.2f}", f"{r.times.max():.2f}") if len(r) else ("-", "-")
        lines.append(
            f"| {s.id} | {s.kind} | {s.recording.format}: `{s.recording.path}` | {len(r)} | {span[0]} | {span[1]} |"
        )
    lines += [
        "",
        "## Tracker",
        "",
        f"filter `{t.filter}`, motion `{t.motion.model}` (q = {t.motion.q}), association `{t.association.method}`, {net.fusion.rate_hz:g} ticks/s, alignment `{net.fusion.alignment}`.",
        "",
    ]
    n_tracks = tracks["track"].nunique() if not tracks.empty else 0
    lines += [
        "## Tracks",
        "",
        f"{n_tracks} track(s), {len(tracks)} published states: `tracks.parquet`, `tracks.csv`.",
        "",
        "![tracks over the scene](scene.png)",
        "",
    ]
    if gif is not None:
        lines += [f"Animation: ![tracks over time]({gif.name})", ""]
    for cam in camera_gifs:
        lines += [f"Over the camera's frames: ![tracks in {cam.stem}]({cam.name})", ""]
    if errors is not None:
        lines += ["## Position error against the ground truth", ""]
        if errors.empty:
            lines += ["No track state falls inside the ground truth's time span.", ""]
        else:
            lines += [
                "| track | truth target | states | RMSE (m) | max (m) |",
                "|---|---|---|---|---|",
            ]
            for tid, g in errors.groupby("track"):
                lines.append(
                    f"| {tid} | {g['target'].iloc[0]} | {len(g)} | {np.sqrt(np.mean(g['error'] ** 2)):.3f} | {g['error'].max():.3f} |"
                )
            lines += [
                "",
                f"**Position RMSE (all tracks): {np.sqrt(np.mean(errors['error'] ** 2)):.3f} m**",
                "",
                "![position error](error.png)",
                "",
            ]
    return "\n".join(lines)


def write_report(
    out: Path,
    scene: Scene,
    net: NetworkConfig,
    readings: list[SensorReadings],
    tracks: pd.DataFrame,
    truth: pd.DataFrame | None,
    *,
    animate_tracks: bool = True,
    videos: dict[str, VideoClock] | None = None,
) -> dict[str, Any]:
    """``report.md`` and its figures (and the animations: over the scene, and over each camera's
    frames for ``videos``, sensor id -> its video) into ``out``; the summary's numbers."""
    scene_figure(out / "scene.png", scene, net, readings, tracks, truth)
    errors = position_errors(tracks, truth) if truth is not None and not tracks.empty else None
    if truth is not None and errors is None:
        errors = pd.DataFrame(columns=["track", "target", "time", "error"])
    if errors is not None and not errors.empty:
        error_figure(out / "error.png", errors)
        errors.to_csv(out / "errors.csv", index=False)
    gif = animate(out / "tracks.gif", scene, net, tracks, truth) if animate_tracks else None
    cams = tuple(
        camera_animation(
            out / f"camera-{sid}.gif",
            clock,
            np.asarray(net.sensor(sid).homography, float),
            tracks,
            truth,
            scene.animation,
        )
        for sid, clock in (videos or {}).items()
        if animate_tracks
    )
    text = _markdown(scene, net, readings, tracks, errors, gif, cams)
    (out / "report.md").write_text(text + "\n")
    rmse = (
        float(np.sqrt(np.mean(errors["error"] ** 2)))
        if errors is not None and not errors.empty
        else None
    )
    return {
        "scene": scene.name,
        "readings": {r.sensor: len(r) for r in readings},
        "tracks": int(tracks["track"].nunique()) if not tracks.empty else 0,
        "states": len(tracks),
        "rmse": rmse,
        "animation": gif.name if gif is not None else None,
        "camera_animations": [c.name for c in cams],
    }


__all__ = ["animate", "position_errors", "write_report"]


def camera_animation(
    path: Path,
    clock: VideoClock,
    homography: np.ndarray,
    tracks: pd.DataFrame,
    truth: pd.DataFrame | None,
    opts: Animation,
) -> Path:
    """The tracks over the camera's own frames (GIF): each track's floor positions mapped into
    the image by the floor homography (trail and current point), the truth as a white cross."""
    import cv2
    from PIL import Image

    from ..sensors import apply_homography
    from .track_video import read_frames

    colours = [(230, 60, 40), (40, 120, 230), (40, 180, 60), (200, 160, 0)]
    frames = list(read_frames(clock.path))
    first = 0  # the first frame at or after the first track state
    if not tracks.empty:
        first = min(
            max(0, math.ceil((tracks["time"].min() - clock.start) * clock.fps - 1e-6)),
            len(frames) - 1,
        )
    keep = np.unique(
        np.linspace(first, len(frames) - 1, min(len(frames) - first, opts.max_frames)).round()
    )
    scale = max(1, round(320 / frames[0].shape[1]))
    images = []
    for k in keep.astype(int):
        t = clock.start + k / clock.fps
        img = cv2.resize(frames[k], None, fx=scale, fy=scale, interpolation=cv2.INTER_NEAREST)
        for i, (_tid, g) in enumerate(tracks.groupby("track") if not tracks.empty else []):
            g = g[g["time"] <= t + 1e-9]
            if g.empty:
                continue
            uv = apply_homography(homography, g[["x", "y"]].to_numpy()) * scale
            pts = np.round(uv).astype(np.int32).reshape(-1, 1, 2)
            cv2.polylines(img, [pts], False, colours[i % len(colours)], 2)
            cv2.circle(img, tuple(int(v) for v in pts[-1, 0]), 5, colours[i % len(colours)], -1)
        for _, g in truth.groupby("target") if truth is not None else []:
            if g["time"].min() <= t <= g["time"].max():
                xy = np.array([np.interp(t, g["time"], g["x"]), np.interp(t, g["time"], g["y"])])
                u, v = np.round(apply_homography(homography, xy) * scale).astype(int)
                cv2.drawMarker(img, (int(u), int(v)), (255, 255, 255), cv2.MARKER_CROSS, 12, 2)
        cv2.putText(
            img,
            f"t = {t:.2f} s",
            (6, 16),
            cv2.FONT_HERSHEY_SIMPLEX,
            0.45,
            (255, 255, 255),
            1,
            cv2.LINE_AA,
        )
        images.append(Image.fromarray(img))
    out = path.with_suffix(".gif")
    images[0].save(
        out, save_all=True, append_images=images[1:], duration=round(1000 / opts.fps), loop=0
    )
    return out
