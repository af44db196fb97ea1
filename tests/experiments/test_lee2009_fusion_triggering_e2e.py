"""End to end: lee2009-detection-fusion and lee2009-camera-triggering with --quick --runs 1."""

import json

import pandas as pd

from fusetrack.cli import main


def test_detection_fusion_quick(tmp_path):
    assert (
        main(["run", "lee2009-detection-fusion", "--quick", "--runs", "1", "--out", str(tmp_path)])
        == 0
    )
    s = json.loads((tmp_path / "summary.json").read_text())
    claims = {c["id"]: c for c in s["claims"]}
    for cid in ("C12_case3", "C13_baseline_accepts_false"):
        assert claims[cid]["holds"], cid
    for cid in ("C12_case1", "C12_case2"):  # with our own P1, not the text's (a real check)
        assert "our P1" in claims[cid]["statement"] and claims[cid]["kind"] == "paper"
    assert (tmp_path / "fig4_3.png").exists()


def test_camera_triggering_quick(tmp_path):
    assert (
        main(["run", "lee2009-camera-triggering", "--quick", "--runs", "1", "--out", str(tmp_path)])
        == 0
    )
    s = json.loads((tmp_path / "summary.json").read_text())
    ids = {c["id"] for c in s["claims"]}
    assert {
        "C7_rises_with_noise",
        "C8_periodic_falls",
        "C9_trigger_beats_none",
        "C10_each_condition_helps",
    } <= ids
    assert any(i.startswith("C11") for i in ids)
    df = pd.read_parquet(tmp_path / "results.parquet")
    assert {"E3.1", "E3.2", "E3.4", "E3.5"} <= set(df["part"])
    report = (tmp_path / "report.md").read_text()
    assert "Table 3.1" in report
    # the best possible beside the tables: E3.1, E3.2 and Table 3.1, and the paper judged on it
    assert report.count("mean-RMS bound") >= 3 and "camera every step" in report
    claims = {c["id"]: c for c in s["claims"]}
    for cid in ("BP_ours_above_bound_e31", "BP_ours_above_bound_e32", "BP_ours_above_bound_e34"):
        assert claims[cid]["holds"] and claims[cid]["kind"] == "diagnostic", cid
    judged = [c for c in claims if c.startswith("BP_possible_t31_")]
    assert len(judged) == 8 and all(claims[c]["holds"] for c in judged)  # far above the bound
    assert claims["BP_possible_e31_O3"]["paper"] == 1.08
