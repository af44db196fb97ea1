"""End to end: the README's example runs, and `fusetrack demo --quick` writes the contract files."""

import json
import re
from pathlib import Path

import pandas as pd

from fusetrack.cli import main

ROOT = Path(__file__).resolve().parents[2]


def test_readme_example_runs():
    text = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks, "README has no python example"
    for block in blocks:
        exec(compile(block, "README.md", "exec"), {})


def test_demo_quick_end_to_end(tmp_path, capsys):
    out = tmp_path / "demo"
    assert (
        main(
            ["demo", "--quick", "--runs", "3", "--workers", "1", "--no-progress", "--out", str(out)]
        )
        == 0
    )
    summary = json.loads((out / "summary.json").read_text())
    assert summary["experiment"] == "demo" and summary["runs"] == 3
    ids = {c["id"] for c in summary["claims"]}
    assert {"ekf_above_bound", "ukf_above_bound", "pf_above_bound", "pf_not_worse_than_ekf"} <= ids
    for c in summary["claims"]:
        assert isinstance(c["holds"], bool) and c["ours"] is not None
    df = pd.read_parquet(out / "results.parquet")
    assert set(df["method"]) == {"EKF", "UKF", "PF"}
    assert df["run"].nunique() == 3 and {"config", "seed", "n_particles"} <= set(df.columns)
    assert (df["sq_pos_err"] >= 0).all() and df["sq_pos_err"].notna().all()
    report = (out / "report.md").read_text()
    for png in re.findall(r"\]\(([^)]+\.png)\)", report):
        assert (out / png).stat().st_size > 1000
    assert "position RMSE" in capsys.readouterr().out
