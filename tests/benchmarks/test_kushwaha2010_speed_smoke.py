"""Smoke test of benchmarks/kushwaha2010_speed.py: it runs and reports both budgets (no timing asserts)."""

from _bench_json import bench_json


def test_speed_benchmark_runs():
    (result,) = bench_json("kushwaha2010_speed.py", "--repeats", "1", timeout=120)
    assert result["beamformer_realtime_factor_6_nodes"] > 0
    assert result["fusion_step_ms_9_sensors_2800_cells"] > 0
