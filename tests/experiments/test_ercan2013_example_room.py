"""The example room shipped for ``fusetrack run ercan2013-selection --config`` stays valid and runs
end to end (Ercan et al. 2013 "Beyond the paper")."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fusetrack.cli import main
from fusetrack.experiments.ercan2013.scenes import load_scene
from fusetrack.experiments.ercan2013.selection import selection_sizes

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "ercan2013_room.yaml"


def test_example_room_is_the_documented_one():
    scene = load_scene(EXAMPLE)
    assert len(scene.cameras) == 6 and len(scene.room.static_occluders) == 1
    assert scene.fixed_order == (0, 3, 1, 5, 2, 4)
    assert np.degrees(scene.cameras.fovs[4]) == pytest.approx(70)
    assert not scene.room.convex  # the walls hide part of the room from some cameras


def test_selection_sizes():
    assert selection_sizes(12, quick=False) == [2, 3, 4, 5, 6]
    assert selection_sizes(6, quick=False) == [2, 3, 4, 5]
    assert selection_sizes(6, quick=True) == [2, 5]
    assert selection_sizes(3, quick=True) == [2]
    assert selection_sizes(2, quick=True) == [1] and selection_sizes(1, quick=False) == [1]


def test_example_room_runs_end_to_end(tmp_path, monkeypatch):
    monkeypatch.setenv("FUSETRACK_SMOKE", "1")
    out = tmp_path / "out"
    args = ["run", "ercan2013-selection", "--config", str(EXAMPLE), "--quick", "--runs", "2",
            "--workers", "1", "--no-progress", "--set", "occluders=5", "--out", str(out)]  # fmt: skip
    assert main(args) == 0
    df = pd.read_parquet(out / "results.parquet")
    assert set(df["label"]) >= {
        "greedy-perspective",
        "brute-weak",
        "fixed",
        "random",
        "closest",
        "all",
    }
    best = df["label"].str.startswith("best L=")  # the floor: all cameras, perfect priors
    assert set(df.loc[best, "method"]) == {"all"} and set(df.loc[best, "prior"]) == {"perfect"}
    assert set(df.loc[(df["label"] != "all") & ~best, "k"]) == {2, 5}
    assert np.isfinite(df["rmse_tr"]).all() and (df["rmse_tr"] > 0).all()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["runs"] == 2 and len(summary["claims"]) >= 8
    assert not any(c["id"].startswith("rmse_") for c in summary["claims"])  # L-room numbers only
    for fig in ("fig11_room.png", "fig12_selection.png"):
        assert (out / fig).stat().st_size > 10_000
    report = (out / "report.md").read_text()
    assert f"--config {EXAMPLE} --set occluders=5`" in report.splitlines()[2]  # rerunnable command
    assert "ercan2013_room.yaml" in report and "yaw (deg)" in report and "paper 11.5" not in report


@pytest.mark.parametrize("option", ["occluders=-1", "sigma_psi=x", "steps=0", "burn_in=20"])
def test_bad_options_are_refused(tmp_path, option, capsys, monkeypatch):
    monkeypatch.setenv("FUSETRACK_SMOKE", "1")
    args = ["run", "ercan2013-selection", "--config", str(EXAMPLE), "--quick", "--set", option,
            "--out", str(tmp_path / "o")]  # fmt: skip
    assert main(args) == 2
    assert "--set" in capsys.readouterr().err
