"""``fusetrack track`` on the committed sample (examples/sample) writes tracks with ids, the
report with the position RMSE against the sample's ground truth, and the animations (over the
scene and over the camera's frames)."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from fusetrack.cli import main

SAMPLE = Path(__file__).resolve().parents[2] / "examples" / "sample"


def test_track_on_the_sample_writes_tracks_report_and_animation(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["track", str(SAMPLE / "scene.yaml"), "--out", str(out), "-q"]) == 0
    said = capsys.readouterr().out
    assert "1 track(s)" in said and "position RMSE" in said
    tracks = pd.read_parquet(out / "tracks.parquet")
    assert tracks.equals(pd.read_csv(out / "tracks.csv").astype(tracks.dtypes.to_dict()))
    assert set(tracks["track"]) == {1}
    assert tracks["time"].is_monotonic_increasing and len(tracks) == 25  # 5 ticks/s for 5 s
    summary = json.loads((out / "summary.json").read_text())
    assert summary["readings"] == {"array": 49, "camera": 50, "tag": 25}
    # fused, the track beats the radio tag alone (its fixes: 0.42 m RMSE) and the truth is near
    assert summary["rmse"] < 0.25
    report = (out / "report.md").read_text()
    assert f"Position RMSE (all tracks): {summary['rmse']:.3f} m" in report
    for name in ("scene.png", "error.png", "tracks.gif", "camera-camera.gif"):
        assert (out / name).stat().st_size > 1000 and f"]({name})" in report
    from PIL import Image

    with Image.open(out / "tracks.gif") as gif:
        assert gif.n_frames == 25  # one per tick
    with Image.open(out / "camera-camera.gif") as gif:
        assert gif.n_frames == 48 and gif.size == (320, 240)  # frames 17..64: from the 1st tick


def test_track_video_runs_on_the_sample_out_of_the_box(tmp_path, capsys):
    import numpy as np

    out = tmp_path / "tv"
    args = ["track-video", str(SAMPLE / "video.avi"), "--radio", str(SAMPLE / "tags.csv")]
    assert main([*args, "--calibration", str(SAMPLE / "camera.yaml"), "--out", str(out), "-q"]) == 0
    tracks, truth = pd.read_csv(out / "tracks.csv"), pd.read_csv(SAMPLE / "truth.csv")
    assert len(tracks) == 50 and tracks["updated_visual"].sum() > 30
    err = np.hypot(
        tracks["x"] - np.interp(tracks["time"], truth["time"], truth["x"]),
        tracks["y"] - np.interp(tracks["time"], truth["time"], truth["y"]),
    )
    assert np.sqrt(np.mean(err**2)) < 0.25  # the tag alone: 0.42 m
