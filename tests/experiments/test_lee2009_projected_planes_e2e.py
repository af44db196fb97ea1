"""End to end: `fusetrack run lee2009-projected-planes --quick --runs 1` writes the contract files."""

import json

import pandas as pd

from fusetrack.cli import main


def test_projected_planes_quick(tmp_path):
    out = tmp_path / "pp"
    assert (
        main(["run", "lee2009-projected-planes", "--quick", "--runs", "1", "--out", str(out)]) == 0
    )
    summary = json.loads((out / "summary.json").read_text())
    ids = {c["id"] for c in summary["claims"]}
    for prefix in ("C1_", "C2_", "C3_", "C4_", "C5_", "C6_"):
        assert any(i.startswith(prefix) for i in ids), prefix
    assert all(isinstance(c["holds"], bool) for c in summary["claims"])
    df = pd.read_parquet(out / "results.parquet")
    assert {"S1", "S4", "table21", "table22", "E2.2", "E2.0"} <= set(df["part"])
    report = (out / "report.md").read_text()
    assert "Table 2.2" in report and "scenario_S3.png" in report
    assert (out / "projected_variance.png").exists()
