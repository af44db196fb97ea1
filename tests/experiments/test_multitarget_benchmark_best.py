"""The best possible of ``multitarget-benchmark`` (multitarget/benchmark_best.py with
gospa_floor.py, clairvoyant.py, best_possible.py): the bound by hand, a Kalman filter attaining
it on a linear-Gaussian model, and the claims failing when a tracker beats the floor or the
clairvoyant filter misses it."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from fusetrack.core import Measurement
from fusetrack.experiments.multitarget.benchmark_best import (
    LAYOUT,
    NEAR,
    benchmark_floor_columns,
    oracle,
    paths,
)
from fusetrack.experiments.multitarget.benchmark_scenario import (
    Setting,
    birth_intensity,
    sensors,
    simulate_births_and_deaths,
    simulate_crossing,
)
from fusetrack.experiments.multitarget.best_possible import best_claims, best_table
from fusetrack.experiments.multitarget.clairvoyant import clairvoyant_tracks
from fusetrack.experiments.multitarget.gospa_floor import Oracle
from fusetrack.filters import ExtendedKalmanFilter
from fusetrack.motion import ConstantVelocity

PRIOR = birth_intensity(1.0).covs[0]  # diag(25^2, 25^2, 2^2, 2^2)


def test_one_scan_bound_by_hand():
    """A target 1000 m east of the radar: the radar's range (sd 10 m) informs x and its bearing
    (sd 0.01 rad x 1000 m = 10 m) informs y, the position sensor (sd 10 m) both, each times
    P_D = 0.9: per axis 1/625 + 0.009 + 0.009, the bound 1 / 0.0196 = 51.02 m²."""
    x = np.array([[300.0, -700.0, 10.0, 0.0]])
    online, whole = oracle("sparse", 0.9).position_bounds(x, PRIOR)
    np.testing.assert_allclose(online[0], np.eye(2) / (1 / 625 + 0.018), rtol=1e-9)
    np.testing.assert_allclose(whole[0], online[0], rtol=1e-12)


@pytest.mark.parametrize("p_detect", [1.0, 0.8])
def test_kalman_filter_attains_the_bound_on_a_linear_gaussian_model(p_detect):
    """Position sensor only, paths drawn with the motion's own noise: the clairvoyant Kalman
    filter's mean-square error is the online bound at P_D = 1, and above it (by the reduction
    factor's Jensen gap) at P_D = 0.8."""
    pos = sensors(p_detect)["pos"]
    cv = ConstantVelocity(ndim=2, q=0.5)
    orc = Oracle(cv, [pos], 1.0, p_detect)
    ekf = ExtendedKalmanFilter(cv, [pos])
    rng = np.random.default_rng(5)
    T, reps = 12, 400

    def draw(x, t, rng):
        z = pos.simulate(x[None], rng)[0]
        return [] if np.isnan(z).any() else [Measurement(t, "pos", z)]

    err, bound = [], None
    for _ in range(reps):
        x = np.empty((T, 4))
        x[0] = [0.0, 0.0, 10.0, 0.0]
        for k in range(1, T):
            x[k] = cv.sample(x[k - 1], 1.0, rng)
        on = np.arange(T)
        (tr,) = clairvoyant_tracks(ekf, [(on, x)], on * 1.0, 1.0, [PRIOR], draw, rng)
        err.append(np.sum((tr.means[:, :2] - x[:, :2]) ** 2, axis=1))
        if bound is None:
            bound = np.trace(orc.position_bounds(x, PRIOR)[0], axis1=1, axis2=2)
    ratio = np.mean(err) / np.mean(bound)
    if p_detect == 1.0:
        assert ratio == pytest.approx(1.0, abs=0.08)
    else:
        assert 1.1 < ratio < 1.4  # 1.25 at this seed


def test_floors_and_clairvoyant_on_the_crossing():
    """Four crossing pairs over 31 scans: the whole-run floor is below the online one, and the
    clairvoyant filter is within NEAR of the online floor over a few runs (the claim's check)."""
    world = simulate_crossing(4, 31)
    cols = [
        benchmark_floor_columns("crossing", world, 0.9, 40.0, np.random.default_rng(s))
        for s in range(6)
    ]
    online = cols[0]["floor_online"]
    assert all(c["floor_online"] == online for c in cols)  # a deterministic world
    assert 0 < cols[0]["floor_whole_run"] < online
    ratio = np.mean([c["clairvoyant"] for c in cols]) / online
    assert 0.9 < ratio < NEAR


def test_paths_follow_births_and_deaths():
    world = simulate_births_and_deaths(Setting(), 40, np.random.default_rng(2))
    ps = paths(world)
    assert len(ps) == world.states.shape[1]
    for i, (on, x) in enumerate(ps):
        assert on[0] == world.born[i] and on[-1] == world.last[i]
        assert np.all(np.diff(on) == 1) and np.all(np.isfinite(x))


def _frame(tracker_total: float, clairvoyant: float) -> pd.DataFrame:
    """Four runs of every scenario and tracker: floors 100 (whole run) and 200 (online)."""
    rng = np.random.default_rng(0)
    rows = []
    for s in LAYOUT.groups:
        for run in range(4):
            noise = rng.normal(0, 1.0)
            for t in LAYOUT.methods:
                total = (tracker_total if t == "PMB" else 1000.0) + noise
                rows.append(
                    {
                        "scenario": s,
                        "tracker": t,
                        "run": run,
                        "localisation": total / 2,
                        "missed": total / 4,
                        "false": total / 4,
                        "floor_whole_run": 100.0,
                        "floor_online": 200.0,
                        "clairvoyant": clairvoyant + noise,
                    }
                )
    return pd.DataFrame(rows)


def test_claims_fail_when_a_tracker_beats_the_floor_or_the_clairvoyant_misses_it():
    ok = {c.id: c.holds for c in best_claims(_frame(300.0, 220.0), LAYOUT)}
    assert ok == {"BP_trackers_above_floor": True, "BP_clairvoyant_attains_floor": True}
    below = {c.id: c for c in best_claims(_frame(50.0, 220.0), LAYOUT)}
    assert not below["BP_trackers_above_floor"].holds
    assert below["BP_trackers_above_floor"].ours["PMB sparse"] == pytest.approx(0.5, abs=0.02)
    for clair in (150.0, 260.0):  # below the online floor, or beyond NEAR = 1.25 of it
        held = {c.id: c.holds for c in best_claims(_frame(300.0, clair), LAYOUT)}
        assert not held["BP_clairvoyant_attains_floor"]
    table = best_table(_frame(300.0, 220.0), LAYOUT)
    assert table.loc["PMB", "crossing / whole-run floor"] == "3.0"
    assert table.loc["clairvoyant EKF, own reports", "sparse (m²)"].startswith("220.")
