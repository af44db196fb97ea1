import json

import pandas as pd
import pytest

from fusetrack.cli import main
from fusetrack.core import ConfigError
from fusetrack.evaluation.report import Claim, Outcome, RunContext, write_outputs


def test_write_outputs_follows_the_contract(tmp_path):
    ctx = RunContext("toy", tmp_path / "out", quick=True, seed=4)
    df = pd.DataFrame(
        {"run": [0, 1], "method": ["a", "b"], "rmse": [1.0, 2.0], "extra": [[1, 2], None]}
    )
    claims = [
        Claim("c1", "a beats b", "a < b", 0.5, 0.1, True),
        Claim("c2", "fails", 3, 4.0, 0.1, False),
    ]
    summary = write_outputs(ctx, Outcome(df, claims, "## Body\n\ntext", runs=2), 1.25, 100.0)
    out = tmp_path / "out"
    back = pd.read_parquet(out / "results.parquet")
    assert list(back.columns) == ["run", "method", "rmse", "extra"]
    s = json.loads((out / "summary.json").read_text())
    assert s == summary
    assert {"experiment", "claims", "runs", "seed", "seconds"} <= set(s)
    assert s["experiment"] == "toy" and s["runs"] == 2 and s["seed"] == 4 and s["seconds"] == 1.25
    assert [c["holds"] for c in s["claims"]] == [True, False]
    assert set(s["claims"][0]) == {"id", "statement", "paper", "ours", "tolerance", "holds"}
    report = (out / "report.md").read_text()
    assert "1 of 2 hold" in report and "**no**" in report and "## Body" in report


def test_run_context_validates():
    with pytest.raises(ConfigError, match="engine"):
        RunContext("x", "o", engine="gpu")
    with pytest.raises(ConfigError, match="scheduler"):
        RunContext("x", "o", scheduler="tcp://127.0.0.1:8786")
    with pytest.raises(ConfigError, match="runs=0"):
        RunContext("x", "o", runs=0)


def test_cli_list_and_unknown_experiment(capsys, tmp_path):
    assert main(["list"]) == 0
    assert "demo" in capsys.readouterr().out
    assert main(["run", "no-such-thing", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "no-such-thing" in err and "demo" in err
