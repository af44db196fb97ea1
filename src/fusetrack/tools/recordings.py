"""Readers of recorded sensor data for ``fusetrack track``: each gives one sensor's readings.

Two steps per recording, so that every input is checked before any long work: :func:`open_source`
reads headers and tables (channel count, frame rate, columns, time span) and returns a
:class:`Source`; ``Source.load()`` then does the work (beamforming of a WAV, background
subtraction of a video) and returns :class:`SensorReadings` on the scene clock.
"""

from __future__ import annotations

import json
import math
import sqlite3
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from ..core import ConfigError, invalid
from .scene import (
    NodeLogRecording,
    SceneSensor,
    TableRecording,
    VideoRecording,
    WavRecording,
    resolve,
)

COLUMNS: dict[str, tuple[str, ...]] = {
    "bearing": ("bearing",),
    "doa": ("azimuth", "polar"),
    "range": ("range",),
    "range_bearing": ("range", "bearing"),
    "position_fix": ("x", "y"),
    "image_position": ("u", "v"),
}
"""The value columns of a table of each sensor kind (after ``time``)."""

ANGLES = {"bearing", "azimuth", "polar"}


@dataclass
class SensorReadings:
    """One sensor's readings on the scene clock: ``times (n,)``, ``values (n, m)``, optional
    per-reading covariances ``(n, m, m)``."""

    sensor: str
    kind: str
    times: NDArray[np.float64]
    values: NDArray[np.float64]
    covariances: NDArray[np.float64] | None = None

    def __len__(self) -> int:
        return len(self.times)


@dataclass
class Source:
    """A checked recording: its time span on the scene clock and how to load it."""

    index: int
    sensor: SceneSensor
    span: tuple[float, float]
    load: Callable[[Any], SensorReadings]  # the progress bar's update(n) or None
    video: VideoClock | None = None


@dataclass(frozen=True)
class VideoClock:
    """A video recording's file and frame times: frame ``k`` is at ``start + k / fps``."""

    path: Path
    start: float
    fps: float


def _field(i: int, name: str) -> str:
    return f"sensors[{i}].recording.{name}"


# -- tables: CSV, JSONL, Parquet -------------------------------------------------------------


def read_table(path: Path, fmt: str, field: str) -> pd.DataFrame:
    """A CSV, JSONL or Parquet file as a table; a ConfigError naming ``field`` if unreadable."""
    try:
        if fmt == "csv":
            return pd.read_csv(path)
        if fmt == "jsonl":
            return pd.read_json(path, lines=True)
        return pd.read_parquet(path)
    except Exception as err:  # each reader raises its own kinds of errors
        raise ConfigError(invalid(field, str(path), f"a readable {fmt} file ({err})")) from None


def table_readings(
    df: pd.DataFrame, i: int, sensor: SceneSensor, rec: TableRecording
) -> SensorReadings:
    """The rows of ``df`` kept by ``where``, as readings: ``time`` + the kind's columns, numbers,
    sorted by time (stable), angles converted from degrees when ``degrees``."""
    for col, value in rec.where.items():
        if col not in df.columns:
            raise ConfigError(
                invalid(_field(i, f"where.{col}"), value, f"a column of {list(df.columns)}")
            )
        df = df[df[col].astype(str) == str(value)]
    names = ("time", *COLUMNS[sensor.kind])
    file_cols = [rec.columns.get(n, n) for n in names]
    missing = [c for c in file_cols if c not in df.columns]
    if missing:
        raise ConfigError(
            invalid(
                _field(i, "path"),
                rec.path,
                f"a table with columns {file_cols} for a {sensor.kind} sensor (missing {missing}; "
                f"found {list(df.columns)}; recording.columns renames)",
            )
        )
    if df.empty:
        raise ConfigError(invalid(_field(i, "path"), rec.path, "at least one reading (row)"))
    data = df[file_cols].apply(pd.to_numeric, errors="coerce").to_numpy(float)
    bad = ~np.isfinite(data)
    if bad.any():
        row, j = (int(v[0]) for v in np.nonzero(bad))
        raise ConfigError(
            invalid(
                f"{rec.path} column {file_cols[j]!r} at data row {row + 1}",
                df[file_cols[j]].iloc[row],
                "a finite number",
            )
        )
    order = np.argsort(data[:, 0], kind="stable")
    data = data[order]
    values = data[:, 1:]
    if rec.degrees:
        for j, n in enumerate(names[1:]):
            if n in ANGLES:
                values[:, j] = np.deg2rad(values[:, j])
    return SensorReadings(sensor.id, sensor.kind, data[:, 0] + rec.offset, values)


