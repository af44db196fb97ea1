"""The committed sample (examples/sample): ``fusetrack make-sample`` regenerates it exactly, and
``fusetrack track`` on it writes tracks with ids, the report with the position RMSE against the
sample's ground truth, and the animation."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from fusetrack.cli import main
from fusetrack.tools import make_sample
from fusetrack.tools.track_video import read_frames

SAMPLE = Path(__file__).resolve().parents[2] / "examples" / "sample"


def test_make_sample_regenerates_the_committed_files(tmp_path):
    paths = make_sample(tmp_path)
    assert sorted(p.name for p in paths.values()) == sorted(p.name for p in SAMPLE.iterdir())
    for p in paths.values():
        if p.suffix == ".avi":  # a codec may write other bytes for the same frames
            new, old = list(read_frames(p)), list(read_frames(SAMPLE / p.name))
            assert len(new) == len(old) == 65
            assert max(np.abs(a.astype(int) - b).max() for a, b in zip(new, old, strict=True)) <= 2
        else:
            assert p.read_bytes() == (SAMPLE / p.name).read_bytes(), p.name
    assert sum(p.stat().st_size for p in SAMPLE.iterdir()) < 4e6  # a few MB at most


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
