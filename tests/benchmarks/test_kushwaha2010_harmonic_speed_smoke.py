"""Smoke test of benchmarks/kushwaha2010_harmonic_speed.py: it runs and reports its ratios (no timing asserts)."""

import json
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "kushwaha2010_harmonic_speed.py"


def test_harmonic_speed_benchmark_runs():
    out = subprocess.run(
        [sys.executable, str(SCRIPT), "--repeats", "1", "--sources", "2", "--json"],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    result = json.loads(out.stdout)
    assert result["sweep_ms_4_sources"] >= 0
    assert result["step_to_cycle_ratio"] > 0
