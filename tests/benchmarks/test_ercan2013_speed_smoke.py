"""Smoke test of benchmarks/ercan2013_speed.py: it runs and prints JSON of the documented shape."""

import json
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "ercan2013_speed.py"


def test_benchmark_prints_timings():
    cmd = [sys.executable, str(SCRIPT), "--particles", "100", "--occluders", "5", "--select", "3",
           "--repeats", "1", "--json"]  # fmt: skip
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=300, check=True)
    data = json.loads(out.stdout.strip().splitlines()[-1])
    for key in ("likelihood_ms", "greedy_perspective_ms", "brute_weak_ms", "moments_weak_ms"):
        assert data[key] > 0
