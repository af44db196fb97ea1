"""The generic "beyond the paper" comparators of issue 5 (no timing assertions: a fake clock)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from fusetrack.core import Gaussian
from fusetrack.experiments.zhai2007.common import timed_gaussian
from fusetrack.experiments.zhai2007.comparators import (
    Scenario,
    beyond_table,
    calibrate_particles,
    compare,
    equal_time_particles,
    pilot_seconds,
    run_comparators,
)
from fusetrack.filters import ExtendedKalmanFilter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import PositionFix


class FakeClock:
    """A clock that only moves when a fake workload says so."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def affine_workload(clock: FakeClock, a: float, b: float, noise: list[float] | None = None):
    extra = iter(noise or [])

    def run(n: int) -> None:
        clock.now += a + b * n + next(extra, 0.0)

    return run


def test_calibration_solves_the_affine_cost_for_the_target():
    clock = FakeClock()
    # t(N) = 0.3 + 1e-4 N: t(200) = 0.32, t(2000) = 0.5; target 1.0 -> N = 7000
    n = calibrate_particles(affine_workload(clock, 0.3, 1e-4), 1.0, clock=clock, repeats=2)
    assert n == 7000
    # the proportional rule from the larger pilot would have said 2000 * 1.0 / 0.5 = 4000
    n = calibrate_particles(affine_workload(clock, 0.3, 1e-4), 0.41, clock=clock, step=10)
    assert n == 1100


def test_calibration_uses_the_fastest_pilot_rounds_and_clips():
    clock = FakeClock()
    # three repeats at each pilot N; the disturbed (slower) ones must be ignored
    noise = [0.5, 0.0, 0.2, 0.0, 0.9, 0.3]
    run = affine_workload(clock, 0.0, 1e-3, noise)
    assert calibrate_particles(run, 1.234, clock=clock) == 1250  # 1234 rounded to 50
    assert (
        calibrate_particles(affine_workload(clock, 0, 1e-3), 1e3, clock=clock, n_max=5000) == 5000
    )
    assert calibrate_particles(affine_workload(clock, 0, 1e-3), 0.0, clock=clock) == 50


def test_calibration_falls_back_to_proportional_when_the_pilot_is_flat():
    clock = FakeClock()
    noise = [0.2, 0.2, 0.2, 0.0, 0.0, 0.0]  # t(200) = 0.2 + 0.02 > t(2000) = 0.2
    run = affine_workload(clock, 0.0, 1e-4, noise)
    assert calibrate_particles(run, 0.4, clock=clock) == 4000  # 2000 * 0.4 / 0.2


def test_pilot_seconds_is_the_minimum():
    clock = FakeClock()
    times = iter([3.0, 1.0, 2.0])

    def fn() -> None:
        clock.now += next(times)

    assert pilot_seconds(fn, 3, clock) == 1.0


def _scenario(rng: np.random.Generator) -> Scenario:
    motion = ConstantVelocity(q=0.1)
    sensor = PositionFix("gps", cov=np.eye(2))
    x = np.array([0.0, 0.0, 1.0, 0.5])
    truth, zs = [], []
    for _ in range(15):
        x = motion.sample(x, 1.0, rng)
        truth.append(x)
        zs.append([sensor.simulate(x, rng)])
    return Scenario(motion, [sensor], Gaussian(np.zeros(4), np.eye(4)), zs, 1.0, np.array(truth))


def test_one_model_imm_is_the_ekf_and_particle_comparators_track():
    scn = _scenario(np.random.default_rng(1))
    out = run_comparators(scn, 7, {"UPF": 1000, "bootstrap equal time": 300})
    ekf, _ = timed_gaussian(
        ExtendedKalmanFilter(scn.motion, scn.sensors), scn.prior, scn.zs, ["gps"], 1.0
    )
    np.testing.assert_allclose(out["IMM-EKF"].estimates, ekf, atol=1e-12)

    def rmse(est: np.ndarray) -> float:
        return float(np.sqrt(np.mean(np.sum((est[5:, :2] - scn.truth[5:, :2]) ** 2, axis=1))))

    # linear-Gaussian: the Kalman filter is optimal; the bootstrap is close to it; the
    # shared-covariance UPF converges slowly (its paired weights degenerate: see the report),
    # but a broken proposal would be far off (the measurements have unit variance)
    assert rmse(out["bootstrap equal time"].estimates) < 1.3 * rmse(ekf) + 0.1
    assert rmse(out["UPF"].estimates) < 2.5 * rmse(ekf)
    again = run_comparators(scn, 7, {"UPF": 1000}, ["IMM-EKF", "UPF"])
    np.testing.assert_array_equal(again["UPF"].estimates, out["UPF"].estimates)


def test_equal_time_particles_with_a_fake_clock():
    scn = _scenario(np.random.default_rng(2))
    clock = FakeClock()

    def reference() -> None:
        clock.now += 1.0

    # the fake clock does not move while the real filters run: flat pilot -> fallback rule;
    # with the clock advanced by the reference only the target is 1.0
    n, target = equal_time_particles(scn, reference, repeats=1, clock=clock)
    assert target == 1.0 and n == {"bootstrap equal time": 200_000}


def _per_run() -> pd.DataFrame:
    rows = []
    spec = {"ref": (1.0, 1.0), "UPF": (0.5, 3.0), "IMM-EKF": (2.0, 0.01), "bs": (0.8, 1.4)}
    for s in ("A", "B"):
        for m, (e, t) in spec.items():
            for r in range(3):
                rows.append({"scn": s, "method": m, "run": r, "error": e + 0.01 * r, "seconds": t})
    return pd.DataFrame(rows)


def test_winner_at_equal_time_excludes_slower_methods():
    table, winners = beyond_table(_per_run(), "ref", by=["scn"])
    assert list(winners["winner at equal time"]) == ["bs", "bs"]
    assert list(winners["winner overall"]) == ["UPF", "UPF"]
    assert table.loc[("A", "UPF"), "time / reference"] == pytest.approx(3.0)
    assert table.loc[("B", "ref"), "mean"] == pytest.approx(1.01)
    # higher-is-better scores (e.g. ISNR) pick the maximum
    _, w = beyond_table(_per_run(), "ref", by=["scn"], better="higher")
    assert list(w["winner at equal time"]) == ["IMM-EKF", "IMM-EKF"]


def test_compare_writes_figure_section_and_summary(tmp_path):
    c = compare(_per_run()[lambda d: d.scn == "A"], "ref", tmp_path / "f.png", calibration="c")
    assert (tmp_path / "f.png").exists()
    assert "Beyond the paper" in c.section and "f.png" in c.section
    assert c.summary["winners"]["all"]["winner at equal time"] == "bs"
    assert c.summary["methods"]["UPF"]["seconds_per_run"] == 3.0
