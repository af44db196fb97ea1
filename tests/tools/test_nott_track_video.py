"""``fusetrack track-video`` end to end on a rendered recording, and its bad-input messages."""

import json

import numpy as np
import pandas as pd
import pytest

from fusetrack.cli import main
from fusetrack.tools.synthetic_recording import write_recording


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    return write_recording(tmp_path_factory.mktemp("rec"), n_empty=20, n_frames=40)


def test_track_video_end_to_end(recording, tmp_path):
    out = tmp_path / "out"
    args = [
        str(recording["video"]),
        "--radio",
        str(recording["radio"]),
        "--calibration",
        str(recording["calibration"]),
    ]
    assert main(["track-video", *args, "--out", str(out), "--no-progress"]) == 0
    for name in ("tracks.csv", "tracks.parquet", "annotated.mp4", "floorplan.png", "summary.json"):
        assert (out / name).stat().st_size > 0
    tracks = pd.read_parquet(out / "tracks.parquet")
    truth = pd.read_csv(recording["truth"])
    m = tracks.merge(truth, on="frame", suffixes=("", "_true"))
    assert len(m) == 40
    rmse = np.sqrt(((m["x"] - m["x_true"]) ** 2 + (m["y"] - m["y_true"]) ** 2).mean())
    assert rmse < 0.1
    assert json.loads((out / "summary.json").read_text())["visual_updates"] >= 35


def _run(recording, tmp_path, capsys, **replace):
    paths = {k: str(v) for k, v in recording.items()}
    paths.update(replace)
    out = tmp_path / "out"
    code = main(
        [
            "track-video",
            paths["video"],
            "--radio",
            paths["radio"],
            "--calibration",
            paths["calibration"],
            "--out",
            str(out),
            "--no-progress",
        ]
    )
    return code, capsys.readouterr().err, out


def test_bad_inputs_give_clear_messages_and_no_output(recording, tmp_path, capsys):
    bad_video = tmp_path / "bad.avi"
    bad_video.write_bytes(b"not a video")
    code, err, out = _run(recording, tmp_path, capsys, video=str(bad_video))
    assert code == 2 and "video" in err and not out.exists()

    tags = pd.read_csv(recording["radio"])
    no_x = tmp_path / "no_x.csv"
    tags.drop(columns=["x"]).to_csv(no_x, index=False)
    code, err, out = _run(recording, tmp_path, capsys, radio=str(no_x))
    assert code == 2 and "['x']" in err and not out.exists()

    shuffled = tmp_path / "shuffled.csv"
    tags.iloc[::-1].to_csv(shuffled, index=False)
    code, err, out = _run(recording, tmp_path, capsys, radio=str(shuffled))
    assert code == 2 and "time order" in err and not out.exists()

    late = tmp_path / "late.csv"
    tags.assign(time=tags["time"] + 1000).to_csv(late, index=False)
    code, err, out = _run(recording, tmp_path, capsys, radio=str(late))
    assert code == 2 and "inside the video" in err and not out.exists()

    singular = tmp_path / "singular.yaml"
    singular.write_text("foot_homography: [[1, 2, 3], [2, 4, 6], [0, 0, 1]]\n")
    code, err, out = _run(recording, tmp_path, capsys, calibration=str(singular))
    assert code == 2 and "non-singular" in err and not out.exists()


def test_a_person_who_never_appears(tmp_path, capsys):
    rec = write_recording(tmp_path / "empty", n_empty=10, n_frames=6)
    # a calibration that maps the floor far outside the image: no blob ever matches the tag
    import yaml

    cal = yaml.safe_load(rec["calibration"].read_text())
    cal["foot_homography"] = [[1.0, 0, 5000.0], [0, 1.0, 5000.0], [0, 0, 1.0]]
    cal["background_frames"] = 10
    bad = tmp_path / "far.yaml"
    bad.write_text(yaml.safe_dump(cal))
    code, err, out = _run(rec, tmp_path, capsys, calibration=str(bad))
    assert code == 2 and "never appears" in err and not out.exists()
