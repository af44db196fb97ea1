"""Smoke test of benchmarks/ercan2013_q_rows.py: it runs, checks the two formulas agree and prints
JSON of the documented shape."""

import json
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "ercan2013_q_rows.py"


def test_benchmark_prints_both_timings():
    cmd = [sys.executable, str(SCRIPT), "--occluders", "7", "--lines", "50", "--repeats", "1",
           "--sd", "0.5", "16", "--json"]  # fmt: skip
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=300, check=True)
    data = json.loads(out.stdout.strip().splitlines()[-1])
    assert [r["sd"] for r in data] == [0.5, 16.0]
    for r in data:
        assert r["row_ns_per_triple"] > 0 and r["one_triple_ns_per_triple"] > 0
    assert 0.0 < data[0]["q_positive_share"] < data[1]["q_positive_share"]  # wider: more q > 0


def test_benchmark_times_rows_on_whole_blocks():
    cmd = [sys.executable, str(SCRIPT), "--lines", "30", "--repeats", "1", "--sd", "8",
           "--lengths", "7", "16", "--json"]  # fmt: skip
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=300, check=True)
    data = json.loads(out.stdout.strip().splitlines()[-1])
    lengths = [r for r in data if "row_length" in r]
    assert [(r["row_length"], r["padded_to"]) for r in lengths] == [(7, 8), (16, 16)]
    for r in lengths:
        assert r["exact_ns_per_line"] > 0 and r["padded_ns_per_line"] > 0


def test_benchmark_refuses_a_row_of_no_occluders():
    cmd = [sys.executable, str(SCRIPT), "--lengths", "0", "--json"]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert out.returncode != 0 and "--lengths=[0] is invalid" in out.stderr
