"""Nott 2009 joint tracker: stacked vs sequential updates, KF steady state, asynchronous reports."""

import numpy as np
import pytest
from scipy.linalg import solve_discrete_are

from fusetrack.core import Gaussian, Measurement
from fusetrack.experiments.nott2009.scenario import SimConfig, run_trackers, simulate_truth
from fusetrack.filters import ExtendedKalmanFilter, KalmanFilter, run_filter
from fusetrack.motion import ConstantVelocity, WalkingPerson
from fusetrack.sensors import HomographyCamera, PositionFix, StackedSensor
from fusetrack.sensors.camera_geometry import default_camera


def _prior():
    return Gaussian(np.array([3.0, 5.0, 1.7, 0.5, 0.3, 0.2]), np.diag([1, 1, 0.01, 0.04, 1, 1.0]))


def test_walking_person_matrices():
    m = WalkingPerson(q_a=0.5, q_h=1e-3, q_w=0.05, step=0.2)
    q = m.noise_cov(0.2)
    assert q[0, 0] == pytest.approx(0.25 * 0.2**4 / 4) and q[0, 4] == pytest.approx(
        0.25 * 0.2**3 / 2
    )
    assert q[2, 2] == pytest.approx(1e-6) and q[3, 3] == pytest.approx(0.0025)
    assert np.allclose(m.transition_matrix(0.2)[[0, 1], [4, 5]], 0.2)


def test_stacked_update_equals_sequential_for_linear_sensors_in_any_order():
    tag = PositionFix("tag", cov=np.diag([0.36, 0.16]), position_index=(0, 1))
    vel = PositionFix("vel", cov=np.diag([0.05, 0.08]), position_index=(4, 5))
    both = StackedSensor("both", [tag, vel])
    kf = KalmanFilter(WalkingPerson(), {"tag": tag, "vel": vel, "both": both})
    b = kf.predict(_prior(), 0.2)
    z, v = np.array([3.1, 5.2]), np.array([0.4, 0.1])
    seq = kf.update(b, [Measurement(0.2, "tag", z), Measurement(0.2, "vel", v)])
    rev = kf.update(b, [Measurement(0.2, "vel", v), Measurement(0.2, "tag", z)])
    stk = kf.update(b, [Measurement(0.2, "both", np.concatenate([z, v]))])
    for other in (rev, stk):
        assert np.allclose(seq.mean, other.mean, atol=1e-12) and np.allclose(
            seq.cov, other.cov, atol=1e-12
        )


def test_stacked_camera_update_close_to_sequential():
    """With the nonlinear camera the two differ only by the relinearisation after the tag update."""
    cam = HomographyCamera("camera", camera_matrix=default_camera().P, variant="corners")
    tag = PositionFix("tag", cov=np.diag([0.36, 0.16]), position_index=(0, 1))
    ekf = ExtendedKalmanFilter(
        WalkingPerson(), {"tag": tag, "camera": cam, "both": StackedSensor("both", [tag, cam])}
    )
    b = ekf.predict(_prior(), 0.2)
    truth = np.array([3.05, 5.1, 1.75, 0.52, 0.3, 0.2])
    z, y = truth[:2] + 0.1, cam.predict(truth) + 0.5
    seq = ekf.update(b, [Measurement(0.2, "tag", z), Measurement(0.2, "camera", y)])
    stk = ekf.update(b, [Measurement(0.2, "both", np.concatenate([z, y]))])
    assert np.abs(seq.mean[:2] - stk.mean[:2]).max() < 0.02


def test_kalman_filter_reaches_the_closed_form_steady_state_gain():
    cv = ConstantVelocity(ndim=1, q=0.3, noise="discrete")
    r = 0.25
    kf = KalmanFilter(cv, [PositionFix("z", cov=[[r]])])
    b = Gaussian(np.zeros(2), np.eye(2) * 10)
    for k in range(200):
        b = kf.update(kf.predict(b, 0.5), [Measurement(k * 0.5, "z", [0.0])])
    F, Q, H = cv.transition_matrix(0.5), cv.noise_cov(0.5), np.array([[1.0, 0.0]])
    p_pred = solve_discrete_are(F.T, H.T, Q, np.array([[r]]))
    gain = p_pred @ H.T / (H @ p_pred @ H.T + r)
    p_post = (np.eye(2) - gain @ H) @ p_pred
    assert np.allclose(b.cov, p_post, rtol=1e-8)


def test_event_driven_with_frame_timestamps_equals_the_frame_grid():
    rng = np.random.default_rng(3)
    grid = SimConfig(dynamics="cv", n_steps=30, occ_len=5)
    event = SimConfig(dynamics="cv", n_steps=30, occ_len=5, mode="event", rfid_rate=5.0)
    truth = simulate_truth(grid, rng)
    a = run_trackers(grid, truth, np.random.default_rng(7))
    b = run_trackers(event, truth, np.random.default_rng(7))
    assert np.allclose(a["est"]["J"], b["est"]["J"], atol=1e-9)


def test_missing_tag_reports_are_skipped_not_zero_filled():
    tag = PositionFix("tag", cov=np.diag([0.36, 0.16]), position_index=(0, 1))
    kf = KalmanFilter(WalkingPerson(), {"tag": tag})
    ms = [
        Measurement(0.2, "tag", [3.1, 5.1]),
        Measurement(0.4, "tag", [np.nan, np.nan]),
        Measurement(0.6, "tag", [3.3, 5.2]),
    ]
    with_gap = run_filter(kf, _prior(), ms, t0=0.0)
    without = run_filter(kf, _prior(), [ms[0], ms[2]], times=[0.4], t0=0.0)
    assert np.allclose(with_gap.means[-1], without.means[-1])
    assert kf.stats.skipped_measurements == 1


def test_joint_tracker_beats_the_tag_and_survives_a_long_occlusion():
    """A broken filter (wrong Jacobian, wrong update order, zero-filled gaps) fails these bounds."""
    errs = {m: [] for m in ("B1", "B4", "J")}
    cfg = SimConfig(dynamics="ca", occ_len=15)
    for seed in range(6):
        rng = np.random.default_rng(seed)
        truth = simulate_truth(cfg, rng)
        out = run_trackers(cfg, truth, rng)
        occ = out["occluded"]
        for m in errs:
            errs[m].append(np.linalg.norm(out["est"][m] - truth[:, :2], axis=1))
    e = {m: np.array(v) for m, v in errs.items()}
    visible = ~cfg.occluded()
    visible[:5] = False
    assert e["J"][:, visible].mean() < 0.06 < 0.3 < e["B1"][:, visible].mean()
    assert e["J"][:, occ].mean() < 0.35
    assert e["J"][:, occ][:, -1].mean() < e["B4"][:, occ][:, -1].mean()


def test_constant_acceleration_person_model():
    from fusetrack.motion import WalkingPersonCA

    m = WalkingPersonCA(q_j=0.1, step=0.2)
    x = np.array([1.0, 2.0, 1.75, 0.5, 1.0, 0.5, 0.2, -0.4])
    assert np.allclose(m.mean(x, 0.5)[[0, 1, 4, 5, 6, 7]], [1.525, 2.2, 1.1, 0.3, 0.2, -0.4])
    q = m.noise_cov(0.2)
    assert (
        np.allclose(q, q.T)
        and q[6, 6] == pytest.approx(0.01)
        and q[0, 6] == pytest.approx(0.01 * 0.02)
    )
