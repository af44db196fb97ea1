"""The best possible on Kushwaha 2010's Ch. V camera runs: the point-projection information by
hand, the PCRB against a Kalman filter, the Gaussian mean error, and the claim failing when a
tracker is below the bound."""

import inspect

import numpy as np
import pandas as pd
import pytest

from fusetrack.core import Gaussian, Measurement, ShapeError
from fusetrack.evaluation import ClaimKinds, expected_norm
from fusetrack.experiments.kushwaha2010 import best_possible as bp
from fusetrack.filters import KalmanFilter, SmartCameraTracker
from fusetrack.sensors import EllipsoidCamera, LinearGaussianSensor, PinholeCamera
from fusetrack.world import render_frames

F, D = 200.0, 5.0  # focal (px) and distance of both cameras to the origin (m)


def camera(name, centre, right, down, forward):
    K = np.array([[F, 0.0, 80.0], [0.0, F, 60.0], [0.0, 0.0, 1.0]])
    R = np.array([right, down, forward], dtype=float)
    return EllipsoidCamera(name, PinholeCamera(K, R, np.array(centre, float), 160, 120))


# A at (-D, 0, 0) looking along +x, B at (0, -D, 0) looking along +y (both right-handed)
CAM_A = camera("A", (-D, 0, 0), (0, -1, 0), (0, 0, -1), (1, 0, 0))
CAM_B = camera("B", (0, -D, 0), (1, 0, 0), (0, 0, -1), (0, 1, 0))


def test_point_projection_information_by_hand():
    """On a camera's optical axis at depth D the projection moves f / D px per metre across the
    axis and not at all along it: information (f / (D sigma))^2 on the two lateral axes."""
    sigma = 0.5
    a, b = bp.projections([CAM_A, CAM_B], sigma)
    x = np.zeros(6)
    k = (F / (D * sigma)) ** 2
    np.testing.assert_allclose(a.predict(x), [80.0, 60.0])
    np.testing.assert_allclose(a.fisher_information(x)[:3, :3], k * np.diag([0, 1, 1]), atol=1e-9)
    both = a.fisher_information(x) + b.fisher_information(x)
    expected = np.zeros((6, 6))
    expected[:3, :3] = k * np.diag([1.0, 1.0, 2.0])  # z seen by both, x by B, y by A
    np.testing.assert_allclose(both, expected, atol=1e-9)


def test_jacobian_matches_finite_differences_off_axis():
    cam = bp.projections([CAM_B])[0]
    x = np.array([0.7, 1.3, -0.4, 0.2, 0.1, 0.0])
    H = cam.jacobian(x)
    h = 1e-6
    num = np.stack(
        [(cam.predict(x + h * e) - cam.predict(x - h * e)) / (2 * h) for e in np.eye(6)], axis=-1
    )
    np.testing.assert_allclose(H, num, rtol=1e-6, atol=1e-6)
    assert H.shape == (2, 6) and np.all(H[:, 3:] == 0)


def kalman_position_covariances(point, visible, sigma):
    """The trackers' constant-velocity Kalman filter with the cameras linearised at the static
    ``point`` (exact: the truth never moves), started from the manual initialisation's prior and
    updated from step 1 by the visible cameras."""
    cams = bp.projections([CAM_A, CAM_B], sigma)
    state = np.concatenate([point, np.zeros(3)])
    sensors = {
        c.sensor_id: LinearGaussianSensor(c.sensor_id, c.jacobian(state), c.noise_cov())
        for c in cams
    }
    kf = KalmanFilter(bp.trackers_motion(), sensors)
    belief = Gaussian(state, bp.PRIOR_SD**2 * np.eye(6))
    out = [belief.cov[:3, :3]]
    for t in range(1, len(visible)):
        belief = kf.predict(belief, 1.0)
        zs = [
            Measurement(float(t), c.sensor_id, c.predict(state))
            for c, seen in zip(cams, visible[t])
            if seen
        ]
        if zs:
            belief = kf.update(belief, zs)
        out.append(belief.cov[:3, :3])
    return np.array(out)


def test_bound_equals_the_kalman_filter_on_a_static_target():
    rng = np.random.default_rng(4)
    T = 25
    visible = rng.random((T, 2)) < 0.7
    visible[8:12] = [True, False]  # a one-camera gap: depth along A's axis from the motion only
    point = np.array([0.3, -0.2, 0.5])
    B = bp.position_bound([CAM_A, CAM_B], np.tile(point, (T, 1)), visible, sigma=0.5)
    np.testing.assert_allclose(B, kalman_position_covariances(point, visible, 0.5), atol=1e-12)
    # step 0 carries no information (the trackers start from the prior there)
    np.testing.assert_allclose(B[0], bp.PRIOR_SD**2 * np.eye(3), atol=1e-15)
    # in the gap the depth along A's axis (x) grows, the lateral axes stay pinned
    assert B[11, 0, 0] > 3 * B[7, 0, 0] and B[11, 1, 1] < 2 * B[7, 1, 1]


