"""``fusetrack track-video VIDEO --radio TAGS.csv --calibration CAMERA.yaml --out DIR``.

Runs the joint visual and wireless tracker of Nott (2009) (:mod:`fusetrack.tools.video_tracker`)
on a video file and a radio-tag log a user brings, and writes into ``DIR``:

* ``tracks.csv`` and ``tracks.parquet`` -- one row per frame: floor estimate (m), its image point
  (px), the blob's foot point, the latest radio fix, the occlusion decision and its reason;
* ``annotated.mp4`` -- the video with the foot point (green), the radio fix (blue), the estimate
  (red cross) and occlusion marks;
* ``floorplan.png`` -- estimate and radio fixes on the floor; ``summary.json``.

Inputs:

* ``TAGS.csv``: columns ``time`` (s), ``tag`` (id), ``x``, ``y`` (floor metres), in time order.
* ``CAMERA.yaml``: ``foot_homography`` (3x3, floor -> image; required), ``head_homography``
  (3x3, optional), ``tag_cov`` (2x2 m^2, default diag(0.36, 0.16)), ``sigma_px`` (default 1),
  ``fps`` (default: the video's), ``video_start`` (time of frame 0 on the tag log's clock, s,
  default 0), ``subject_tag`` (default: the first tag in the log), ``background_frames`` (how many
  leading frames show the empty scene, default 30), ``min_area`` (px, default 150).

The tag log's clock may be off: ``--clock-offset S`` says the log is ``S`` seconds late
(subtracted from its times). Every input is checked before any output is written; outputs are
written to a temporary folder and moved into ``DIR`` only when the run succeeds.
"""

from __future__ import annotations

import json
import shutil
import tempfile
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, field_validator

from ..core import ConfigError, FusetrackError, MeasurementError, invalid
from ..evaluation import load_yaml, plots
from .video_tracker import FrameResult, TrackerConfig, VideoRadioTracker

REQUIRED_COLUMNS = ("time", "tag", "x", "y")


class InputError(FusetrackError, ValueError):
    """A video, tag log or calibration file that cannot be used."""


@dataclass
class VideoInfo:
    path: Path
    fps: float
    n_frames: int
    width: int
    height: int


def open_video(path: Path) -> VideoInfo:
    """Check that ``path`` is a readable, non-empty video and return its properties."""
    import cv2

    if not path.is_file():
        raise InputError(invalid("video", str(path), "an existing video file"))
    cap = cv2.VideoCapture(str(path))
    try:
        ok, frame = cap.read()
        if not cap.isOpened() or not ok or frame is None:
            raise InputError(
                invalid(
                    "video", str(path), "a video file OpenCV can decode with at least one frame"
                )
            )
        fps = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
        n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
        return VideoInfo(path, fps, n, frame.shape[1], frame.shape[0])
    finally:
        cap.release()


def read_frames(path: Path) -> Iterator[NDArray[np.uint8]]:
    """RGB frames of a video."""
    import cv2

    cap = cv2.VideoCapture(str(path))
    try:
        while True:
            ok, frame = cap.read()
            if not ok:
                return
            yield np.asarray(cv2.cvtColor(frame, cv2.COLOR_BGR2RGB), dtype=np.uint8)
    finally:
        cap.release()


