"""Smoke tests of the issue-3 speed benchmarks: they run and print JSON of the documented shape,
and their equality checks hold. No timing assertions (speed is measured by the benchmarks)."""

from __future__ import annotations

from _bench_json import bench_json


def test_pf_bearing_limit_reference_matches_fusetrack_rmse() -> None:
    (row,) = bench_json(
        "pf_bearing.py", "--N", "300", "--steps", "4", "--repeats", "1",
        "--libs", "fusetrack", "limit_reference",
    )  # fmt: skip
    assert set(row["seconds_per_step"]) == {"fusetrack", "limit_reference"}
    assert row["seconds_per_step"]["limit_reference"] > 0
    # the same draws: the estimates agree to rounding
    assert abs(row["rmse"]["fusetrack"] - row["rmse"]["limit_reference"]) < 1e-9


def test_kalman_batch_equals_filterpy() -> None:
    rows = bench_json("kalman_batch.py", "--tracks", "6", "--steps", "4", "--repeats", "1")
    assert [r["filter"] for r in rows] == ["ekf", "ukf"]
    for r in rows:
        assert set(r["seconds_per_step"]) == {"fusetrack", "filterpy"}
        assert r["max_abs_diff"]["mean"] < 1e-9 and r["max_abs_diff"]["cov"] < 1e-9


def test_batched_runs_are_bit_identical_to_separate_runs() -> None:
    (row,) = bench_json(
        "batched_runs.py", "--runs", "3", "--N", "64", "--steps", "3", "--repeats", "1"
    )
    assert row["bit_identical"] is True
    assert set(row["seconds_per_step"]) == {"separate", "batched"}


def test_step_floor_reports_every_phase_and_the_bar() -> None:
    (row,) = bench_json("step_floor.py", "--N", "20000", "--repeats", "2", "--steps", "2")
    phases = {"normals", "propagate", "bearings", "max + NumPy exp", "resample + gather"}
    assert phases <= set(row["ns_per_particle"])
    floor = row["floor_ns_per_particle"]["serial"]
    parts = [v["serial"] for k, v in row["ns_per_particle"].items() if not k.startswith("(")]
    assert abs(floor - sum(parts)) <= 1e-9 * floor
    assert abs(row["bar_ms_per_step"] - 107.0 / 30.0) < 1e-12
    assert set(row["whole_steps"]) == {"fusetrack", "limit_reference"}
