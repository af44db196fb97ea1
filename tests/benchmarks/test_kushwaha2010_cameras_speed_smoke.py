"""Smoke test of benchmarks/kushwaha2010_cameras_speed.py: it runs and reports (no timing asserts)."""

from _bench_json import bench_json


def test_cameras_speed_benchmark_runs():
    (result,) = bench_json(
        "kushwaha2010_cameras_speed.py", "--repeats", "1", "--particles", "100", timeout=300
    )
    assert result["cameras"] == 10 and result["particles"] == 100
    assert result["T0_step_cpu_s"] > 0 and result["numpy_reference_over_numba"] > 0
