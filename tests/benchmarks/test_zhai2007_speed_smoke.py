"""Smoke test of benchmarks/zhai2007_speed.py: every filter runs and is timed."""

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

import zhai2007_speed


def test_speed_benchmark_runs(capsys):
    assert (
        zhai2007_speed.main(
            ["--N", "50", "--steps", "3", "--repeats", "1", "--no-scaling", "--json"]
        )
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    per = out["N=50"]["seconds_per_step"]
    assert set(per) == set(zhai2007_speed.builders(50))
    assert all(v > 0 for v in per.values())
    # every Zhai 2007 filter of issue 5 is in the benchmark, with the two comparators
    assert {"CPF-SP", "discretisation MMPF", "PF + MH-prior move", "PF + MIS move"} <= set(per)
    assert {"UPF", "IMM-EKF"} <= set(per)


def test_linear_fit_recovers_a_line():
    fit = zhai2007_speed.linear_fit([1, 2, 4, 8], [3.0, 5.0, 9.0, 17.0])
    assert abs(fit["slope"] - 2) < 1e-12 and abs(fit["intercept"] - 1) < 1e-12
    assert abs(fit["r2"] - 1) < 1e-12
