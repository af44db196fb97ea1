"""PCRB with nonlinear sensors and motion: EKF-at-truth recursion, loop reference, detection."""

import numpy as np
import pytest

from fusetrack.core import ConfigError, ShapeError
from fusetrack.evaluation.crlb import (
    deterministic_crlb,
    posterior_crlb,
    posterior_information,
)
from fusetrack.motion import ConstantVelocity, CoordinatedTurnRate
from fusetrack.sensors import Bearing, PositionFix

CV = ConstantVelocity(ndim=2, q=0.2)
MICS = [
    Bearing("m1", position=[0.0, 0.0], sigma=0.02),
    Bearing("m2", position=[30.0, 5.0], sigma=0.05),
]
P0 = np.diag([1.0, 1.0, 0.25, 0.25])


def cv_truth(T, dt, R=1, seed=1):
    rng = np.random.default_rng(seed)
    x = np.empty((R, T, 4))
    x[:, 0] = [5.0, 10.0, 1.0, 0.2]
    for k in range(T - 1):
        x[:, k + 1] = CV.sample(x[:, k], dt, rng)
    return x


def test_one_trajectory_equals_ekf_linearised_at_the_truth():
    T, dt = 25, 1.0
    x = cv_truth(T, dt)
    B = posterior_crlb(CV, MICS, x, dt, P0)
    F, Q = CV.transition_matrix(dt), CV.noise_cov(dt)
    P = P0.copy()
    for k in range(T):
        if k:
            P = F @ P @ F.T + Q
        info = sum(s.fisher_information(x[0, k]) for s in MICS)
        P = np.linalg.inv(np.linalg.inv(P) + info)
        np.testing.assert_allclose(B[k], P, rtol=1e-9, atol=1e-12)


def reference_information(motion, sensors, x, dts, P0, weights):
    """Tichavský et al. 1998 written out with a loop over runs (slow, obvious)."""
    R, T, d = x.shape
    J = np.linalg.inv(P0) + np.mean(
        [
            sum(w * s.fisher_information(x[r, 0]) for w, s in zip(weights[r, 0], sensors))
            for r in range(R)
        ],
        axis=0,
    )
    out = [J]
    for k in range(T - 1):
        Qi = np.linalg.inv(motion.noise_cov(dts[k]))
        D11 = np.zeros((d, d))
        EF = np.zeros((d, d))
        I = np.zeros((d, d))
        for r in range(R):
            F = motion.jacobian(x[r, k], dts[k])
            D11 += F.T @ Qi @ F / R
            EF += F / R
            I += (
                sum(
                    w * s.fisher_information(x[r, k + 1])
                    for w, s in zip(weights[r, k + 1], sensors)
                )
                / R
            )
        D12 = -EF.T @ Qi
        D22 = Qi + I
        J = D22 - D12.T @ np.linalg.inv(J + D11) @ D12
        out.append(J)
    return np.array(out)


def test_coordinated_turn_with_bearings_matches_loop_reference():
    rng = np.random.default_rng(5)
    motion = CoordinatedTurnRate(q=0.3, q_omega=0.02)
    R, T = 20, 12
    dts = rng.uniform(0.2, 1.0, size=T - 1)
    x = np.empty((R, T, 5))
    x[:, 0] = np.array([10.0, 0.0, 0.0, 2.0, 0.1]) + rng.normal(0, [1, 1, 0.2, 0.2, 0.05], (R, 5))
    for k in range(T - 1):
        x[:, k + 1] = motion.sample(x[:, k], dts[k], rng)
    mask = rng.random((R, T, 2)) < 0.7
    p0 = np.diag([1.0, 1.0, 0.2, 0.2, 0.01])
    J = posterior_information(motion, MICS, x, dts, p0, mask=mask)
    ref = reference_information(motion, MICS, x, dts, p0, mask.astype(float))
    np.testing.assert_allclose(J, ref, rtol=1e-9, atol=1e-9)
    # per trajectory: each equals the R = 1 bound along it
    Jr = posterior_information(motion, MICS, x, dts, p0, mask=mask, average=False)
    for r in (0, 7):
        np.testing.assert_allclose(
            Jr[r], posterior_information(motion, MICS, x[r], dts, p0, mask=mask[r]), rtol=1e-10
        )