def _open_table(i: int, sensor: SceneSensor, rec: TableRecording, base: Path) -> Source:
    path = resolve(base, rec.path, _field(i, "path"))
    r = table_readings(read_table(path, rec.format, _field(i, "path")), i, sensor, rec)
    return Source(i, sensor, (float(r.times[0]), float(r.times[-1])), lambda _bar: r)


# -- the durable log of a fusion node (SQLite) ------------------------------------------------


def node_log_readings(
    path: Path, i: int, sensor: SceneSensor, rec: NodeLogRecording
) -> SensorReadings:
    """The messages of one sensor in a node's durable log (:mod:`fusetrack.service.log`: table
    ``messages``, a JSON :class:`~fusetrack.service.SensorMessage` per row), read-only."""
    from ..service import SensorMessage

    name = rec.sensor or sensor.id
    try:
        db = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
        try:
            rows = db.execute(
                "SELECT body FROM messages WHERE sensor = ? ORDER BY id", (name,)
            ).fetchall()
        finally:
            db.close()
    except sqlite3.Error as err:
        raise ConfigError(
            invalid(_field(i, "path"), rec.path, f"a fusion node's SQLite log ({err})")
        ) from None
    if not rows:
        raise ConfigError(
            invalid(_field(i, "sensor"), name, f"a sensor with messages in {rec.path}")
        )
    messages = [SensorMessage.model_validate_json(body) for (body,) in rows]
    kinds = {m.reading.kind for m in messages}
    if kinds != {sensor.kind}:
        raise ConfigError(
            invalid(
                f"sensors[{i}].kind",
                sensor.kind,
                f"the kind of the logged readings {sorted(kinds)}",
            )
        )
    times = np.array([m.time for m in messages]) + rec.offset
    values = np.array([m.value() for m in messages])
    order = np.argsort(times, kind="stable")
    covs = None
    if all(m.covariance is not None for m in messages):
        covs = np.array([m.covariance for m in messages], float)[order]
    return SensorReadings(sensor.id, sensor.kind, times[order], values[order], covs)


def _open_node_log(i: int, sensor: SceneSensor, rec: NodeLogRecording, base: Path) -> Source:
    r = node_log_readings(resolve(base, rec.path, _field(i, "path")), i, sensor, rec)
    return Source(i, sensor, (float(r.times[0]), float(r.times[-1])), lambda _bar: r)


# -- a microphone array's WAV -> bearings ---------------------------------------------------


def read_wav(path: Path, field: str) -> tuple[int, NDArray[Any]]:
    """Sample rate and samples ``(n, channels)`` (memory-mapped) of a WAV file."""
    from scipy.io import wavfile

    try:
        fs, data = wavfile.read(path, mmap=True)
    except (ValueError, OSError) as err:
        raise ConfigError(invalid(field, str(path), f"a readable PCM WAV file ({err})")) from None
    return int(fs), data.reshape(len(data), -1)


