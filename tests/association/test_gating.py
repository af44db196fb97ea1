"""Gates and scan scores against hand-computed Mahalanobis distances and Gaussian densities."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fusetrack.association import (
    gate_probability,
    gate_threshold,
    mahalanobis_distance,
    mahalanobis_gate,
    predicted_measurement,
    scan_likelihoods,
)
from fusetrack.core import (
    ConfigError,
    Gaussian,
    Measurement,
    MeasurementError,
    Particles,
    ShapeError,
    UnknownSensorError,
)
from fusetrack.filters import KalmanFilter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import Bearing, LinearGaussianSensor

H = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]]
SENSOR = LinearGaussianSensor("pos", H=H, R=np.eye(2))
# position covariance [[3, 1], [1, 5]] so that S = [[4, 1], [1, 6]]
P = np.array([[3.0, 1.0, 0.0, 0.0], [1.0, 5.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0, 0, 0, 1.0]])
TRACK = Gaussian(np.array([1.0, 2.0, 0.5, -0.5]), P)
S = np.array([[4.0, 1.0], [1.0, 6.0]])  # det 23, S^-1 = [[6, -1], [-1, 4]] / 23


def test_predicted_measurement_is_h_of_mean_and_h_p_ht_plus_r():
    z_pred, s = predicted_measurement(TRACK, SENSOR)
    np.testing.assert_allclose(z_pred, [1.0, 2.0])
    np.testing.assert_allclose(s, S)


def test_mahalanobis_distance_by_hand():
    # y = (2, 3): y^T S^-1 y = (6*4 - 2*2*3 + 4*9) / 23 = 48 / 23
    assert mahalanobis_distance(TRACK, SENSOR, [3.0, 5.0]) == pytest.approx(48 / 23, rel=1e-12)


def test_measurement_covariance_replaces_r_in_the_gate():
    z = Measurement(0.0, "pos", [3.0, 5.0], covariance=np.diag([2.0, 3.0]))
    # S = [[5, 1], [1, 8]], det 39: (8*4 - 2*2*3 + 5*9) / 39 = 65 / 39
    assert mahalanobis_distance(TRACK, SENSOR, z) == pytest.approx(65 / 39, rel=1e-12)


def test_gate_threshold_is_the_chi2_quantile():
    # with 2 degrees of freedom chi2.cdf(g) = 1 - exp(-g / 2): g = -2 log(1 - P_G)
    assert gate_threshold(0.99, 2) == pytest.approx(-2 * math.log(0.01), rel=1e-10)
    assert gate_probability(-2 * math.log(0.01), 2) == pytest.approx(0.99, rel=1e-10)
    assert gate_threshold(1.0, 2) == math.inf
    assert gate_threshold(0.95, 1) == pytest.approx(1.959963984540054**2, rel=1e-10)  # z_0.975^2


@pytest.mark.parametrize(("d2", "inside"), [(9.0, True), (9.5, False)])
def test_gate_boundary(d2, inside):
    # scale the innovation (2, 3) so that its squared distance is d2; the 0.99 gate is 9.21
    y = np.array([2.0, 3.0]) * math.sqrt(d2 / (48 / 23))
    z = np.array([1.0, 2.0]) + y
    assert mahalanobis_distance(TRACK, SENSOR, z) == pytest.approx(d2, rel=1e-12)
    assert mahalanobis_gate(TRACK, SENSOR, z, probability=0.99) is inside


def test_angle_residual_is_wrapped_in_the_gate():
    bearing = Bearing("doa", position=[0.0, 0.0], sigma=0.01)
    track = Gaussian(np.array([-10.0, 0.1, 0.0, 0.0]), np.diag([0.01, 0.01, 1.0, 1.0]))
    z_pred = float(bearing.predict(track.mean)[0])  # about pi - 0.01
    assert z_pred > 3.13
    z = [z_pred + 0.005 - 2 * math.pi]  # the same direction, written near -pi
    assert mahalanobis_distance(track, bearing, z) < 1.0
    assert mahalanobis_gate(track, bearing, z)


def test_particles_are_gated_by_their_moments():
    rng = np.random.default_rng(0)
    cloud = Particles.from_gaussian(TRACK, 4000, rng)
    d2 = mahalanobis_distance(cloud, SENSOR, [3.0, 5.0])
    _, s = predicted_measurement(cloud, SENSOR)
    y = np.array([3.0, 5.0]) - cloud.mean[:2]
    assert d2 == pytest.approx(float(y @ np.linalg.solve(s, y)), rel=1e-12)


@pytest.mark.parametrize("bad", [0.0, -0.1, 1.5, float("nan"), "x"])
def test_gate_probability_outside_0_1_is_a_config_error(bad):
    with pytest.raises(ConfigError, match="gate probability"):
        mahalanobis_gate(TRACK, SENSOR, [1.0, 2.0], probability=bad)


def test_batched_belief_and_wrong_size_measurement_are_errors():
    batched = Gaussian(np.zeros((3, 4)), np.broadcast_to(np.eye(4), (3, 4, 4)))
    with pytest.raises(ShapeError, match="no batch axes"):
        mahalanobis_distance(batched, SENSOR, [0.0, 0.0])
    with pytest.raises(MeasurementError, match=r"z\.shape"):
        mahalanobis_distance(TRACK, SENSOR, [0.0, 0.0, 0.0])


# -- scan_likelihoods -----------------------------------------------------------------------


def _kf() -> KalmanFilter:
    return KalmanFilter(ConstantVelocity(ndim=2, q=0.1), [SENSOR])


def _log_gauss(y, s):
    return -0.5 * (
        y @ np.linalg.solve(s, y) + math.log(np.linalg.det(s)) + 2 * math.log(2 * math.pi)
    )


OTHER = Gaussian(np.array([20.0, 20.0, 0.0, 0.0]), np.eye(4))
SCAN = [
    Measurement(1.0, "pos", [3.0, 5.0]),  # near TRACK only
    Measurement(1.0, "pos", [20.5, 19.0]),  # near OTHER only
    Measurement(1.0, "pos", [1.5, 2.5]),  # near TRACK only
    Measurement(1.0, "pos", [np.nan, np.nan]),  # saw nothing
]


def test_scan_likelihoods_with_a_kalman_filter_are_the_innovation_densities():
    scores = scan_likelihoods(
        [7, 9], [TRACK, OTHER], SCAN, [SENSOR], _kf(), p_detect=0.9, clutter_density=1e-3
    )
    assert scores.track_ids == (7, 9)
    expected = np.full((2, 4), -np.inf)
    expected[0, 0] = math.log(0.9) + _log_gauss(np.array([2.0, 3.0]), S)
    expected[0, 2] = math.log(0.9) + _log_gauss(np.array([0.5, 0.5]), S)
    expected[1, 1] = math.log(0.9) + _log_gauss(np.array([0.5, -1.0]), 2 * np.eye(2))
    np.testing.assert_allclose(scores.log_likelihood, expected, rtol=1e-12)
    np.testing.assert_allclose(scores.log_missed, [math.log(1 - 0.9 * 0.99)] * 2, rtol=1e-12)
    np.testing.assert_allclose(scores.log_clutter, [math.log(1e-3)] * 4)


class _UpdateOnly:
    """A filter without update_with_likelihood: the gate's Gaussian density is used."""

    def __init__(self, inner):
        self.inner = inner

    def predict(self, belief, dt, rng=None):
        return self.inner.predict(belief, dt, rng)

    def update(self, belief, measurements, rng=None):
        return self.inner.update(belief, measurements, rng)


