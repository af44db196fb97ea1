"""Smoke test of benchmarks/kushwaha2010_speed.py: it runs and reports both budgets (no timing asserts)."""

import json
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "kushwaha2010_speed.py"


def test_speed_benchmark_runs():
    out = subprocess.run(
        [sys.executable, str(SCRIPT), "--repeats", "1", "--json"],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    result = json.loads(out.stdout)
    assert result["beamformer_realtime_factor_6_nodes"] > 0
    assert result["fusion_step_ms_9_sensors_2800_cells"] > 0
