"""The readers of ``fusetrack track`` on tiny recordings written here: tables (CSV, JSONL,
Parquet), a node's SQLite log, a microphone array's WAV (a source at a known bearing), and the
offline engine run over them."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from fusetrack.tools.recordings import open_source, read_truth
from fusetrack.tools.scene import SceneSensor
from fusetrack.tools.track_report import position_errors


def sensor(**kw):
    return SceneSensor.model_validate(kw)


TAG = {"id": "tag", "kind": "position_fix", "cov": [[0.01, 0], [0, 0.01]]}


@pytest.mark.parametrize("fmt", ["csv", "jsonl", "parquet"])
def test_a_table_of_fixes_is_read_filtered_sorted_and_shifted(tmp_path, fmt):
    df = pd.DataFrame(
        {
            "t": [0.2, 0.1, 0.3, 0.15],
            "tag": ["a", "a", "a", "b"],
            "x": [2.0, 1.0, 3.0, 9.0],
            "y": [20.0, 10.0, 30.0, 90.0],
        }
    )
    path = tmp_path / f"log.{fmt}"
    {
        "csv": lambda: df.to_csv(path, index=False),
        "jsonl": lambda: df.to_json(path, orient="records", lines=True),
        "parquet": lambda: df.to_parquet(path),
    }[fmt]()
    rec = {
        "format": fmt,
        "path": path.name,
        "offset": 100.0,
        "where": {"tag": "a"},
        "columns": {"time": "t"},
    }
    src = open_source(0, sensor(**TAG, recording=rec), tmp_path)
    r = src.load(None)
    np.testing.assert_allclose(r.times, [100.1, 100.2, 100.3])
    np.testing.assert_allclose(r.values, [[1, 10], [2, 20], [3, 30]])
    assert src.span == pytest.approx((100.1, 100.3))


def test_bearings_in_degrees_are_converted(tmp_path):
    pd.DataFrame({"time": [0.0, 1.0], "bearing": [90.0, -45.0]}).to_csv(
        tmp_path / "b.csv", index=False
    )
    s = sensor(
        id="b",
        kind="bearing",
        position=[0, 0],
        sigma=0.1,
        recording={"path": "b.csv", "degrees": True},
    )
    r = open_source(0, s, tmp_path).load(None)
    np.testing.assert_allclose(r.values[:, 0], [math.pi / 2, -math.pi / 4])


def test_the_node_log_gives_one_sensors_messages_with_their_covariances(tmp_path):
    from fusetrack.service import DurableLog, SensorMessage

    log = DurableLog(tmp_path / "node.sqlite")
    for i, (sid, t, xy) in enumerate(
        [("tag", 1.0, [1, 2]), ("other", 1.5, [7, 7]), ("tag", 2.0, [3, 4])]
    ):
        msg = SensorMessage(
            node="n1",
            seq=i,
            sensor=sid,
            time=t,
            reading={"kind": "position_fix", "position": xy},
            covariance=[[0.5, 0.0], [0.0, 0.5]],
        )
        log.append_message(i + 1, msg, received=t)
    log.commit()
    log.close()
    r = open_source(0, sensor(**TAG, recording={"path": "node.sqlite"}), tmp_path).load(None)
    np.testing.assert_allclose(r.times, [1.0, 2.0])
    np.testing.assert_allclose(r.values, [[1, 2], [3, 4]])
    np.testing.assert_allclose(r.covariances, [np.eye(2) * 0.5] * 2)


def test_a_wav_of_a_source_at_a_known_bearing_gives_that_bearing(tmp_path):
    from scipy.io import wavfile

    from fusetrack.world import pink_noise, propagate, speech_like

    rng = np.random.default_rng(3)
    fs, mics = 16_000, np.array([[0.1, 0.1], [-0.1, 0.1], [-0.1, -0.1], [0.1, -0.1]])
    heading, bearing = math.radians(30.0), math.radians(100.0)  # world bearing of the source
    c, s = math.cos(heading), math.sin(heading)
    world = mics @ np.array([[c, s], [-s, c]]) + [1.0, 2.0]
    src = np.array([1.0, 2.0]) + 6.0 * np.array([math.cos(bearing), math.sin(bearing)])
    x = propagate(
        speech_like(1.2, rng, fs=fs),
        lambda t: np.broadcast_to(src, (t.size, 2)),
        world,
        0.1 + np.arange(fs) / fs,
        fs=fs,
    )
    x += 0.05 * x.std() * pink_noise(x.shape, rng)
    wavfile.write(tmp_path / "a.wav", fs, (x / np.abs(x).max() * 20000).astype(np.int16).T.copy())
    rec = {"path": "a.wav", "microphones": mics.tolist(), "offset": 5.0, "hop": 0.25}
    s_ = sensor(id="a", kind="bearing", position=[1, 2], heading=heading, sigma=0.05, recording=rec)
    r = open_source(0, s_, tmp_path).load(None)
    assert len(r) >= 3 and np.all((r.times > 5.0) & (r.times < 6.0))
    error = np.angle(np.exp(1j * (r.values[:, 0] - (bearing - heading))))  # the sensor frame
    assert np.max(np.abs(np.degrees(error))) < 2.0


def test_position_errors_follow_the_nearest_truth_target(tmp_path):
    pd.DataFrame(
        {"time": [0, 2, 0, 2], "x": [0, 2, 10, 10], "y": [0, 0, 5, 5], "target": [1, 1, 2, 2]}
    ).to_csv(tmp_path / "t.csv", index=False)
    truth = read_truth(tmp_path / "t.csv")
    tracks = pd.DataFrame(
        {"track": [7, 7, 7], "time": [1.0, 2.0, 3.0], "x": [1.0, 2.0, 5.0], "y": [0.3, 0.4, 0.0]}
    )
    e = position_errors(tracks, truth)
    assert list(e["target"]) == [1, 1]  # t = 3 is outside the truth
    np.testing.assert_allclose(e["error"], [0.3, 0.4])


def test_two_targets_in_a_jsonl_log_give_two_tracks_with_their_own_ids(tmp_path):
    """GNN on a log of position fixes of two people 6 m apart: two confirmed tracks, each staying
    with its person (the node's multi-target tracker, run offline)."""
    import yaml

    from fusetrack.tools import track_scene

    rng = np.random.default_rng(0)
    t = np.arange(0.0, 4.0, 0.25)
    rows = [
        {
            "time": float(ti),
            "x": float(x0 + 0.5 * ti + rng.normal(0, 0.1)),
            "y": float(y0 + rng.normal(0, 0.1)),
        }
        for ti in t
        for x0, y0 in ((2.0, 2.0), (2.0, 8.0))
    ]
    pd.DataFrame(rows).to_json(tmp_path / "fixes.jsonl", orient="records", lines=True)
    truth = pd.DataFrame(
        [
            {"time": ti, "x": 2.0 + 0.5 * ti, "y": y0, "target": k}
            for k, y0 in enumerate((2.0, 8.0))
            for ti in t
        ]
    )
    truth.to_csv(tmp_path / "truth.csv", index=False)
    scene = {
        "area": [0, 10, 0, 10],
        "truth": "truth.csv",
        "sensors": [{**TAG, "recording": {"path": "fixes.jsonl"}}],
        "fusion": {"rate_hz": 4},
        "tracker": {
            "prior_mean": [5, 5, 0, 0],
            "prior_std": [5, 5, 1, 1],
            "association": {"method": "gnn", "p_detect": 0.95, "clutter_density": 0.001},
        },
    }
    (tmp_path / "scene.yaml").write_text(yaml.safe_dump(scene))
    summary = track_scene(tmp_path / "scene.yaml", tmp_path / "out", progress=False, quick=True)
    tracks = pd.read_csv(tmp_path / "out" / "tracks.csv")
    assert summary["tracks"] == 2 and sorted(set(tracks["track"])) == [1, 2]
    for _, g in tracks.groupby("track"):
        assert g["y"].std() < 0.2  # each track stays with one person
    errors = pd.read_csv(tmp_path / "out" / "errors.csv")
    assert sorted(errors.groupby("track")["target"].first()) == [0, 1]
    assert summary["rmse"] < 0.2
