"""lee2009-detection-fusion's best possible: ground fixes through a homography, one frame's
information fusion and the posterior mean (Kalman filter) from the known start, against
hand-computed cases, and the filter attaining its own bound on a linear-Gaussian model."""

import math

import numpy as np
import pytest

from fusetrack.core import ConfigError
from fusetrack.experiments.lee2009 import detection_fusion as df
from fusetrack.experiments.lee2009 import fusion_bound as fb
from fusetrack.filters import to_image
from fusetrack.sensors import apply_homography


def test_homography_jacobian_matches_finite_differences():
    eps = 1e-5
    for h in df.homographies():
        uv = to_image(h, np.array([6.0, 5.0]))
        num = np.column_stack(
            [
                (apply_homography(h, uv + eps * e) - apply_homography(h, uv - eps * e)) / (2 * eps)
                for e in np.eye(2)
            ]
        )
        np.testing.assert_allclose(fb.homography_jacobian(h, uv), num, rtol=1e-7)


def test_ground_detection_of_an_affine_map_by_hand():
    """``g = A l + b``: the Jacobian is ``A``, the fix's covariance ``s^2 A A^T``."""
    h = np.array([[0.5, 0.0, 1.0], [0.0, 0.25, -2.0], [0.0, 0.0, 1.0]])
    g, r = fb.ground_detection(h, np.array([4.0, 8.0]), pixel_sigma=2.0)
    np.testing.assert_allclose(g, [3.0, 0.0])
    np.testing.assert_allclose(r, np.diag([4 * 0.25, 4 * 0.0625]))
    with pytest.raises(ConfigError, match="pixel_sigma"):
        fb.ground_detection(h, np.zeros(2), 0.0)


def test_frame_fusion_by_hand():
    """Fixes (0, 0) with I and (3, 0) with 2 I: P = (1 + 1/2)^-1 I = 2/3 I, mean 2/3 (3/2, 0)."""
    mean, cov = fb.frame_fusion(
        np.array([[0.0, 0.0], [3.0, 0.0]]), np.array([np.eye(2), 2 * np.eye(2)])
    )
    np.testing.assert_allclose(mean, [1.0, 0.0])
    np.testing.assert_allclose(cov, np.eye(2) * 2 / 3)
    mean, cov = fb.frame_fusion(np.zeros((0, 2)), np.zeros((0, 2, 2)))
    assert np.isnan(mean).all() and np.isnan(cov).all()


def test_posterior_track_by_hand():
    """Frame 0 with one fix ``g`` (``r^2 I``): mean ``m + q^2 / (q^2 + r^2) (g - m)``, ``m =
    start + drift``; covariance ``q^2 r^2 / (q^2 + r^2) I``. Frame 1 without a fix: the mean moves
    by the drift, the covariance grows by ``q^2``."""
    q, r = 0.1, 0.2
    start, drift = np.array([1.0, 2.0]), np.array([0.5, -0.5])
    g = np.array([1.8, 1.2])
    frames = [(g[None], r**2 * np.eye(2)[None]), (np.zeros((0, 2)), np.zeros((0, 2, 2)))]
    means, covs = fb.posterior_track(frames, start, drift, q)
    m = start + drift
    k = q**2 / (q**2 + r**2)
    np.testing.assert_allclose(means[0], m + k * (g - m))
    np.testing.assert_allclose(covs[0], k * r**2 * np.eye(2))
    np.testing.assert_allclose(means[1], means[0] + drift)
    np.testing.assert_allclose(covs[1], (k * r**2 + q**2) * np.eye(2))
    with pytest.raises(ConfigError, match="step_sigma"):
        fb.posterior_track(frames, start, drift, 0.0)


def test_posterior_mean_attains_its_bound_on_a_linear_gaussian_model():
    """Fixes Gaussian on the ground (no homography): the Kalman filter's mean Euclidean error is
    E|N(0, P_n)| (``mean_error_bound``) and its mean square error trace P_n; a filter that
    ignored the motion (one frame) is worse. 120 runs x 60 frames."""
    rng = np.random.default_rng(3)
    q, start, drift = 0.01, np.zeros(2), np.array([0.05, 0.03])
    r = [np.diag([0.04**2, 0.03**2]), np.array([[0.0016, 0.0005], [0.0005, 0.0012]])]
    errs, sq, bound, trace, one = [], [], [], [], []
    for _ in range(120):
        x, frames, truth = start.copy(), [], []
        for _ in range(60):
            x = x + drift + q * rng.standard_normal(2)
            keep = [rj for rj in r if rng.random() < 0.8]
            g = np.array([rng.multivariate_normal(x, rj) for rj in keep]).reshape(-1, 2)
            frames.append((g, np.array(keep).reshape(-1, 2, 2)))
            truth.append(x)
        means, covs = fb.posterior_track(frames, start, drift, q)
        e = means - np.array(truth)
        errs.append(np.hypot(*e.T).mean())
        sq.append((e**2).sum(1).mean())
        bound.append(fb.mean_error_bound(covs).mean())
        trace.append(np.trace(covs, axis1=1, axis2=2).mean())
        one += [
            np.hypot(*(fb.frame_fusion(g, rr)[0] - t))
            for (g, rr), t in zip(frames, truth)
            if len(g)
        ]
    for got, want in ((errs, bound), (sq, trace)):
        se = np.std(got, ddof=1) / math.sqrt(len(got))
        assert abs(np.mean(got) - np.mean(want)) <= 3 * se
    assert np.mean(one) > 1.5 * np.mean(bound)


def test_block_se_by_hand():
    """Two blocks of means 0 and 1: std 0.7071 over sqrt(2) = 0.5; one block: NaN."""
    assert fb.block_se([0.0] * 10 + [1.0] * 10, block=10) == pytest.approx(0.5)
    assert math.isnan(fb.block_se(np.zeros(15), block=10))
    v = np.random.default_rng(0).standard_normal(20_000)
    assert fb.block_se(v, block=10) == pytest.approx(1 / math.sqrt(20_000), rel=0.1)


def test_sequence_rows_carry_the_bound():
    """One sequence: each method's mean error is above the posterior mean's bound on its frames;
    the oracle rows are there and their errors are near their expected values."""
    rows = {r["method"]: r for r in df.run_sequence({"pixel_sigma": 2.0}, 0)}
    assert set(rows) == {*df.SEQUENCE_METHODS, df.POSTERIOR, df.ONE_FRAME}
    for m in df.SEQUENCE_METHODS:
        assert rows[m]["position_error"] > 1.3 * rows[m]["best_position_error"]
    post, one = rows[df.POSTERIOR], rows[df.ONE_FRAME]
    assert (
        abs(post["position_error"] - post["best_position_error"])
        <= 4 * post["best_position_error_gap_se"]
    )
    assert abs(one["position_error"] - one["one_frame_bound"]) <= 4 * one["one_frame_bound_gap_se"]
    assert post["fused_local_rate"] == 1.0 and post["false_accept_rate"] == 0.0
