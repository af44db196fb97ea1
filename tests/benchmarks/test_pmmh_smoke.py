"""Smoke test of benchmarks/pmmh.py: it runs, prints the documented JSON, and fusetrack's PMMH
is the hand-written limit reference's chain (the same draws in the same order).

No timing assertions: speed is measured by running the benchmark, not by the test suite.
"""

from __future__ import annotations

from _bench_json import bench_json


def test_fusetrack_runs_the_limit_references_chain() -> None:
    rows = bench_json(
        "pmmh.py", "--iterations", "20", "--libs", "fusetrack", "limit_reference", timeout=600
    )
    assert [r["library"] for r in rows] == ["fusetrack", "limit_reference"]
    ours, ref = rows
    for r in rows:
        assert r["ms_per_iteration_cpu"] > 0 and r["ms_per_iteration_wall"] > 0
        assert 0.0 <= r["acceptance_rate"] <= 1.0
        assert r["agreement_with_limit_reference"]["agree"] is True
    for key in ("acceptance_rate", "posterior_mean_log_q", "posterior_mean_log_r"):
        assert ours[key] == ref[key], key
    assert ref["cpu_ratio_to_limit_reference"] == 1.0
