"""Smoke test of benchmarks/kushwaha2010_harmonic_speed.py: it runs and reports its ratios (no timing asserts)."""

from _bench_json import bench_json


def test_harmonic_speed_benchmark_runs():
    (result,) = bench_json(
        "kushwaha2010_harmonic_speed.py", "--repeats", "1", "--sources", "2", timeout=120
    )
    assert result["sweep_ms_4_sources"] >= 0
    assert result["step_to_cycle_ratio"] > 0
