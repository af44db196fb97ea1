"""NEES / NIS against hand values, the chi-square interval, a correctly specified Kalman filter."""

import numpy as np
import pytest
from scipy.stats import chi2

from fusetrack.core import ConfigError, ShapeError
from fusetrack.evaluation.metrics import average, chi2_interval, nees, nis


def test_nees_hand_values():
    est = np.array([[[1.0, 2.0]], [[0.0, 3.0]]])  # (T=2, R=1, d=2)
    truth = np.zeros((2, 1, 2))
    cov = np.array([[[[1.0, 0.0], [0.0, 4.0]]], [[[2.0, 1.0], [1.0, 2.0]]]])
    v = nees(est, cov, truth)
    # step 0: 1/1 + 4/4 = 2; step 1: [0,3] inv([[2,1],[1,2]]) [0,3] = 9 * 2/3 = 6
    np.testing.assert_allclose(v, [[2.0], [6.0]])
    # sub-block: only the second component
    np.testing.assert_allclose(nees(est, cov, truth, index=(1,)), [[1.0], [4.5]])


def test_nees_nan_and_shapes():
    est = np.array([[1.0, 0.0], [np.nan, 0.0]])
    cov = np.broadcast_to(np.eye(2), (2, 2, 2)).copy()
    v = nees(est, cov, np.zeros(2))
    assert v[0] == pytest.approx(1.0) and np.isnan(v[1])
    cov[0] = np.nan
    assert np.isnan(nees(est, cov, np.zeros(2))).all()
    with pytest.raises(ShapeError, match="covariances"):
        nees(est, np.eye(2), np.zeros(2))
    with pytest.raises(ConfigError, match="singular"):
        nees(est[:1], np.zeros((1, 2, 2)), np.zeros(2))


def test_nis():
    nu = np.array([[2.0], [1.0]])
    s = np.array([[[4.0]], [[0.5]]])
    np.testing.assert_allclose(nis(nu, s), [1.0, 2.0])


def test_chi2_interval():
    lo, hi = chi2_interval(2, 50)
    assert lo == pytest.approx(chi2.ppf(0.025, 100) / 50)
    assert hi == pytest.approx(chi2.ppf(0.975, 100) / 50)
    assert lo < 2 < hi
    # coverage: averages of 50 chi2(4) draws fall inside about 95 % of the time
    lo, hi = chi2_interval(4, 50)
    means = np.random.default_rng(0).chisquare(4, size=(4000, 50)).mean(axis=1)
    assert np.mean((means > lo) & (means < hi)) == pytest.approx(0.95, abs=0.015)
    with pytest.raises(ConfigError, match="dof"):
        chi2_interval(0, 10)
    with pytest.raises(ConfigError, match="confidence"):
        chi2_interval(2, 10, confidence=1.0)


def test_nees_of_a_correct_kalman_filter_averages_to_d():
    rng = np.random.default_rng(7)
    R, T, dt, q = 400, 40, 0.5, 0.3
    F = np.eye(4)
    F[0, 2] = F[1, 3] = dt
    qa = q * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
    Q = np.kron(qa, np.eye(2))
    H = np.hstack([np.eye(2), np.zeros((2, 2))])
    Rm = np.diag([0.4, 0.9])
    P0 = np.diag([1.0, 1.0, 0.5, 0.5])
    x = rng.multivariate_normal(np.zeros(4), P0, size=R)  # truth
    m = np.zeros((R, 4))
    P = P0.copy()
    means, covs, truths, innov, scov = [], [], [], [], []
    for k in range(T):
        if k:
            x = x @ F.T + rng.multivariate_normal(np.zeros(4), Q, size=R)
            m = m @ F.T
            P = F @ P @ F.T + Q
        z = x @ H.T + rng.multivariate_normal(np.zeros(2), Rm, size=R)
        S = H @ P @ H.T + Rm
        K = P @ H.T @ np.linalg.inv(S)
        nu = z - m @ H.T
        m = m + nu @ K.T
        P = (np.eye(4) - K @ H) @ P
        means.append(m)
        covs.append(np.broadcast_to(P, (R, 4, 4)))
        truths.append(x)
        innov.append(nu)
        scov.append(np.broadcast_to(S, (R, 2, 2)))
    v = nees(np.array(means), np.array(covs), np.array(truths))  # (T, R)
    assert v.shape == (T, R)
    assert average(v, over="all") == pytest.approx(4.0, abs=0.15)
    lo, hi = chi2_interval(4, R)
    per_step = average(v)
    assert np.mean((per_step > lo) & (per_step < hi)) >= 0.85
    w = nis(np.array(innov), np.array(scov))
    assert average(w, over="all") == pytest.approx(2.0, abs=0.1)
    # position-only NEES has 2 degrees of freedom
    assert average(
        nees(np.array(means), np.array(covs), np.array(truths), index=(0, 1)), over="all"
    ) == pytest.approx(2.0, abs=0.1)
