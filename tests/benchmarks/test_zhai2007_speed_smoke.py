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
