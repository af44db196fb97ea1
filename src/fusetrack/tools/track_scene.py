"""``fusetrack track --config scene.yaml --out DIR``: the offline counterpart of ``fusetrack serve``.

Reads the scene (:mod:`.scene`), checks every recording before any work (files, channel counts,
frame rates, columns, clocks: :mod:`.recordings`), turns the recordings into readings (WAV ->
bearings, video -> image positions, tables and node logs as they are), then runs the live node's
own engine (:class:`fusetrack.service.FusionEngine`: the configured filter or multi-target
tracker) over the node's tick alignment (:class:`fusetrack.service.Aligner`, ``lag`` 0), so the
tracks are those ``fusetrack serve`` would publish for the same readings. Writes into ``DIR``:

* ``tracks.parquet``, ``tracks.csv``: one row per published track state (``track`` id, tick,
  time, position, position covariance, state, sensors fused);
* ``readings.csv``: every reading the recordings gave (sensor, kind, time, value);
* ``report.md`` with ``scene.png`` (tracks over the scene) and, with ground truth,
  ``error.png`` and the position RMSE; ``tracks.gif`` (or ``.mp4``): the animation over the
  scene, and ``camera-ID.gif`` over each camera's frames;
* ``summary.json``.

Outputs are written into a temporary folder and moved into ``DIR`` when the run succeeds.
"""

from __future__ import annotations

import json
import math
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..core import ConfigError, invalid
from ..service import Aligner, NetworkConfig, Reading, TrackState, build_engine
from .recordings import (
    SensorReadings,
    Source,
    check_clocks,
    open_source,
    read_truth,
    readings_table,
)
from .scene import Scene, load_scene, resolve


def run_engine(
    net: NetworkConfig,
    readings: list[SensorReadings],
    start: float,
    end: float,
    progress: Any = None,
) -> list[TrackState]:
    """Every tick from ``start`` to ``end`` through the node's aligner and engine (module docstring)."""
    total = sum(len(r) for r in readings)
    aligner = Aligner(
        [s.id for s in net.sensors],
        net.fusion.rate_hz,
        start,
        net.fusion.alignment,
        lag=0.0,
        buffer_size=max(total, 1),
    )
    n = 0
    for r in readings:
        covs = r.covariances if r.covariances is not None else [None] * len(r)
        for t, z, c in zip(r.times, r.values, covs, strict=True):
            aligner.push(Reading(n, r.sensor, float(t), np.asarray(z, float), c))
            n += 1
    engine = build_engine(net, start)
    states: list[TrackState] = []
    ticks = max(1, math.ceil((end - start) * net.fusion.rate_hz - 1e-9))
    for k in range(1, ticks + 1):
        states.extend(engine.step_all(k, aligner.tick_time(k), aligner.take(k)))
        if progress is not None:
            progress.update()
    return states


def tracks_table(states: list[TrackState]) -> pd.DataFrame:
    """The published states as rows: ``track``, ``tick``, ``time``, ``x``, ``y`` (``z``), the
    position covariance ``cov_xx``, ``cov_xy``, ``cov_yy``, ``state_i``, sensors, readings."""
    rows = []
    for s in states:
        p, P = s.position, np.asarray(s.position_covariance)
        row: dict[str, Any] = {
            "track": s.track,
            "tick": s.tick,
            "time": s.time,
            "x": p[0],
            "y": p[1],
        }
        if len(p) > 2:
            row["z"] = p[2]
        row.update(cov_xx=P[0, 0], cov_xy=P[0, 1], cov_yy=P[1, 1])
        row.update({f"state_{i}": v for i, v in enumerate(s.state)})
        row.update(sensors=";".join(s.sensors), readings=s.readings)
        rows.append(row)
    return pd.DataFrame(rows)


def _check(scene: Scene, base: Path) -> list[Source]:
    """Every recording opened and checked, and the clocks against each other (no long work yet)."""
    sources = [open_source(i, s, base) for i, s in enumerate(scene.sensors)]
    check_clocks(sources, scene.clock_tolerance)
    return sources


