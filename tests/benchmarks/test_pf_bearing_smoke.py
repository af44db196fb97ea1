"""Smoke test of benchmarks/pf_bearing.py: it runs and prints JSON of the documented shape.

No timing assertions: speed is measured by running the benchmark, not by the test suite.
"""

from __future__ import annotations

import math

import pytest
from _bench_json import bench_json


def _has_bootstrap_filter() -> bool:
    try:
        from fusetrack.filters import BootstrapFilter  # noqa: F401
    except ImportError:
        return False
    return True


def _run(libs: list[str]) -> list[dict]:
    args = ("--N", "200", "300", "--steps", "4", "--repeats", "1", "--libs", *libs)
    return bench_json("pf_bearing.py", *args, timeout=300)


def _check_shape(rows: list[dict], libs: list[str]) -> None:
    assert [r["N"] for r in rows] == [200, 300]
    for r in rows:
        assert {"N", "seconds_per_step", "rmse"} <= set(r)
        assert set(r["seconds_per_step"]) == set(libs)
        assert set(r["rmse"]) == set(libs)
        for lib in libs:
            t, rmse = r["seconds_per_step"][lib], r["rmse"][lib]
            assert isinstance(t, float) and t > 0
            assert isinstance(rmse, float) and math.isfinite(rmse) and rmse >= 0


def test_numpy_only_prints_documented_json() -> None:
    _check_shape(_run(["numpy"]), ["numpy"])


@pytest.mark.skipif(not _has_bootstrap_filter(), reason="fusetrack.filters.BootstrapFilter missing")
def test_fusetrack_and_numpy_print_documented_json() -> None:
    _check_shape(_run(["numpy", "fusetrack"]), ["numpy", "fusetrack"])
