"""The ``fusetrack track-video`` arguments, apart from the chain that runs them."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def add_track_video_parser(sub: Any) -> None:
    """The ``track-video`` subcommand (``fusetrack.cli`` calls this)."""
    p = sub.add_parser(
        "track-video", help="track a tagged person in a video file with its radio-tag log"
    )
    p.add_argument("video", type=Path)
    p.add_argument("--radio", type=Path, required=True, help="tag log CSV: time, tag, x, y")
    p.add_argument(
        "--calibration", type=Path, required=True, help="camera YAML (foot_homography, ...)"
    )
    p.add_argument("--out", type=Path, required=True, help="output directory")
    p.add_argument(
        "--clock-offset", type=float, default=0.0, help="seconds the tag log's clock is late"
    )
    p.add_argument(
        "--drop-frames", default=None, help="A:B - skip the visual updates on frames A..B"
    )
    p.add_argument("--no-progress", action="store_true")