def _load(sources: list[Source], show: bool | None) -> list[SensorReadings]:
    from ..evaluation import progress_bar

    out = []
    for src in sources:
        with progress_bar(None, f"track: {src.sensor.id}", show, unit="reading") as bar:
            r = src.load(bar)
        if len(r) == 0:
            raise ConfigError(
                invalid(
                    f"sensors[{src.index}].recording.path",
                    src.sensor.recording.path,
                    "a recording that gives readings (it gave none)",
                )
            )
        out.append(r)
    return out


def track_scene(
    config: str | Path, out: str | Path, *, progress: bool | None = None, quick: bool = False
) -> dict[str, Any]:
    """Run the chain of the module docstring; returns the summary. ``quick``: no animation."""
    from ..evaluation import progress_bar
    from .track_report import write_report

    started = time.perf_counter()
    scene, net, base = load_scene(config)
    sources = _check(scene, base)
    truth = read_truth(resolve(base, scene.truth, "truth")) if scene.truth else None
    readings = _load(sources, progress)
    t_first = min(float(r.times.min()) for r in readings)
    t_last = max(float(r.times.max()) for r in readings)
    start = scene.fusion.start if scene.fusion.start is not None else t_first - 1e-6
    ticks = max(1, math.ceil((t_last - start) * net.fusion.rate_hz - 1e-9))
    with progress_bar(ticks, "track: fusion", progress, unit="tick") as bar:
        states = run_engine(net, readings, start, t_last, bar)
    tracks = tracks_table(states)
    tmp = Path(
        tempfile.mkdtemp(prefix=f".{Path(out).name}.partial-", dir=Path(out).absolute().parent)
    )
    try:
        if not tracks.empty:
            tracks.to_parquet(tmp / "tracks.parquet", index=False)
        tracks.to_csv(tmp / "tracks.csv", index=False)
        readings_table(readings).to_csv(tmp / "readings.csv", index=False)
        videos = {s.sensor.id: s.video for s in sources if s.video is not None}
        summary = write_report(
            tmp, scene, net, readings, tracks, truth, animate_tracks=not quick, videos=videos
        )
        summary.update(
            config=str(config),
            ticks=ticks,
            start=start,
            seconds=round(time.perf_counter() - started, 3),
        )
        (tmp / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
        dest = Path(out)
        dest.mkdir(parents=True, exist_ok=True)
        for item in tmp.iterdir():
            target = dest / item.name
            if target.exists():
                target.unlink()
            shutil.move(str(item), target)
        return summary
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def add_track_parser(sub: Any) -> None:
    """The ``track`` subcommand (``fusetrack.cli`` calls this)."""
    p = sub.add_parser(
        "track",
        help="track from recordings (WAV, video, CSV/JSONL/Parquet logs, a node's SQLite log)",
        description="Track offline from a scene YAML (docs/track.md): its sensors, their recordings "
        "and the tracker; writes tracks, a report and an animation.",
    )
    p.add_argument("scene", nargs="?", type=Path, default=None, help="the scene YAML (= --config)")
    p.add_argument("--config", type=Path, default=None, help="the scene YAML")
    p.add_argument("--out", type=Path, required=True, help="output directory")
    p.add_argument("--quick", action="store_true", help="skip the animation (tests)")
    p.add_argument("--no-progress", action="store_true", help="hide progress (also -q)")


def run_track_command(args: Any) -> int:
    if (args.scene is None) == (args.config is None):
        raise ConfigError(
            invalid(
                "--config", args.config or args.scene, "one scene YAML: SCENE or --config SCENE"
            )
        )
    config = args.config or args.scene
    show = False if args.no_progress or getattr(args, "quiet", 0) else None
    summary = track_scene(config, args.out, progress=show, quick=args.quick)
    rmse = summary.get("rmse")
    said = f", position RMSE {rmse:.3f} m" if isinstance(rmse, float) else ""
    print(
        f"track: {summary['tracks']} track(s) over {summary['ticks']} ticks{said}; report: {Path(args.out) / 'report.md'}"
    )
    return 0


__all__ = ["add_track_parser", "run_engine", "run_track_command", "track_scene", "tracks_table"]
