"""Every Ercan 2013 experiment end to end through the CLI, at smoke size, writing the contract files."""

import json

import pandas as pd
import pytest

from fusetrack.cli import main

EXPERIMENTS = [
    "ercan2013-occlusion-probability",
    "ercan2013-cameras",
    "ercan2013-cameras-sigma-v",
    "ercan2013-prior-accuracy",
    "ercan2013-tradeoff",
    "ercan2013-prior-calibration",
    "ercan2013-occluders",
    "ercan2013-likelihood-cost",
    "ercan2013-selection",
    "ercan2013-lab",
]


@pytest.mark.parametrize("name", EXPERIMENTS)
def test_experiment_writes_the_contract_files(name, tmp_path, monkeypatch):
    monkeypatch.setenv("FUSETRACK_SMOKE", "1")
    out = tmp_path / name
    assert (
        main(
            [
                "run",
                name,
                "--quick",
                "--runs",
                "1",
                "--workers",
                "1",
                "--no-progress",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    summary = json.loads((out / "summary.json").read_text())
    assert summary["experiment"] == name and summary["claims"]
    for c in summary["claims"]:
        assert {"id", "statement", "paper", "ours", "tolerance", "holds"} <= set(c)
        assert isinstance(c["holds"], bool)
    assert len(pd.read_parquet(out / "results.parquet")) > 0
    report = (out / "report.md").read_text()
    figures = sorted(p.name for p in out.glob("*.png"))
    assert figures and all(f"({f})" in report for f in figures)
    assert "Differences" in report
