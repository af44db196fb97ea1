"""Smoke test of benchmarks/kushwaha2010_cameras_speed.py: it runs and reports (no timing asserts)."""

import json
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "kushwaha2010_cameras_speed.py"


def test_cameras_speed_benchmark_runs():
    out = subprocess.run(
        [sys.executable, str(SCRIPT), "--repeats", "1", "--particles", "100", "--json"],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    result = json.loads(out.stdout)
    assert result["cameras"] == 10 and result["particles"] == 100
    assert result["T0_step_cpu_s"] > 0 and result["numpy_reference_over_numba"] > 0
