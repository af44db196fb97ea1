"""Ellipse-contour likelihood over Canny frames (Zhai 2007, Eqs. 49-52) and its EKF form."""

import cv2
import numpy as np
import pytest

from fusetrack.core import Gaussian, Measurement
from fusetrack.core.errors import ShapeError
from fusetrack.filters.sp_pekf import SPPEKFBank
from fusetrack.motion import ConstantVelocity
from fusetrack.perception.visual_edges import EllipseEdgeSensor, edge_map, ellipse_rays


def test_boundary_points_lie_on_the_ellipse_in_every_quadrant():
    a, b = 14.0, 9.0
    d, r = ellipse_rays(a, b, 24)
    p = r[:, None] * d
    np.testing.assert_allclose((p[:, 0] / a) ** 2 + (p[:, 1] / b) ** 2, 1.0)
    # the thesis's Eq. 49, c = sqrt(a^2 b^2 / (b^2 + a^2 tan^2)), is positive for every ray:
    th = 2 * np.pi * np.arange(24) / 24
    c_printed = np.sqrt(a * a * b * b / (b * b + a * a * np.tan(th) ** 2))
    left = np.cos(th) < -1e-9
    assert np.all(p[left, 0] < 0) and np.all(c_printed[left] > 0)
    np.testing.assert_allclose(np.abs(p[:, 0]), c_printed, atol=1e-9)


def _outline(h, w, centre, axes):
    img = np.zeros((h, w), np.uint8)
    cv2.ellipse(
        img, (int(centre[0]), int(centre[1])), (int(axes[0]), int(axes[1])), 0, 0, 360, 1, 1
    )
    return img.astype(float)


def test_single_edge_pixel_gives_the_hand_computed_likelihood():
    s = EllipseEdgeSensor("e", 50, 60, axes=(10.0, 10.0), n_rays=4, sigma=3.0, search=5)
    edges = np.zeros((50, 60))
    edges[25, 30 + 12] = 1.0  # on ray 0 (pointing +x), 2 px beyond the boundary at radius 10
    ll = s.log_likelihood(s.measurement(edges), np.array([30.0, 25.0, 0, 0]))
    # the cross-dilated pixel covers columns 41-43 of the ray: samples s = 1, 2, 3
    g = sum(np.exp(-0.5 * (d / 3) ** 2) / (2 * np.pi * 9) for d in (1.0, 2.0, 3.0))
    assert float(ll) == pytest.approx(np.log1p(g / s.clutter_floor))
    assert float(s.log_likelihood(s.measurement(np.zeros((50, 60))), np.zeros(4))) == 0.0


def test_likelihood_peaks_at_the_drawn_ellipse():
    s = EllipseEdgeSensor("e", 80, 100, axes=(14.0, 18.0))
    z = s.measurement(_outline(80, 100, (47, 38), (14, 18)))
    xs, ys = np.meshgrid(np.arange(35, 60), np.arange(28, 50))
    states = np.stack([xs.ravel(), ys.ravel(), 0 * xs.ravel(), 0 * xs.ravel()], -1).astype(float)
    best = states[np.argmax(s.log_likelihood(z, states))]
    np.testing.assert_allclose(best[:2], [47, 38], atol=1.0)


def test_centre_pseudo_measurement_recovers_the_shift():
    s = EllipseEdgeSensor("e", 80, 100, axes=(14.0, 18.0))
    z = s.measurement(_outline(80, 100, (53, 36), (14, 18)))
    np.testing.assert_allclose(s.residual(z, np.array([50.0, 38.0])), [3, -2], atol=0.8)
    assert np.all(s.residual(s.measurement(np.zeros((80, 100))), np.array([50.0, 38.0])) == 0)
    np.testing.assert_allclose(s.noise_cov(), 2 * 9 / 24 * np.eye(2), atol=1e-12)