def test_unseen_camera_carries_no_information():
    rng = np.random.default_rng(1)
    x = np.cumsum(rng.normal(0, 0.1, (12, 3)), axis=0)
    hidden_b = np.column_stack([np.ones(12, bool), np.zeros(12, bool)])
    with_hidden = bp.position_bound([CAM_A, CAM_B], x, hidden_b)
    alone = bp.position_bound([CAM_A], x, np.ones((12, 1), bool))
    np.testing.assert_allclose(with_hidden, alone, atol=1e-15)
    with pytest.raises(ShapeError, match=r"visible\.shape"):
        bp.position_bound([CAM_A, CAM_B], x, np.ones((12, 3), bool))


def test_prior_motion_and_visibility_rule_are_the_trackers():
    tracker = SmartCameraTracker(None)  # the network is not read by the initialisation
    kin = tracker.initial_belief(np.zeros(3), np.zeros(3), np.array([0, 0, 0, 1.0])).kinematics
    np.testing.assert_allclose(kin.cov, bp.PRIOR_SD**2 * np.eye(6))
    np.testing.assert_allclose(
        tracker.kf.motion.noise_cov(1.0), bp.trackers_motion().noise_cov(1.0)
    )
    assert inspect.signature(render_frames).parameters["min_pixels"].default == bp.MIN_PIXELS


def test_expected_norm_of_gaussians():
    s = 0.3
    np.testing.assert_allclose(expected_norm(s**2 * np.eye(3)), s * np.sqrt(8 / np.pi), rtol=1e-9)
    np.testing.assert_allclose(
        expected_norm(np.diag([s**2, 0, 0])), s * np.sqrt(2 / np.pi), rtol=1e-9
    )
    # the 3-D integral with a zero third axis against the 2-D closed form (elliptic integral)
    C = np.array([[0.04, 0.01], [0.01, 0.01]])
    C3 = np.zeros((3, 3))
    C3[:2, :2] = C
    np.testing.assert_allclose(expected_norm(C3), expected_norm(C), rtol=1e-8)
    assert expected_norm(np.zeros((3, 3))) == 0.0


def test_run_bound_trivial_estimator_and_rows():
    x = np.array([[0.0, 0, 0], [0.1, 0, 0], [0.2, 0.1, 0], [0.3, 0.3, 0]])
    rows = [{"tracker": "T0", "t": t, "err3d": 0.1} for t in (1, 2, 3)]
    out = bp.with_bound(rows, [CAM_A, CAM_B], x, [0.1, 0, 0], np.ones((4, 2), bool))
    np.testing.assert_allclose([r["trivial_err"] for r in out], [0.0, 0.1, 0.3])
    assert all(0 < r["pcrb_mean"] < np.sqrt(r["pcrb_mse"]) for r in out)


def frame(errors, bound_mse):
    """Rows of two runs x three steps per tracker, the bound's trace ``bound_mse`` everywhere."""
    rows = []
    for name, err in errors.items():
        for run in (0, 1):
            for t in (1, 2, 3):
                e = err * (1 + 0.1 * run)
                rows.append({"tracker": name, "run": run, "t": t, "err3d": e})
    df = pd.DataFrame(rows)
    mean = float(bp.expected_norm(bound_mse / 3 * np.eye(3)))
    return df.assign(pcrb_mse=bound_mse, pcrb_mean=mean, trivial_err=1.0)


def test_claim_fails_when_a_tracker_is_below_the_bound():
    kinds = ClaimKinds({"BP_*": "diagnostic"})
    above = bp.bound_table(frame({"T0": 0.2, "T2": 0.3}, 0.01), ["T2", "T0"])
    assert list(above.index) == ["T2", "T0"]
    np.testing.assert_allclose(above.loc["T0", "PCRB RMS (m)"], 0.1)
    assert bp.above_claim(kinds, "BP_x", above, "test").holds
    below = bp.bound_table(frame({"T0": 0.2, "T2": 0.05}, 0.01), ["T0", "T2"])
    claim = bp.above_claim(kinds, "BP_x", below, "test")
    assert not claim.holds and claim.kind == "diagnostic"
    assert claim.ours["mean / bound"] < 1