def test_filter_without_likelihood_gets_the_gaussian_innovation_density():
    kf = _kf()
    with_ll, posts = scan_likelihoods(
        [7, 9], [TRACK, OTHER], SCAN, [SENSOR], kf, 0.9, 1e-3, keep_posteriors=True
    )
    plain, plain_posts = scan_likelihoods(
        [7, 9], [TRACK, OTHER], SCAN, [SENSOR], _UpdateOnly(kf), 0.9, 1e-3, keep_posteriors=True
    )
    np.testing.assert_allclose(plain.log_likelihood, with_ll.log_likelihood, rtol=1e-12)
    assert sorted(posts) == sorted(plain_posts) == [(0, 0), (0, 2), (1, 1)]
    expected = kf.update(TRACK, [SCAN[2]])
    for p in (posts[(0, 2)], plain_posts[(0, 2)]):
        np.testing.assert_allclose(p.mean, expected.mean, rtol=1e-12)
        np.testing.assert_allclose(p.cov, expected.cov, rtol=1e-12)


def test_per_sensor_clutter_and_per_track_detection():
    second = LinearGaussianSensor("pos2", H=H, R=4 * np.eye(2))
    kf = KalmanFilter(ConstantVelocity(ndim=2, q=0.1), [SENSOR, second])
    scan = [Measurement(1.0, "pos", [1.0, 2.0]), Measurement(1.0, "pos2", [1.0, 2.0])]
    scores = scan_likelihoods(
        [1, 2],
        [TRACK, OTHER],
        scan,
        [SENSOR, second],
        kf,
        [0.5, 1.0],
        {"pos": 0.01, "pos2": 0.02},
        gate_probability=1.0,
    )
    np.testing.assert_allclose(scores.log_clutter, np.log([0.01, 0.02]))
    np.testing.assert_allclose(scores.log_missed, [math.log(0.5), -np.inf])
    assert np.isfinite(scores.log_likelihood).all()  # P_G = 1: no gating
    z_pred, s = predicted_measurement(OTHER, second)
    expected = _log_gauss(np.array([1.0, 2.0]) - z_pred, s)
    assert scores.log_likelihood[1, 1] == pytest.approx(expected, rel=1e-12)