class Calibration(BaseModel):
    """The camera calibration YAML of ``fusetrack track-video`` (Nott 2009, Sec. 4.1)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    foot_homography: list[list[float]] = Field(description="3x3 floor-to-image homography")
    head_homography: list[list[float]] | None = Field(
        default=None, description="3x3 head-plane homography (head rows of the image)"
    )
    tag_cov: list[list[float]] = Field(default=[[0.36, 0.0], [0.0, 0.16]])
    sigma_px: float = Field(default=1.0, gt=0)
    fps: float | None = Field(default=None, gt=0, description="default: the video's")
    background_frames: int = Field(default=30, ge=1)
    min_area: int = Field(default=150, ge=1)
    video_start: float = 0.0
    subject_tag: str | int | None = Field(default=None, description="default: the log's first")

    @field_validator("foot_homography", "head_homography")
    @classmethod
    def _three_by_three(cls, v: list[list[float]] | None) -> list[list[float]] | None:
        if v is not None and np.shape(v) != (3, 3):
            raise ValueError("a 3x3 matrix of numbers")
        return v


def read_calibration(path: Path) -> dict[str, Any]:
    """The calibration file checked against :class:`Calibration`; the keys it sets."""
    try:
        return load_yaml(Calibration, path, "calibration").model_dump(exclude_none=True)
    except ConfigError as err:
        raise InputError(str(err)) from None


def read_radio(
    path: Path, *, clock_offset: float, video_start: float, duration: float
) -> pd.DataFrame:
    """The tag log, checked: required columns, numbers, time order, overlap with the video.

    Returns columns ``t`` (seconds on the video clock: ``time - clock_offset - video_start``),
    ``tag`` (str), ``x``, ``y``; rows outside the video are dropped.
    """
    if not path.is_file():
        raise InputError(invalid("radio", str(path), "an existing CSV file"))
    try:
        df = pd.read_csv(path)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as e:
        raise InputError(f"radio={str(path)!r} is not a readable CSV file: {e}") from None
    missing = [c for c in REQUIRED_COLUMNS if c not in df.columns]
    if missing:
        raise InputError(
            f"radio={str(path)!r} lacks the column(s) {missing}: expected columns {list(REQUIRED_COLUMNS)} "
            f"(found {list(df.columns)})"
        )
    for c in ("time", "x", "y"):
        vals = pd.to_numeric(df[c], errors="coerce")
        bad = vals.isna() & df[c].notna()
        if bad.any():
            row = int(np.flatnonzero(bad.to_numpy())[0])
            raise InputError(
                invalid(f"radio column {c!r} at data row {row + 1}", df[c].iloc[row], "a number")
            )
        df[c] = vals
    if df.empty:
        raise InputError(invalid("radio", str(path), "at least one tag fix"))
    t = df["time"].to_numpy(float)
    back = np.flatnonzero(np.diff(t) < 0)
    if back.size:
        i = int(back[0]) + 1
        raise MeasurementError(
            f"radio={str(path)!r}: time={t[i]} at data row {i + 1} comes after time={t[i - 1]}: "
            "the tag log must be in time order"
        )
    out = pd.DataFrame(
        {
            "t": t - clock_offset - video_start,
            "tag": df["tag"].astype(str),
            "x": df["x"],
            "y": df["y"],
        }
    ).dropna()
    inside = (out["t"] >= -1.0) & (out["t"] <= duration + 1.0)
    if not inside.any():
        raise MeasurementError(
            f"radio={str(path)!r}: no tag fix falls inside the video (tag times {t.min():.3f}..{t.max():.3f} s, "
            f"video {video_start + clock_offset:.3f}..{video_start + clock_offset + duration:.3f} s on the tag clock): "
            "check video_start in the calibration and --clock-offset"
        )
    return out[inside].reset_index(drop=True)


def _annotate(
    image: NDArray[np.uint8], r: FrameResult | None, radio_px: NDArray[np.float64] | None
) -> NDArray[np.uint8]:
    import cv2

    out = np.asarray(cv2.cvtColor(image, cv2.COLOR_RGB2BGR), dtype=np.uint8)
    if r is None:
        return out
    if r.box is not None:
        u0, v0, u1, v1 = r.box
        cv2.rectangle(out, (u0, v0), (u1, v1), (0, 200, 0), 1)
    if np.isfinite(r.foot_u):
        cv2.circle(out, (round(r.foot_u), round(r.foot_v)), 4, (0, 200, 0), 2)
    if radio_px is not None and np.all(np.isfinite(radio_px)):
        cv2.circle(out, (round(radio_px[0]), round(radio_px[1])), 6, (255, 80, 0), 2)
    if np.isfinite(r.u):
        cv2.drawMarker(out, (round(r.u), round(r.v)), (0, 0, 255), cv2.MARKER_CROSS, 14, 2)
    label = f"frame {r.frame}  t={r.time:.2f}s"
    if r.occluded:
        label += f"  OCCLUDED ({r.reason})"
        cv2.rectangle(out, (0, 0), (out.shape[1] - 1, out.shape[0] - 1), (0, 0, 255), 4)
    cv2.putText(out, label, (8, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
    return out


def _frame_rate(cal: dict[str, Any], info: VideoInfo) -> float:
    """The calibration's frame rate, else the video's; an error if neither is > 0."""
    fps = float(cal.get("fps") or info.fps)
    if not fps > 0:
        raise InputError(
            invalid("fps", fps, "a frame rate > 0 (the video has none: set fps in the calibration)")
        )
    return fps


def _background_frames(cal: dict[str, Any], info: VideoInfo) -> tuple[int, int]:
    """How many leading frames show the empty scene, and the video's length (10^9 if unknown)."""
    n_bg = int(cal.get("background_frames", 30))
    if n_bg < 2:
        raise InputError(invalid("background_frames", n_bg, "an integer >= 2"))
    n_frames = info.n_frames if info.n_frames > 0 else 10**9
    if n_frames <= n_bg:
        raise InputError(
            invalid(
                "video length",
                info.n_frames,
                f"more than background_frames={n_bg} frames (the leading frames must show the empty scene)",
            )
        )
    return n_bg, n_frames


