"""End to end: `fusetrack run lee2009-periodic-sweep --quick --set periods=1,100` (E3.2, Fig. 3-6)."""

import json

import pandas as pd

from fusetrack.cli import main


def test_periodic_sweep_quick(tmp_path):
    out = tmp_path / "sweep"
    argv = ["run", "lee2009-periodic-sweep", "--quick", "--runs", "3", "--workers", "1"]
    assert main([*argv, "--no-progress", "--out", str(out), "--set", "periods=1,100"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    claim, best = summary["claims"]
    assert claim["id"] == "C8_periodic_falls" and set(claim["ours"]) == {"1", "100"}
    assert claim["holds"]  # a camera fix every step against one every 100 steps: no contest
    assert best["id"] == "BP_ours_above_bound_e32" and best["kind"] == "diagnostic"
    assert best["holds"] and best["ours"] > 1  # our RMS / the CRLB, smallest over T_v, objects
    report = (out / "report.md").read_text()
    assert "RMS bound" in report and "mean-RMS bound" in report  # the bound beside the table
    df = pd.read_parquet(out / "results.parquet")
    assert sorted(df["trial"].unique()) == [0, 1, 2]
    assert (df["bound_ms"] > 0).all()
    assert set(df["policy"]) == {"periodic 1", "periodic 100"}
    assert (out / "e32_periodic.png").exists()