def test_scan_likelihoods_bad_input():
    kf = _kf()
    with pytest.raises(UnknownSensorError, match="'cam'"):
        scan_likelihoods([1], [TRACK], [Measurement(0, "cam", [1.0, 2.0])], [SENSOR], kf, 0.9, 1.0)
    with pytest.raises(ConfigError, match="p_detect"):
        scan_likelihoods([1], [TRACK], SCAN, [SENSOR], kf, 0.0, 1.0)
    with pytest.raises(ConfigError, match="p_detect"):
        scan_likelihoods([1], [TRACK], SCAN, [SENSOR], kf, [0.9, 0.9], 1.0)
    with pytest.raises(ConfigError, match="clutter_density"):
        scan_likelihoods([1], [TRACK], SCAN, [SENSOR], kf, 0.9, -1.0)
    with pytest.raises(ConfigError, match="clutter_density"):
        scan_likelihoods([1], [TRACK], SCAN, [SENSOR], kf, 0.9, {"other": 1.0})
    with pytest.raises(ConfigError, match="gate probability"):
        scan_likelihoods([1], [TRACK], SCAN, [SENSOR], kf, 0.9, 1.0, gate_probability=1.2)
    with pytest.raises(ShapeError, match=r"len\(beliefs\)"):
        scan_likelihoods([1, 2], [TRACK], SCAN, [SENSOR], kf, 0.9, 1.0)
    with pytest.raises(MeasurementError, match=r"value\.shape"):
        scan_likelihoods([1], [TRACK], [Measurement(0, "pos", [1.0])], [SENSOR], kf, 0.9, 1.0)
    batched = Measurement(0, "pos", np.zeros((3, 2)))
    with pytest.raises(MeasurementError, match="a vector"):
        scan_likelihoods([1], [TRACK], [batched], [SENSOR], kf, 0.9, 1.0)
    frame = Measurement(0, "pos", {"pixels": None})
    with pytest.raises(MeasurementError, match="a vector"):
        scan_likelihoods([1], [TRACK], [frame], [SENSOR], kf, 0.9, 1.0)


def test_scan_scores_feed_every_associator():
    from fusetrack.association import (
        Associator,
        GlobalNearestNeighbour,
        JointProbabilisticDataAssociation,
        TrackOrientedMHT,
    )

    scores = scan_likelihoods([7, 9], [TRACK, OTHER], SCAN, [SENSOR], _kf(), 0.9, 1e-3)
    for associator in (
        GlobalNearestNeighbour(),
        JointProbabilisticDataAssociation(),
        TrackOrientedMHT(n_scan=0),
    ):
        assert isinstance(associator, Associator)
        result = associator.associate(scores)
        best = {
            t: max(hs, key=lambda h: h.probability).measurement
            for t, hs in result.hypotheses.items()
        }
        # track 7 prefers z2 (innovation (0.5, 0.5)) over z0, track 9 takes z1; z3 is NaN
        assert best == {7: 2, 9: 1}
        assert 3 in result.unassociated