def _make_tracker(
    cal: dict[str, Any], info: VideoInfo, calibration: Path, drop_frames: tuple[int, int] | None
) -> VideoRadioTracker:
    """The tracker configured from the calibration file (errors name the file)."""
    try:
        cfg = TrackerConfig(
            foot_homography=np.asarray(cal["foot_homography"], float),
            head_homography=np.asarray(cal["head_homography"], float)
            if cal.get("head_homography") is not None
            else None,
            tag_cov=np.asarray(cal.get("tag_cov", [[0.36, 0.0], [0.0, 0.16]]), float),
            sigma_px=float(cal.get("sigma_px", 1.0)),
            image_size=(info.width, info.height),
            min_area=int(cal.get("min_area", 150)),
            drop_frames=drop_frames,
        )
        return VideoRadioTracker(cfg)
    except ConfigError as e:
        raise InputError(f"calibration={str(calibration)!r}: {e}") from None


def _split_tags(
    log: pd.DataFrame, cal: dict[str, Any]
) -> tuple[str, pd.DataFrame, NDArray[np.float64]]:
    """The subject's tag and fixes, and the other tags' fixes as rows (t, x, y, tag index)."""
    subject = str(cal.get("subject_tag", log["tag"].iloc[0]))
    if subject not in set(log["tag"]):
        raise InputError(
            invalid("subject_tag", subject, f"one of the tags in the log {sorted(set(log['tag']))}")
        )
    mine = log[log["tag"] == subject]
    tag_ids = {t: i for i, t in enumerate(sorted(set(log["tag"]) - {subject}))}
    others = log[log["tag"] != subject]
    other_arr = np.column_stack(
        [others[["t", "x", "y"]].to_numpy(float), others["tag"].map(tag_ids).to_numpy(float)]
    )
    return subject, mine, other_arr


def _train_background(
    tracker: VideoRadioTracker, frames: Iterator[NDArray[np.uint8]], n_bg: int
) -> None:
    """Train the background model on the first ``n_bg`` frames (an error if the video is shorter)."""
    background = []
    for _ in range(n_bg):
        f = next(frames, None)
        if f is None:
            break
        background.append(f)
    if len(background) < n_bg:
        raise InputError(
            invalid("video length", len(background), f"more than background_frames={n_bg} frames")
        )
    tracker.train_background(np.stack(background))


@dataclass(frozen=True)
class _Inputs:
    """Everything read and checked before any output is written."""

    info: VideoInfo
    fps: float
    n_bg: int
    cfg: TrackerConfig
    subject: str
    mine: pd.DataFrame
    other_arr: NDArray[np.float64]


def _read_inputs(
    video: Path,
    radio: Path,
    calibration: Path,
    clock_offset: float,
    drop_frames: tuple[int, int] | None,
) -> tuple[_Inputs, VideoRadioTracker]:
    """Open the video, read the calibration and the tag log, check them against each other;
    the inputs and the tracker they configure."""
    info = open_video(Path(video))
    cal = read_calibration(Path(calibration))
    fps = _frame_rate(cal, info)
    n_bg, n_frames = _background_frames(cal, info)
    tracker = _make_tracker(cal, info, calibration, drop_frames)
    video_start = float(cal.get("video_start", 0.0))
    log = read_radio(
        Path(radio), clock_offset=clock_offset, video_start=video_start, duration=n_frames / fps
    )
    subject, mine, other_arr = _split_tags(log, cal)
    return _Inputs(info, fps, n_bg, tracker.cfg, subject, mine, other_arr), tracker


def _track_and_annotate(
    tracker: VideoRadioTracker,
    inp: _Inputs,
    frames: Iterator[NDArray[np.uint8]],
    annotated: Path,
    progress: bool | None,
) -> list[dict[str, Any]]:
    """Track every frame after the background ones, writing the annotated video as it goes."""
    import cv2

    from ..evaluation import progress_bar
    from ..sensors import apply_homography

    info, fps, n_bg, cfg, other_arr = inp.info, inp.fps, inp.n_bg, inp.cfg, inp.other_arr
    writer = cv2.VideoWriter(
        str(annotated),
        cv2.VideoWriter.fourcc(*"mp4v"),
        fps,
        (info.width, info.height),
    )
    rows: list[dict[str, Any]] = []
    total = max(info.n_frames - n_bg, 0) or None
    bar = progress_bar(total, "track-video", progress, unit="frame")
    buffered: list[tuple[int, float, NDArray[np.uint8]]] = []

    def feed() -> Iterator[tuple[int, float, NDArray[np.uint8]]]:
        for k, image in enumerate(frames, start=n_bg):
            item = (k, k / fps, image)
            buffered.append(item)
            yield item

    radio_arr = inp.mine[["t", "x", "y"]].to_numpy(float)
    for r in tracker.run(feed(), radio_arr, other_arr if len(other_arr) else None):
        while buffered and buffered[0][0] <= r.frame:
            k, _t, image = buffered.pop(0)
            res = r if k == r.frame else None
            px = (
                apply_homography(cfg.foot_homography, np.array([r.radio_x, r.radio_y]))
                if res
                else None
            )
            writer.write(_annotate(image, res, px))
            bar.update()
        rows.append(r.as_row())
    for _k, _t, image in buffered:
        writer.write(_annotate(image, None, None))
    writer.release()
    bar.close()
    return rows


