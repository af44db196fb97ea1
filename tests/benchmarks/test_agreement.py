"""The agreement checks of pf_bearing.py (RMSE over runs) and multitarget.py (GOSPA over
seeds): a configuration whose libraries disagree beyond Monte Carlo error gets no speed-up."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

import multitarget
import pf_bearing


def _lib(t: float, rmse_runs: list[float]) -> dict:
    return {"seconds_per_step": t, "rmse": rmse_runs[0], "estimate": t, "runs": len(rmse_runs),
            "wall": t, "cpu": 2 * t, "rmse_runs": rmse_runs}  # fmt: skip


def test_pf_bearing_row_gives_no_speedup_to_a_library_that_disagrees() -> None:
    res = {
        "fusetrack": _lib(0.001, [3.30, 3.32, 3.31]),
        "stonesoup": _lib(0.012, [3.29, 3.33, 3.31]),  # the same filter: agrees
        "numpy": _lib(0.004, [4.30, 4.32, 4.31]),  # 1 m off with SE ~0.008: disagrees
        "particles": _lib(0.005, [3.31]),  # one run: borrows fusetrack's spread
    }
    row = pf_bearing.result_row(1000, 3, list(res), res)
    assert row["agreement"]["stonesoup"]["agree"] is True
    assert row["agreement"]["numpy"]["agree"] is False
    assert row["agreement"]["particles"]["agree"] is True
    assert row["agree"] is False
    assert row["speedup_over"]["numpy"] is None
    assert row["speedup_over"]["stonesoup"] == {
        "wall": pytest.approx(12.0),
        "cpu": pytest.approx(12.0),
    }
    assert row["wall_seconds_per_step"]["fusetrack"] == 0.001
    assert row["cpu_seconds_per_step"]["fusetrack"] == 0.002


def test_multitarget_gospa_agreement() -> None:
    a = np.array([40.0, 41.0, 39.0, 40.5])
    same = multitarget.gospa_agreement(a, a + 0.01)
    assert same["agree"] is True
    assert same["gospa_paired"]["difference"] == pytest.approx(-0.01)
    assert multitarget.gospa_agreement(a, a + 5.0)["agree"] is False
    assert multitarget.gospa_agreement(a, np.array([np.nan] * 4))["agree"] is None
