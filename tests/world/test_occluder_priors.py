"""Occluder-prior constructions of Ercan et al. 2013 Sec. 6.1 (world/occluder_priors.py)."""

import numpy as np
import pytest

from fusetrack.core import Gaussian, Measurement
from fusetrack.core.errors import ConfigError
from fusetrack.experiments.ercan2013.scenes import get_scene
from fusetrack.experiments.ercan2013.simulation import run_tracking, simulate_world
from fusetrack.filters import KalmanFilter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import PositionFix
from fusetrack.world.occluder_priors import (
    ConstantVelocityPriorFilter,
    prior_nees,
    prior_track,
    rmse_per_coordinate,
)

CENTER = np.array([50.0, 50.0])


@pytest.fixture(scope="module")
def walkers():
    """20 walkers of the open square room for 2000 steps (the truth the priors track)."""
    _, occ = simulate_world(get_scene("square-open"), 20, 2000, seed=5)
    return occ[1:]


def test_constant_velocity_bank_equals_the_library_kalman_filter():
    """Each occluder's filter is the textbook CV Kalman filter: same means and variances."""
    rng = np.random.default_rng(0)
    steps, sigma, q = 60, 4.0, 0.03
    truth = np.cumsum(rng.normal(0, 1, (steps, 3, 2)), axis=0) + CENTER
    bank = ConstantVelocityPriorFilter(sigma, q)
    means, var = bank.run(truth, CENTER, np.random.default_rng(7))
    readings = truth + sigma * np.random.default_rng(7).standard_normal(truth.shape)
    kf = KalmanFilter(
        ConstantVelocity(ndim=2, q=q, noise="discrete"),
        [PositionFix("psi", cov=sigma**2 * np.eye(2))],
    )
    for j in range(3):
        g = Gaussian(
            np.array([*CENTER, 0.0, 0.0]),
            np.diag([bank.initial_var] * 2 + [bank.initial_speed_var] * 2),
        )
        for t in range(steps):
            g = kf.update(kf.predict(g, 1.0), Measurement(float(t), "psi", readings[t, j]))
            np.testing.assert_allclose(means[t, j], g.mean[:2], rtol=0, atol=1e-8)
            np.testing.assert_allclose(g.cov[:2, :2], var[t] * np.eye(2), rtol=1e-9, atol=1e-9)


def test_constant_velocity_priors_are_calibrated_and_random_walk_ones_are_not(walkers):
    """On heading-keeping walkers the CV priors claim the variance they have; the random walk
    (process noise 3, the experiments' default) lags them and claims too little at large noise."""
    cv = prior_track("constant-velocity", 16.0, 3.0, walkers, CENTER, np.random.default_rng(1))
    rw = prior_track("random-walk", 32.0, 3.0, walkers, CENTER, np.random.default_rng(1))
    assert 0.8 < prior_nees(*cv, walkers) < 1.25
    assert prior_nees(*rw, walkers) > 1.5


def test_calibrated_oracle_scales_the_random_walk_to_unit_ratio(walkers):
    rw = prior_track("random-walk", 16.0, 3.0, walkers, CENTER, np.random.default_rng(2))
    cal = prior_track(
        "calibrated-random-walk", 16.0, 3.0, walkers, CENTER, np.random.default_rng(2)
    )
    np.testing.assert_array_equal(cal[0], rw[0])  # same track
    assert prior_nees(*cal, walkers) == pytest.approx(1.0, abs=1e-12)
    assert np.all(cal[1] > rw[1])  # overconfident before: the oracle widens


def test_white_oracle_keeps_the_accuracy_and_drops_the_persistence(walkers):
    rw_m, _ = prior_track("random-walk", 16.0, 3.0, walkers, CENTER, np.random.default_rng(3))
    wh_m, wh_v = prior_track("white", 16.0, 3.0, walkers, CENTER, np.random.default_rng(3))
    s = rmse_per_coordinate(rw_m, walkers)
    assert rmse_per_coordinate(wh_m, walkers) == pytest.approx(s, rel=0.02)
    np.testing.assert_allclose(wh_v, s * s)

    def lag1(err):  # correlation of an occluder's error with its error one step later
        e = err - err.mean(axis=0)
        return float(np.sum(e[1:] * e[:-1]) / np.sum(e * e))

    assert lag1(rw_m - walkers) > 0.9  # the Kalman track's error persists
    assert abs(lag1(wh_m - walkers)) < 0.05


def test_perfect_and_empty_inputs():
    truth = np.zeros((5, 0, 2))
    for kind in ("random-walk", "constant-velocity", "calibrated-random-walk", "white"):
        m, v = prior_track(kind, 3.0, 3.0, truth, CENTER, np.random.default_rng(0))
        assert m.shape == (5, 0, 2) and v.shape == (5,)
    t = np.ones((4, 2, 2))
    m, v = prior_track("white", 0.0, 3.0, t, CENTER, np.random.default_rng(0))
    np.testing.assert_array_equal(m, t)
    assert np.all(v == 0)


def test_unknown_prior_filter_is_refused():
    with pytest.raises(ConfigError, match="prior_filter"):
        prior_track("kalman", 3.0, 3.0, np.zeros((2, 1, 2)), CENTER, np.random.default_rng(0))
    with pytest.raises(ConfigError, match="prior_filter"):
        run_tracking({"prior_filter": "kalman", "steps": 2, "particles": 10}, 0)