def _track_table(rows: list[dict[str, Any]], subject: str, n_bg: int) -> pd.DataFrame:
    """The per-frame rows as a table; an error if the subject was never located or never seen."""
    if not rows:
        raise InputError(
            "the subject was never located: no tag fix of tag "
            f"{subject!r} during the video and no foreground blob to start from"
        )
    df = pd.DataFrame(rows)
    if not df["updated_visual"].any():
        raise InputError(
            f"the subject (tag {subject!r}) never appears in the video: no foreground blob matched it in "
            f"{len(df)} frames (check that the first {n_bg} frames show the empty scene and that the "
            "foot_homography maps the floor into this image)"
        )
    return df


def _write_outputs(
    tmp: Path, df: pd.DataFrame, inp: _Inputs, video: Path, clock_offset: float, start: float
) -> dict[str, Any]:
    """Tracks (CSV, Parquet), the floor plan and the summary into ``tmp``; the summary."""
    df.to_csv(tmp / "tracks.csv", index=False)
    df.to_parquet(tmp / "tracks.parquet", index=False)
    _floorplan(tmp / "floorplan.png", df, inp.mine)
    summary = {
        "video": str(video),
        "frames": int(len(df) + inp.n_bg),
        "background_frames": inp.n_bg,
        "fps": inp.fps,
        "tracked_frames": len(df),
        "visual_updates": int(df["updated_visual"].sum()),
        "occluded_frames": int(df["occluded"].sum()),
        "radio_fixes": len(inp.mine),
        "subject_tag": inp.subject,
        "clock_offset": clock_offset,
        "seconds": round(time.perf_counter() - start, 3),
    }
    (tmp / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    return summary


def track_video(
    video: Path,
    radio: Path,
    calibration: Path,
    out: Path,
    *,
    clock_offset: float = 0.0,
    progress: bool | None = None,
    drop_frames: tuple[int, int] | None = None,
) -> dict[str, Any]:
    """Run the chain and write the outputs (see the module docstring); returns the summary."""
    start = time.perf_counter()
    inp, tracker = _read_inputs(video, radio, calibration, clock_offset, drop_frames)
    frames = read_frames(Path(video))
    _train_background(tracker, frames, inp.n_bg)
    tmp = Path(
        tempfile.mkdtemp(prefix=f".{Path(out).name}.partial-", dir=Path(out).absolute().parent)
    )
    try:
        rows = _track_and_annotate(tracker, inp, frames, tmp / "annotated.mp4", progress)
        df = _track_table(rows, inp.subject, inp.n_bg)
        summary = _write_outputs(tmp, df, inp, video, clock_offset, start)
        dest = Path(out)
        dest.mkdir(parents=True, exist_ok=True)
        for item in tmp.iterdir():
            shutil.move(str(item), dest / item.name)
        return summary
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _floorplan(path: Path, df: pd.DataFrame, radio: pd.DataFrame) -> None:
    """Top view: radio fixes, the estimate, and the frames the person was occluded."""
    fig, ax = plots.panel(size=(6, 6))
    ax.plot(radio["x"], radio["y"], "b.", ms=4, label="radio fixes")
    ax.plot(df["x"], df["y"], "r-", lw=1.5, label="estimate")
    occ = df[df["occluded"]]
    ax.plot(occ["x"], occ["y"], "kx", ms=4, label="occluded frames")
    ax.set_aspect("equal")
    plots.label_axes(ax)
    plots.legend(ax)
    plots.save(fig, path)


def run_track_video_command(args: Any) -> int:
    drop = None
    if args.drop_frames:
        try:
            a, b = (int(v) for v in str(args.drop_frames).split(":"))
            drop = (a, b)
        except ValueError:
            raise InputError(
                invalid("--drop-frames", args.drop_frames, "A:B with integers A <= B")
            ) from None
    summary = track_video(
        args.video,
        args.radio,
        args.calibration,
        args.out,
        clock_offset=args.clock_offset,
        progress=False if args.no_progress or getattr(args, "quiet", 0) else None,
        drop_frames=drop,
    )
    print(  # the command's result, on stdout
        f"track-video: {summary['tracked_frames']} frames tracked, {summary['visual_updates']} visual updates, "
        f"{summary['occluded_frames']} occluded; outputs in {args.out}"
    )
    return 0


__all__ = ["InputError", "run_track_video_command", "track_video"]