def wav_bearings(
    samples: NDArray[Any], fs: int, rec: WavRecording, progress: Any = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Bearings (sensor frame, rad) of the loudest beam, one per ``hop``, and their times (s from
    the first sample, the window's centre). Band-pass, up-sampling by ``upsample`` (finer integer
    delays), delay-and-sum beam energies (Kushwaha 2010, Eq. 33), the peak refined by a parabola
    through its neighbours; windows whose peak beam is at most ``min_snr_db`` above the mean beam
    are skipped (no directional sound)."""
    from scipy.signal import butter, resample_poly, sosfiltfilt

    from ..perception import Beamformer, MicrophoneArray, beam_angles

    x = np.asarray(samples, float).T
    sos = butter(4, list(rec.band), btype="bandpass", fs=fs, output="sos")
    x = resample_poly(sosfiltfilt(sos, x, axis=1), rec.upsample, 1, axis=1)
    fs_up = fs * rec.upsample
    bf = Beamformer(
        MicrophoneArray(np.array(rec.microphones)),
        n_beams=rec.beams,
        fs=fs_up,
        window=rec.window * rec.upsample,
        alpha=0.0,
        c=rec.speed_of_sound,
        filter_band=None,
    )
    span = bf.window + (bf.preroll - 2000)  # window + the largest delay
    hop = max(1, round(rec.hop * fs_up))
    angles = beam_angles(rec.beams)
    times, bearings = [], []
    for start in range(0, x.shape[1] - span + 1, hop):
        e = bf.energies(x[:, start : start + span])
        k = int(np.argmax(e))
        if e.mean() <= 0 or 10 * math.log10(e[k] / e.mean()) <= rec.min_snr_db:
            continue
        lo, mid, hi = e[k - 1], e[k], e[(k + 1) % len(e)]
        curv = lo - 2 * mid + hi
        shift = 0.5 * (lo - hi) / curv if curv < 0 else 0.0
        bearings.append(float(np.angle(np.exp(1j * (angles[k] + shift * 2 * np.pi / rec.beams)))))
        times.append((start + bf.window / 2) / fs_up)
        if progress is not None:
            progress.update()
    return np.array(times), np.array(bearings)


def _open_wav(i: int, sensor: SceneSensor, rec: WavRecording, base: Path) -> Source:
    path = resolve(base, rec.path, _field(i, "path"))
    fs, data = read_wav(path, _field(i, "path"))
    if data.shape[1] != len(rec.microphones):
        raise ConfigError(
            invalid(
                _field(i, "microphones"),
                f"{len(rec.microphones)} microphones",
                f"one [x, y] per channel: {rec.path} has {data.shape[1]} channels",
            )
        )
    if len(data) < 2 * rec.window:
        raise ConfigError(
            invalid(
                _field(i, "path"),
                rec.path,
                f"at least 2 windows of audio ({2 * rec.window} samples)",
            )
        )

    def load(progress: Any) -> SensorReadings:
        t, b = wav_bearings(data, fs, rec, progress)
        return SensorReadings(sensor.id, sensor.kind, t + rec.offset, b[:, None])

    return Source(i, sensor, (rec.offset, rec.offset + len(data) / fs), load)


# -- a camera's video -> image positions -----------------------------------------------------


def video_positions(
    path: Path, cal: dict[str, Any], fps: float, progress: Any = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Frame times (s from frame 0) and foot points ``(n, 2)`` (px) of the largest foreground
    blob (Nott 2009, Sec. 4.5) after a Horprasert background model trained on the leading
    ``background_frames`` frames; frames without a blob give no reading."""
    from ..perception import HorprasertModel, find_blobs, largest_blob
    from .track_video import read_frames

    n_bg, min_area = int(cal.get("background_frames", 30)), int(cal.get("min_area", 150))
    frames = read_frames(path)
    background = [f for _, f in zip(range(n_bg), frames, strict=False)]
    model = HorprasertModel.train(np.stack(background))
    times, feet = [], []
    for k, image in enumerate(frames, start=n_bg):
        blob = largest_blob(find_blobs(model.foreground(image), min_area=min_area))
        if blob is not None:
            times.append(k / fps)
            feet.append(blob.foot)
        if progress is not None:
            progress.update()
    return np.array(times), np.array(feet, float).reshape(-1, 2)


def _open_video(i: int, sensor: SceneSensor, rec: VideoRecording, base: Path) -> Source:
    from .track_video import (
        InputError,
        _background_frames,
        _frame_rate,
        open_video,
        read_calibration,
    )

    path = resolve(base, rec.path, _field(i, "path"))
    cal_path = resolve(base, rec.calibration, _field(i, "calibration"))
    try:
        info = open_video(path)
        cal = read_calibration(cal_path)
        fps = _frame_rate(cal, info)
        _background_frames(cal, info)
    except InputError as err:
        raise ConfigError(f"sensors[{i}].recording: {err}") from None
    start = rec.offset + float(cal.get("video_start", 0.0))
    end = start + (info.n_frames - 1) / fps

    def load(progress: Any) -> SensorReadings:
        t, feet = video_positions(path, cal, fps, progress)
        return SensorReadings(sensor.id, sensor.kind, t + start, feet)

    return Source(i, sensor, (start, end), load, VideoClock(path, start, fps))


def open_source(i: int, sensor: SceneSensor, base: Path) -> Source:
    """Check sensor ``i``'s recording (module docstring)."""
    rec = sensor.recording
    if isinstance(rec, WavRecording):
        return _open_wav(i, sensor, rec, base)
    if isinstance(rec, VideoRecording):
        return _open_video(i, sensor, rec, base)
    if isinstance(rec, NodeLogRecording):
        return _open_node_log(i, sensor, rec, base)
    return _open_table(i, sensor, rec, base)


def check_clocks(sources: list[Source], tolerance: float) -> None:
    """Every recording's time span must come within ``tolerance`` s of the others' (else its
    clock, or its ``offset``, is wrong: a WAV from 0 s beside logs in Unix seconds)."""
    if len(sources) < 2:
        return
    for s in sources:
        others = [o.span for o in sources if o is not s]
        lo, hi = min(a for a, _ in others), max(b for _, b in others)
        gap = max(s.span[0] - hi, lo - s.span[1], 0.0)
        if gap > tolerance:
            raise ConfigError(
                invalid(
                    _field(s.index, "offset"),
                    s.sensor.recording.offset,
                    f"an offset that puts sensor {s.sensor.id!r}'s times ({s.span[0]:.3f}..{s.span[1]:.3f} s) "
                    f"within clock_tolerance={tolerance:g} s of the other recordings' "
                    f"({lo:.3f}..{hi:.3f} s): the clocks are {gap:.3f} s apart",
                )
            )


def read_truth(path: Path) -> pd.DataFrame:
    """The ground truth CSV: ``time``, ``x``, ``y`` and optionally ``target`` (default 0)."""
    df = read_table(path, "csv", "truth")
    missing = [c for c in ("time", "x", "y") if c not in df.columns]
    if missing:
        raise ConfigError(
            invalid("truth", str(path), f"a CSV with columns time, x, y (missing {missing})")
        )
    if "target" not in df.columns:
        df["target"] = 0
    return df.sort_values(["target", "time"], kind="stable").reset_index(drop=True)


def readings_table(readings: list[SensorReadings]) -> pd.DataFrame:
    """All readings as one table: sensor, kind, time, value (JSON list)."""
    rows = [
        {
            "sensor": r.sensor,
            "kind": r.kind,
            "time": float(t),
            "value": json.dumps(np.round(v, 6).tolist()),
        }
        for r in readings
        for t, v in zip(r.times, r.values, strict=True)
    ]
    return pd.DataFrame(rows, columns=["sensor", "kind", "time", "value"]).sort_values(
        "time", kind="stable"
    )


__all__ = [
    "COLUMNS",
    "SensorReadings",
    "Source",
    "VideoClock",
    "check_clocks",
    "node_log_readings",
    "open_source",
    "read_truth",
    "readings_table",
    "table_readings",
    "video_positions",
    "wav_bearings",
]