def test_an_ekf_bank_follows_the_contour():
    s = EllipseEdgeSensor("e", 80, 100, axes=(14.0, 18.0))
    bank = SPPEKFBank(ConstantVelocity(q=1.0), [s], 10)
    rng = np.random.default_rng(0)
    st = bank.initialize(Gaussian(np.array([40.0, 40.0, 0, 0]), np.diag([4, 4, 1, 1.0])), rng)
    for k in range(1, 6):
        z = s.measurement(_outline(80, 100, (40 + 2 * k, 40), (14, 18)))
        st = bank.update(bank.predict(st, 1.0, rng), [Measurement(k, "e", z)])
    np.testing.assert_allclose(st.mean[:2], [50, 40], atol=1.5)


def test_edge_map_and_shapes():
    img = np.zeros((40, 50, 3), np.uint8)
    img[10:30, 15:35] = 255
    e = edge_map(img)
    assert e.shape == (40, 50) and set(np.unique(e)) == {0.0, 1.0}
    s = EllipseEdgeSensor("e", 40, 50, axes=(5.0, 5.0))
    with pytest.raises(ShapeError, match=r"edges\.shape"):
        s.measurement(np.zeros((10, 10)))
    with pytest.raises(ShapeError, match=r"z\.shape"):
        s.log_likelihood(np.zeros((2, s.measurement(e).size)), np.zeros((3, 4)))


def test_simulated_outline_is_seen_where_it_was_drawn():
    s = EllipseEdgeSensor("e", 60, 80, axes=(10.0, 12.0))
    z = s.simulate(np.array([37.4, 29.6, 0, 0]), np.random.default_rng(0))
    xs, ys = np.meshgrid(np.arange(25, 50), np.arange(18, 42))
    states = np.stack([xs.ravel(), ys.ravel()], -1).astype(float)
    np.testing.assert_allclose(
        states[np.argmax(s.log_likelihood(z, states))], [37.4, 29.6], atol=1.5
    )
    np.testing.assert_allclose(
        s.fisher_information(np.zeros(4))[:2, :2], np.eye(2) / 0.75, atol=1e-12
    )
    np.testing.assert_array_equal(
        s.detection_probability(np.array([[5.0, 5.0], [-3.0, 5.0]])), [1, 0]
    )


def test_an_ekf_reads_the_frame_as_the_centre_pseudo_measurement():
    """One EKF update with the edge frame moves the mean exactly as an update with the position
    fix ``c + residual(z, c)`` and covariance ``noise_cov`` would (the sensor is linear in the
    centre); between two centres the residual is their difference (UKF sigma points)."""
    from fusetrack.core.measurement import Measurement
    from fusetrack.filters import ExtendedKalmanFilter
    from fusetrack.sensors import PositionFix

    s = EllipseEdgeSensor("e", 80, 100, axes=(14.0, 18.0))
    z = s.measurement(_outline(80, 100, (53, 36), (14, 18)))
    prior = Gaussian(np.array([50.0, 38.0, 0.0, 0.0]), np.diag([4.0, 4.0, 1.0, 1.0]))
    ekf = ExtendedKalmanFilter(ConstantVelocity(q=1.0), [s])
    post = ekf.update(prior, [Measurement(0.0, "e", z)])
    fix = PositionFix("e", cov=s.noise_cov())
    c = prior.mean[:2]
    ref = ExtendedKalmanFilter(ConstantVelocity(q=1.0), [fix]).update(
        prior, [Measurement(0.0, "e", c + s.residual(z, c))]
    )
    np.testing.assert_allclose(post.mean, ref.mean, atol=1e-12)
    np.testing.assert_allclose(post.cov, ref.cov, atol=1e-12)
    assert abs(post.mean[0] - 53) < 1.0 and abs(post.mean[1] - 36) < 1.0
    np.testing.assert_allclose(s.residual(np.array([[3.0, 4.0]]), np.array([1.0, 1.0])), [[2, 3]])
