import json
import os

import pandas as pd
import pytest

from fusetrack.cli import main
from fusetrack.core import ConfigError
from fusetrack.evaluation.report import (
    Claim,
    ClaimKinds,
    Outcome,
    RunContext,
    claims_table,
    verdict_line,
    write_outputs,
)


def test_write_outputs_follows_the_contract(tmp_path):
    ctx = RunContext("toy", tmp_path / "out", quick=True, seed=4, workers=3)
    df = pd.DataFrame(
        {"run": [0, 1], "method": ["a", "b"], "rmse": [1.0, 2.0], "extra": [[1, 2], None]}
    )
    claims = [
        Claim("c1", "a beats b", "a < b", 0.5, 0.1, True, "paper"),
        Claim("c2", "fails", 3, 4.0, 0.1, False, "paper"),
        Claim("c3", "tuned", 3, 3.0, 0.1, True, "calibration"),
    ]
    summary = write_outputs(ctx, Outcome(df, claims, "## Body\n\ntext", runs=2), 1.25, 100.0)
    out = tmp_path / "out"
    back = pd.read_parquet(out / "results.parquet")
    assert list(back.columns) == ["run", "method", "rmse", "extra"]
    s = json.loads((out / "summary.json").read_text())
    assert s == summary
    assert {"experiment", "claims", "runs", "seed", "seconds"} <= set(s)
    assert s["experiment"] == "toy" and s["runs"] == 2 and s["seed"] == 4 and s["seconds"] == 1.25
    assert s["workers"] == 3  # the wall time means little without the worker count
    # ... nor without the machine: its CPU, the microarchitecture the kernels were compiled for
    assert set(s["machine"]) == {"cpu_model", "cpu_arch", "avx512", "cores", "platform"}
    assert s["machine"]["cores"] == os.cpu_count() and isinstance(s["machine"]["avx512"], bool)
    assert [c["holds"] for c in s["claims"]] == [True, False, True]
    assert set(s["claims"][0]) == {"id", "statement", "paper", "ours", "tolerance", "holds", "kind"}
    assert [c["kind"] for c in s["claims"]] == ["paper", "paper", "calibration"]
    report = (out / "report.md").read_text()
    assert "## Claims (1 of 2 paper claims hold; calibration 1 of 1)" in report
    assert "**no**" in report and "## Body" in report
    assert "| c3 | calibration | tuned |" in report
    assert "--workers 3`" in report
    assert f"1.2 s on {s['machine']['cores']} cores, {s['machine']['cpu_model']} (" in report


def test_claim_kind_is_required_and_checked():
    with pytest.raises(TypeError):
        Claim("c", "s", 1, 1, 0, True)  # type: ignore[call-arg]
    with pytest.raises(ConfigError, match=r"kind of claim 'c'='papers' is invalid.*'paper'"):
        Claim("c", "s", 1, 1, 0, True, "papers")


def test_claim_kinds_table():
    kinds = ClaimKinds({"C1_level_*": "calibration", "C1_*": "paper"}, retired=["C1_old"])
    assert kinds.kind_of("C1_level_EKF") == "calibration"  # first match wins
    assert kinds.kind_of("C1_order") == "paper"
    claim = kinds.claim("C1_order", "s", 1, 2, 0, False)
    assert claim.kind == "paper" and not claim.holds
    assert (
        kinds.claim(id="C1_level_x", statement="s", paper=1, ours=1, tolerance=0, holds=1).kind
        == "calibration"
    )
    for unknown in ("C2_x", "C1_old"):
        with pytest.raises(ConfigError, match=f"claim id='{unknown}'"):
            kinds.kind_of(unknown)
    with pytest.raises(ConfigError, match="kind of 'x'"):
        ClaimKinds({"x": "modern"})


def test_verdict_counts_paper_claims_and_lists_the_others_apart():
    claims = [
        Claim("a", "s", 1, 1, 0, True, "paper"),
        Claim("b", "s", 1, 1, 0, False, "diagnostic"),
        Claim("c", "s", 1, 1, 0, True, "beyond"),
        Claim("d", "s", 1, 1, 0, True, "beyond"),
    ]
    assert verdict_line(claims) == "1 of 1 paper claims hold; diagnostic 0 of 1; beyond 2 of 2"
    assert verdict_line(claims[1:2]) == "0 of 0 paper claims hold; diagnostic 0 of 1"
    assert claims_table(claims).splitlines()[0].startswith("| id | kind | statement |")


def test_report_prints_measurements_as_given(tmp_path):
    ctx = RunContext("toy", tmp_path, extra={"measurements": "audio", "n": "3"})
    write_outputs(ctx, Outcome(pd.DataFrame({"run": [0]}), [], "", runs=1), 1.0, 1.0)
    assert "--measurements audio --set n=3`" in (tmp_path / "report.md").read_text()


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


def test_a_claim_without_a_paper_value_shows_a_dash_not_none():
    row = claims_table([Claim("conv", "s", None, 1.5, "tol", True, "diagnostic")]).splitlines()[2]
    assert row == "| conv | diagnostic | s | – | 1.5 | tol | yes |"
    assert "None" not in claims_table([Claim("p", "s", 0, 0.0, 0, True, "paper")])  # 0 is a value
