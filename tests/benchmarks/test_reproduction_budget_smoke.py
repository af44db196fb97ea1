"""benchmarks/reproduction_budget.py: the CPU split of a report against the 30-minute budget,
checked on a hand-made report, and its run on the committed reports."""

import importlib.util
import json
import math
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "reproduction_budget.py"


def _module():
    spec = importlib.util.spec_from_file_location("reproduction_budget", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _report(folder: Path, wall: float, runs: list[dict]) -> None:
    folder.mkdir(parents=True)
    (folder / "summary.json").write_text(json.dumps({"seconds": wall, "workers": 2, "claims": []}))
    pd.DataFrame(runs).to_parquet(folder / "results.parquet")


def test_split_by_hand(tmp_path):
    """Two runs of 1000 steps, 1000 CPU s each: the likelihood 600 and 900 s (0.6 and 0.9 s a
    step); selection every 5 steps (200 epochs) at 2 s in the first run, none in the second:
    400 s; other 100 s. 2000 CPU s on 2 workers in 2500 s of wall (efficiency 0.4)."""
    _report(tmp_path / "slow", 2500.0, [
        {"cpu_seconds": 1000.0, "likelihood_ms_per_step": 600.0, "steps": 1000,
         "selection_ms_per_epoch": 2000.0, "period": 5},
        {"cpu_seconds": 1000.0, "likelihood_ms_per_step": 900.0, "steps": 1000,
         "selection_ms_per_epoch": float("nan"), "period": 5},
    ])  # fmt: skip
    _report(tmp_path / "untimed", 10.0, [{"rmse": 1.0}])
    rows = _module().budget(tmp_path)
    assert [r["report"] for r in rows] == ["slow"]
    r = rows[0]
    assert r["cpu_seconds"] == 2000.0 and r["parallel_efficiency"] == pytest.approx(0.4)
    assert r["likelihood_share"] == pytest.approx(1500 / 2000)
    assert r["selection_share"] == pytest.approx(400 / 2000)
    assert r["other_share"] == pytest.approx(100 / 2000)
    assert r["speedup_needed"] == pytest.approx(2500 / 1800)
    # 700 s over the budget x 2 workers = 1400 of the likelihood's 1500 CPU s must go: 15x
    assert r["likelihood_speedup_needed"] == pytest.approx(15.0)
    assert r["wall_if_likelihood_free"] == pytest.approx(2500 - 1500 / 2)


def test_a_free_likelihood_that_is_not_enough_says_never(tmp_path):
    _report(tmp_path / "r", 4000.0, [
        {"cpu_seconds": 8000.0, "likelihood_ms_per_step": 1000.0, "steps": 1000},
    ])  # fmt: skip
    (r,) = _module().budget(tmp_path)
    assert math.isinf(r["likelihood_speedup_needed"])
    assert "| never |" in _module().markdown([r])


def test_committed_reports_print_a_table():
    out = subprocess.run(
        [sys.executable, str(SCRIPT), "--json"], capture_output=True, text=True, timeout=300,
        check=True,
    )  # fmt: skip
    rows = json.loads(out.stdout)
    assert rows and all(r["report"].startswith("ercan2013-") for r in rows)
    for r in rows:
        assert 0.99 < r["likelihood_share"] + r["selection_share"] + r["other_share"] < 1.01
        assert (r["speedup_needed"] <= 1.0) == (r["wall_seconds"] <= 1800.0)
