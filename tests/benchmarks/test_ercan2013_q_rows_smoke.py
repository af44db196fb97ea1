"""Smoke test of benchmarks/ercan2013_q_rows.py: it runs, checks the two formulas agree and prints
JSON of the documented shape."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

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
    for r in data:  # the probe of where the row's time goes
        assert r["table_reads_ns_per_triple"] > 0 and r["l1_table_reads_ns_per_triple"] > 0


def test_probe_reads_the_rows_the_row_reads():
    """The reads probe interpolates the normal CDF at the row's own arguments: through the
    kernels' table it gives Phi at each triple's four arguments (to the table's 3.3e-8)."""
    import importlib.util

    from scipy.stats import norm

    spec = importlib.util.spec_from_file_location("q_rows", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    rng = np.random.default_rng(3)
    m = rng.uniform(-30, 30, (6, 2))
    ang = rng.uniform(0, 2 * np.pi, 20)
    lines = np.c_[np.cos(ang), np.sin(ang), rng.uniform(5, 40, 20)]
    index, frac = mod.table_rows(lines, m, 8.0)
    out = np.empty(index.shape)
    mod.reads(index, frac, mod._PHI_TABLE, out)
    phi = -lines[:, 1:2] * m[:, 0] + lines[:, 0:1] * m[:, 1]
    m_a = lines[:, 0:1] * m[:, 0] + lines[:, 1:2] * m[:, 1]
    args = np.stack([mod.HALF - phi, -mod.HALF - phi, lines[:, 2:3] - m_a, -m_a], axis=1) / 8.0
    assert np.max(np.abs(out - norm.cdf(args))) < 4e-8
    assert ((frac >= 0) & (frac < 1)).all()