def test_field_of_view_through_detection_probability():
    # a microphone looking away from the target (narrow fov) adds nothing
    blind = Bearing("blind", position=[0.0, 0.0], sigma=0.02, heading=np.pi, fov=0.5)
    x = cv_truth(3, 1.0)
    J = posterior_information(CV, [blind], x, 1.0, P0, use_detection_probability=True)
    J0 = posterior_information(CV, [], x, 1.0, P0)
    np.testing.assert_allclose(J, J0, atol=1e-12)
    # without the flag the sensor is assumed to report
    assert not np.allclose(posterior_information(CV, [blind], x, 1.0, P0), J0)


def test_deterministic_crlb_equals_noiseless_kalman_filter():
    T, dt = 15, 0.5
    x = cv_truth(T, dt, R=2)
    tag = PositionFix("tag", cov=np.diag([0.3, 0.6]))
    mask = np.ones((T, 1), bool)
    mask[3:8] = False
    motion = ConstantVelocity(ndim=2, q=0.2, noise="discrete")  # Q is never used
    B = deterministic_crlb(motion, [tag], x, dt, P0, mask=mask)
    assert B.shape == (2, T, 4, 4)
    F, H = motion.transition_matrix(dt), np.hstack([np.eye(2), np.zeros((2, 2))])
    P = P0.copy()
    for k in range(T):
        if k:
            P = F @ P @ F.T
        if mask[k, 0]:
            K = P @ H.T @ np.linalg.inv(H @ P @ H.T + tag.noise_cov())
            P = (np.eye(4) - K @ H) @ P
        np.testing.assert_allclose(B[:, k], np.broadcast_to(P, (2, 4, 4)), rtol=1e-9, atol=1e-12)
    assert deterministic_crlb(motion, [tag], x[0], dt, P0).shape == (T, 4, 4)


def test_deterministic_crlb_nonlinear_motion_per_trajectory():
    motion = CoordinatedTurnRate(q=0.3, q_omega=0.02)
    x = np.array([[10.0, 0.0, 0.0, 2.0, 0.1], [10.0, 0.0, 0.0, 2.0, -0.2]])
    traj = np.stack([x, motion.mean(x, 1.0), motion.mean(motion.mean(x, 1.0), 1.0)], axis=1)
    p0 = np.diag([1.0, 1.0, 0.2, 0.2, 0.01])
    B = deterministic_crlb(motion, MICS, traj, 1.0, p0)
    for r in range(2):
        J = np.linalg.inv(p0) + sum(s.fisher_information(traj[r, 0]) for s in MICS)
        for k in range(2):
            Fi = np.linalg.inv(motion.jacobian(traj[r, k], 1.0))
            J = Fi.T @ J @ Fi + sum(s.fisher_information(traj[r, k + 1]) for s in MICS)
        np.testing.assert_allclose(B[r, 2], np.linalg.inv(J), rtol=1e-8)


def test_singular_process_noise_is_named():
    """Prop. 1 needs Q^-1; a linear model takes the covariance form (test_crlb_covariance_form)."""
    with pytest.raises(ConfigError, match="noise_cov"):
        posterior_crlb(
            ConstantVelocity(noise="discrete"), MICS, cv_truth(3, 1.0), 1.0, P0, form="information"
        )


def test_precomputed_information_equals_the_per_step_calls():
    """``information``: the sensors' H^T R^-1 H computed once over all steps (reusable across
    masks and priors) gives the bound of the per-step calls; a wrong shape is named."""
    x = cv_truth(12, 1.0, R=3)
    mask = np.random.default_rng(5).random((12, 2)) < 0.7
    info = np.stack([s.fisher_information(x) for s in MICS], axis=2)  # (R, T, S, d, d)
    B = posterior_crlb(CV, MICS, x, 1.0, P0, mask=mask)
    Bi = posterior_crlb(CV, MICS, x, 1.0, P0, mask=mask, information=info)
    np.testing.assert_allclose(Bi, B, rtol=1e-12, atol=0)
    with pytest.raises(ShapeError, match="information"):
        posterior_crlb(CV, MICS, x, 1.0, P0, information=info[:, :, :1, :, :3])
