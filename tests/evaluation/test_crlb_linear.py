"""PCRB on linear-Gaussian models equals the Kalman filter's covariance recursion."""

import numpy as np
import pytest

from fusetrack.core import ConfigError, ShapeError
from fusetrack.evaluation.crlb import (
    axis_bounds,
    position_rmse_bound,
    posterior_crlb,
    posterior_information,
    velocity_rmse_bound,
)
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import PositionFix

CV = ConstantVelocity(ndim=2, q=0.3)
TAG_A = PositionFix("a", cov=[[0.5, 0.1], [0.1, 0.3]])
TAG_B = PositionFix("b", cov=np.diag([2.0, 0.05]))
P0 = np.diag([4.0, 4.0, 1.0, 1.0])


def kf_covariances(dts, mask, sensors=(TAG_A, TAG_B)):
    """Textbook KF covariance recursion: predict P = F P F^T + Q, update P = (I - K H) P."""
    H = np.hstack([np.eye(2), np.zeros((2, 2))])
    P = P0.copy()
    out = []
    for k in range(len(mask)):
        if k:
            F = CV.transition_matrix(dts[k - 1])
            P = F @ P @ F.T + CV.noise_cov(dts[k - 1])
        for s, sensor in enumerate(sensors):
            if mask[k][s]:
                S = H @ P @ H.T + sensor.noise_cov()
                K = P @ H.T @ np.linalg.inv(S)
                P = (np.eye(4) - K @ H) @ P
        out.append(P)
    return np.array(out)


def trajectories(R, T, dts, seed=0):
    rng = np.random.default_rng(seed)
    x = np.empty((R, T, 4))
    x[:, 0] = rng.multivariate_normal([0, 0, 1, -1], P0, size=R)
    for k in range(T - 1):
        x[:, k + 1] = CV.sample(x[:, k], dts[k], rng)
    return x


def test_equals_kalman_filter_every_step_measured():
    T, dt = 30, 0.5
    x = trajectories(1, T, [dt] * (T - 1))
    B = posterior_crlb(CV, [TAG_A], x, dt, P0)
    P = kf_covariances([dt] * T, np.ones((T, 1), bool), sensors=(TAG_A,))
    assert B.shape == (T, 4, 4)
    np.testing.assert_allclose(B, P, rtol=0, atol=1e-9)


def test_equals_kalman_filter_irregular_dt_and_missing_reports():
    rng = np.random.default_rng(3)
    T = 40
    dts = rng.uniform(0.05, 2.0, size=T - 1)
    mask = rng.random((T, 2)) < 0.6
    mask[0] = False  # the filter starts from the prior without a report
    mask[10:18] = False  # a gap with no reports at all
    x = trajectories(5, T, dts)  # linear model: the trajectories do not matter
    B = posterior_crlb(CV, {"a": TAG_A, "b": TAG_B}, x, dts, P0, mask=mask)
    np.testing.assert_allclose(B, kf_covariances(dts, mask), rtol=0, atol=1e-9)
    # the same through a per-run mask (R, T, S), and per run
    Bm = posterior_crlb(CV, [TAG_A, TAG_B], x, dts, P0, mask=np.broadcast_to(mask, (5, T, 2)))
    np.testing.assert_allclose(Bm, B, atol=1e-12)
    Br = posterior_crlb(CV, [TAG_A, TAG_B], x, dts, P0, mask=mask, average=False)
    assert Br.shape == (5, T, 4, 4)
    np.testing.assert_allclose(Br, np.broadcast_to(B, Br.shape), atol=1e-9)


def test_per_run_masks_average_information():
    T, dt = 6, 1.0
    x = trajectories(2, T, [dt] * (T - 1))
    mask = np.ones((2, T, 1), bool)
    mask[1, 3] = False  # run 1 misses step 3: expected information at step 3 is half
    J = posterior_information(CV, [TAG_A], x, dt, P0, mask=mask)
    half = posterior_information(CV, [TAG_A], x, dt, P0, mask=np.where(mask.all(0), 1.0, 0.5))
    np.testing.assert_allclose(J, half, atol=1e-12)
    Jr = posterior_information(CV, [TAG_A], x, dt, P0, mask=mask, average=False)
    np.testing.assert_allclose(
        Jr[1], posterior_information(CV, [TAG_A], x[1], dt, P0, mask=mask[1]), atol=1e-12
    )


@pytest.mark.parametrize("p", [0.3, 0.8])
def test_detection_probability_scales_one_step_of_information(p):
    tag = PositionFix("p", cov=TAG_A.cov, detection_prob=p)
    x = trajectories(3, 2, [1.0])
    J = posterior_information(CV, [tag], x, 1.0, P0, use_detection_probability=True)
    HRH = TAG_A.fisher_information(x[0, 0])
    np.testing.assert_allclose(J[0] - np.linalg.inv(P0), p * HRH, atol=1e-12)
    F, Q = CV.transition_matrix(1.0), CV.noise_cov(1.0)
    prior1 = np.linalg.inv(F @ np.linalg.inv(J[0]) @ F.T + Q)
    np.testing.assert_allclose(J[1] - prior1, p * HRH, atol=1e-9)
    # the same factor given through a float mask
    Jm = posterior_information(CV, [TAG_A], x, 1.0, P0, mask=np.full((2, 1), p))
    np.testing.assert_allclose(Jm, J, atol=1e-12)
    # and mask x detection probability multiply
    Jb = posterior_information(
        CV, [tag], x, 1.0, P0, mask=np.full((2, 1), 0.5), use_detection_probability=True
    )
    np.testing.assert_allclose(Jb[0] - np.linalg.inv(P0), 0.5 * p * HRH, atol=1e-12)


def test_rmse_bound_helpers():
    B = posterior_crlb(CV, [TAG_A], trajectories(1, 5, [1.0] * 4), 1.0, P0)
    np.testing.assert_allclose(
        position_rmse_bound(B, CV.position_index), np.sqrt(B[:, 0, 0] + B[:, 1, 1])
    )
    np.testing.assert_allclose(
        velocity_rmse_bound(B, CV.velocity_index), np.sqrt(B[:, 2, 2] + B[:, 3, 3])
    )
    np.testing.assert_allclose(axis_bounds(B, (1, 3)), np.sqrt(B[:, [1, 3], [1, 3]]))
    assert axis_bounds(B).shape == (5, 4)


def test_errors():
    x = trajectories(1, 4, [1.0] * 3)
    discrete = ConstantVelocity(ndim=2, q=0.3, noise="discrete")
    with pytest.raises(ConfigError, match=r"dt=0\.25"):  # Prop. 1 needs Q^-1
        posterior_crlb(discrete, [TAG_A], x, 0.25, P0, form="information")
    with pytest.raises(ConfigError, match=r"dt\[1\]"):
        posterior_crlb(CV, [TAG_A], x, [1.0, 0.0, 1.0], P0)
    with pytest.raises(ShapeError, match="dt"):
        posterior_crlb(CV, [TAG_A], x, [1.0, 1.0], P0)
    with pytest.raises(ShapeError, match="mask"):
        posterior_crlb(CV, [TAG_A], x, 1.0, P0, mask=np.ones((4, 2), bool))
    with pytest.raises(ConfigError, match="mask"):
        posterior_crlb(CV, [TAG_A], x, 1.0, P0, mask=np.full((4, 1), 2.0))
    with pytest.raises(ConfigError, match="prior_cov"):
        posterior_crlb(CV, [TAG_A], x, 1.0, -P0)
    with pytest.raises(ShapeError, match="trajectories"):
        posterior_crlb(CV, [TAG_A], x[..., :3], 1.0, P0)
