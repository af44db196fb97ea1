"""kushwaha2010-cameras-lcr (spec E9, A-V-18): the carried box in the 10 x 8 m room."""

import json

import numpy as np
import pandas as pd

from fusetrack.cli import main
from fusetrack.experiments.kushwaha2010.camera_lcr import (
    BOX,
    CARRY_HIGH,
    CARRY_LOW,
    _setup_claims,
    _tracker_claims,
    error_bound,
    lcr_cameras,
)


def test_quick_run_writes_the_claims_and_both_figures(tmp_path):
    out = tmp_path / "lcr"
    args = ["run", "kushwaha2010-cameras-lcr", "--quick", "--runs", "1", "--seed", "3"]
    assert main([*args, "--workers", "1", "--out", str(out), "--no-progress"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    kinds = {c["id"]: c["kind"] for c in summary["claims"]}
    assert kinds == {
        "lcr_in_all_four_views": "diagnostic",
        "lcr_pixel_fraction_above_1pct": "diagnostic",
        "lcr_t3_tracks_box": "paper",
        "lcr_t3_beats_t2": "diagnostic",
        "lcr_t0_beats_t3": "diagnostic",
        "BP_lcr_trackers_above_bound": "diagnostic",
    }
    df = pd.read_parquet(out / "results.parquet")
    assert set(df.tracker) == {"T0", "T2", "T3"}
    assert {"x", "y", "z", "true_x", "min_camera_fraction"} <= set(df.columns)
    # the best possible beside the error table (issue 19): a row there and its own section
    report = (out / "report.md").read_text()
    assert "| PCRB (best possible)" in report
    assert "## The best possible (PCRB)" in report
    assert {"pcrb_mse", "pcrb_mean", "trivial_err"} <= set(df.columns)
    assert (df.pcrb_mean > 0).all() and (df.pcrb_mean < df.pcrb_mse**0.5 + 1e-12).all()
    for png in ("lcr_trajectory.png", "lcr_pixel_fraction.png"):
        assert (out / png).exists()


def test_the_box_fills_over_1pct_of_every_camera_at_the_carrying_region_corners():
    corners = np.array(np.meshgrid(*zip(CARRY_LOW, CARRY_HIGH), indexing="ij")).reshape(3, -1).T
    q = np.array([0.0, 0.0, 0.0, 1.0])
    for cam in lcr_cameras():
        for x in corners:
            img = np.zeros((120, 160, 3), np.uint8)
            assert BOX.paint(img, cam, x, q).mean() > 0.01


def test_claims_fail_when_the_set_up_or_the_tracker_does():
    rows = pd.DataFrame(
        {
            "run": [0, 0],
            "t": [1, 2],
            "participating": [4, 3],  # a camera lost the box at step 2
            "pixel_fraction": [0.02, 0.02],
            "min_camera_fraction": [0.02, 0.009],
        }
    )
    assert [c.holds for c in _setup_claims(rows)] == [False, False]
    bound = error_bound()
    assert bound == min(BOX.half_sizes)
    good = pd.DataFrame({"T0": [0.03, 0.04, 0.03], "T2": [0.09, 0.1, 0.11], "T3": [0.05] * 3})
    assert [c.holds for c in _tracker_claims(good)] == [True, True, True]
    lost = good.assign(T3=[0.05, bound + 0.2, 0.05])  # one run lost the box: interval too wide
    assert not _tracker_claims(lost)[0].holds
