"""The tracker's parts on hand-computed cases: scan scores and gate (association's, as the
tracker calls them), the PDA combination, the
IPDA existence update, the inverse-measurement prior, the M-of-N rule, the deleters."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2, multivariate_normal

from fusetrack.association import gate_threshold, mahalanobis_squared, scan_likelihoods
from fusetrack.core import ConfigError, Gaussian, Measurement, Particles
from fusetrack.filters import ExtendedKalmanFilter, KalmanFilter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import LinearGaussianSensor, PositionFix, RangeBearing
from fusetrack.tracking import (
    AnyOf,
    CovarianceDeleter,
    ExistenceDeleter,
    InverseMeasurementPrior,
    LiveTrack,
    MissedCountDeleter,
    MofNInitiator,
    SinglePointInitiator,
    combine_hypotheses,
    update_existence,
)

H = np.hstack([np.eye(2), np.zeros((2, 2))])
R = np.diag([0.25, 0.5])
POS = LinearGaussianSensor("pos", H=H, R=R)
KF = KalmanFilter(ConstantVelocity(ndim=2, q=0.1), [POS])


def test_scores_are_log_pd_plus_the_predictive_density_inside_the_gate():
    tracks = [
        Gaussian([0.0, 0.0, 1.0, 0.0], np.diag([1.0, 2.0, 1.0, 1.0])),
        Gaussian([10.0, 0.0, 0.0, 0.0], np.eye(4)),
    ]
    zs = [Measurement(0.0, "pos", v) for v in ([0.5, -1.0], [10.2, 0.3], [30.0, 30.0])]
    s, posteriors = scan_likelihoods(
        [7, 9], tracks, zs, {"pos": POS}, KF, p_detect=0.8, clutter_density=1e-3,
        gate_probability=0.99, keep_posteriors=True,
    )  # fmt: skip
    assert s.track_ids == (7, 9) and s.shape == (2, 3)
    expected = np.full((2, 3), -np.inf)
    for i, b in enumerate(tracks):
        cov = H @ b.cov @ H.T + R
        for j, z in enumerate(zs):
            d2 = (z.value - b.mean[:2]) @ np.linalg.solve(cov, z.value - b.mean[:2])
            if d2 <= chi2.ppf(0.99, 2):
                expected[i, j] = np.log(0.8) + multivariate_normal(b.mean[:2], cov).logpdf(z.value)
    assert np.isfinite(expected).sum() == 2  # (0, 0) and (1, 1) only
    np.testing.assert_allclose(s.log_likelihood, expected, rtol=1e-12)
    np.testing.assert_allclose(s.log_missed, np.log(1 - 0.8 * 0.99))
    np.testing.assert_allclose(s.log_clutter, np.log(1e-3))
    assert set(posteriors) == {(0, 0), (1, 1)}
    post = KF.update(tracks[1], [zs[1]])
    np.testing.assert_allclose(posteriors[(1, 1)].mean, post.mean, rtol=1e-14)


def test_the_gate_uses_the_measurement_covariance_and_the_sensor_residual():
    # the gate is exactly chi2^-1(P_G): a measurement on the boundary's two sides
    b = Gaussian(np.zeros(4), np.eye(4))
    s_xx = 1.0 + 0.25
    edge = np.sqrt(gate_threshold(0.95, 2) * s_xx)
    zs = [Measurement(0.0, "pos", [edge * f, 0.0]) for f in (0.999, 1.001)]
    d2 = mahalanobis_squared(POS, [b], zs)
    assert d2[0, 0] < gate_threshold(0.95, 2) < d2[0, 1]
    # a measurement's own covariance replaces R
    wide = Measurement(0.0, "pos", [edge * 1.001, 0.0], covariance=100.0 * np.eye(2))
    assert mahalanobis_squared(POS, [b], [wide])[0, 0] < 1.0
    # bearings are compared on the circle: pi - 0.01 and -pi + 0.01 are 0.02 apart
    radar = RangeBearing("radar", position=[0.0, 0.0], sigma_range=1.0, sigma_bearing=0.01)
    target = Gaussian([-10.0, 0.1, 0.0, 0.0], 1e-6 * np.eye(4))  # bearing pi - 0.01
    z = Measurement(0.0, "radar", [10.0, -np.pi + 0.01])
    assert mahalanobis_squared(radar, [target], [z])[0, 0] == pytest.approx(4.0, rel=1e-3)
    assert gate_threshold(1.0, 3) == np.inf


def test_pda_combination_equals_the_pdaf_update():
    """Bar-Shalom, Daum & Huang 2009, Eqs. 39-40: with innovations nu_j, gain K, posterior P+
    and prediction P-, the mixture is x = x- + K nu, nu = sum beta_j nu_j, and
    P = beta_0 P- + (1 - beta_0) P+ + K (sum beta_j nu_j nu_j^T - nu nu^T) K^T."""
    pred = Gaussian([1.0, 2.0, 0.5, -0.5], np.diag([2.0, 1.0, 0.5, 0.5]) + 0.1)
    zs = [Measurement(0.0, "pos", v) for v in ([1.5, 2.2], [0.2, 1.9])]
    posts = [KF.update(pred, [z]) for z in zs]
    beta = np.array([0.2, 0.5, 0.3])  # missed, z_1, z_2
    got = combine_hypotheses([pred, *posts], beta)
    s = H @ pred.cov @ H.T + R
    k = pred.cov @ H.T @ np.linalg.inv(s)
    nus = [z.value - pred.mean[:2] for z in zs]
    nu = beta[1] * nus[0] + beta[2] * nus[1]
    spread = sum(b * np.outer(n, n) for b, n in zip(beta[1:], nus)) - np.outer(nu, nu)
    p_plus = pred.cov - k @ s @ k.T
    expected_cov = beta[0] * pred.cov + (1 - beta[0]) * p_plus + k @ spread @ k.T
    np.testing.assert_allclose(got.mean, pred.mean + k @ nu, rtol=1e-12)
    np.testing.assert_allclose(got.cov, expected_cov, rtol=1e-10, atol=1e-12)


def test_combination_of_one_sure_hypothesis_or_of_particles_takes_the_most_probable():
    a = Gaussian([0.0], [[1.0]])
    assert combine_hypotheses([a], [1.0]) is a
    p = [Particles.uniform(np.full((5, 1), v)) for v in (0.0, 1.0, 2.0)]
    assert combine_hypotheses(p, [0.2, 0.5, 0.3]) is p[1]
    np.testing.assert_allclose(combine_hypotheses([a, a], [2.0, 2.0]).cov, [[1.0]])  # normalised
    with pytest.raises(ConfigError, match="probabilities"):
        combine_hypotheses([a, a], [0.5, -0.1])
    with pytest.raises(ConfigError, match="probabilities"):
        combine_hypotheses([a], [0.5, 0.5])


def test_existence_update_by_hand():
    # missed: r = (1 - 0.891) 0.5 / (1 - 0.891 * 0.5) = 0.0545 / 0.5545
    assert update_existence(0.5, 0.891, []) == pytest.approx(0.0545 / 0.5545, rel=1e-12)
    # one measurement with likelihood ratio 10: delta = 0.891 - 10
    assert update_existence(0.5, 0.891, [np.log(10.0)]) == pytest.approx(
        10.109 * 0.5 / (1 + 9.109 * 0.5), rel=1e-12
    )
    # a measurement as likely under the track as P_D P_G (delta = 0) leaves it as it was
    assert update_existence(0.3, 0.9, [np.log(0.9)]) == pytest.approx(0.3)
    assert update_existence(1.0, 1.0, []) == 0.0  # certain target certainly missed
    assert update_existence(0.9, 0.5, [50.0]) == 1.0 - 1e-9  # capped below 1


def test_inverse_measurement_prior_of_a_linear_sensor():
    wide = Gaussian([0.0, 0.0, 1.0, -1.0], np.diag([1e6, 1e6, 4.0, 9.0]))
    prior = InverseMeasurementPrior({"pos": POS}, wide)
    g = prior(Measurement(2.0, "pos", [3.0, 4.0]))
    np.testing.assert_allclose(g.mean, [3.0, 4.0, 1.0, -1.0])
    np.testing.assert_allclose(g.cov, np.diag([0.25, 0.5, 4.0, 9.0]))
    own = prior(Measurement(2.0, "pos", [3.0, 4.0], covariance=np.eye(2)))
    np.testing.assert_allclose(own.cov[:2, :2], np.eye(2))
    # a biased position fix on the last two components: x_o = z - bias
    tag = PositionFix("tag", cov=np.eye(2), bias=[0.5, -0.5], position_index=(2, 3))
    g = InverseMeasurementPrior([tag], wide)(Measurement(0.0, "tag", [1.0, 1.0]))
    np.testing.assert_allclose(g.mean, [0.0, 0.0, 0.5, 1.5])
    assert prior(Measurement(0.0, "other", [1.0, 1.0])) is None  # not a birth sensor
    # it equals the Kalman update of the wide prior as the position variance goes to infinity
    post = KF.update(wide, [Measurement(0.0, "pos", [3.0, 4.0])])
    np.testing.assert_allclose(post.mean, [3.0, 4.0, 1.0, -1.0], atol=1e-5)
    np.testing.assert_allclose(post.cov, np.diag([0.25, 0.5, 4.0, 9.0]), atol=1e-6)


def test_inverse_prior_refuses_what_it_cannot_invert():
    wide = Gaussian(np.zeros(4), np.eye(4))
    radar = RangeBearing("radar", position=[0.0, 0.0], sigma_range=1.0, sigma_bearing=0.1)
    with pytest.raises(ConfigError, match="linear sensor"):
        InverseMeasurementPrior([radar], wide)
    # x + y only: two state components, one reading
    sum_sensor = LinearGaussianSensor("sum", H=[[1.0, 1.0, 0.0, 0.0]], R=[[1.0]])
    with pytest.raises(ConfigError, match="determines"):
        InverseMeasurementPrior([sum_sensor], wide)
    with pytest.raises(ConfigError, match="unobserved"):
        InverseMeasurementPrior([POS], Gaussian(np.zeros((2, 4)), np.eye(4)))


def _track(**kw):
    return LiveTrack(0, Gaussian(np.zeros(4), np.eye(4)), 0.0, 0.0, 0.0, **kw)


@pytest.mark.parametrize(
    ("hits", "scans", "status"),
    [
        (1, 1, "tentative"),
        (2, 2, "tentative"),
        (3, 3, "confirmed"),  # the m-th hit
        (2, 3, "tentative"),  # 2 + 2 scans left >= 3
        (1, 3, "tentative"),  # 1 + 2 = 3: still possible
        (1, 4, "dropped"),  # 1 + 1 < 3
        (3, 5, "confirmed"),
        (2, 5, "dropped"),
    ],
)
def test_m_of_n_status_table(hits, scans, status):
    init = MofNInitiator(3, 5, lambda m: None)
    assert init.status(_track(hits=hits, scans=scans)) == status


def test_single_point_initiator_confirms_at_birth():
    init = SinglePointInitiator(lambda m: None, existence=0.2)
    assert (init.m, init.n, init.existence) == (1, 1, 0.2)
    assert init.status(_track()) == "confirmed"
    with pytest.raises(ConfigError, match="prior_from"):
        MofNInitiator(1, 2, "not a function")
    with pytest.raises(ConfigError, match="existence"):
        MofNInitiator(1, 2, lambda m: None, existence=0.0)


def test_deleters():
    assert not MissedCountDeleter(3).should_delete(_track(misses=2))
    assert MissedCountDeleter(3).should_delete(_track(misses=3))
    big = LiveTrack(0, Gaussian(np.zeros(4), np.diag([1.0, 2.0, 50.0, 50.0])), 0.0, 0.0, 0.0)
    assert CovarianceDeleter(10.0).should_delete(big)
    assert not CovarianceDeleter(10.0, indices=[0, 1]).should_delete(big)  # trace 3
    assert ExistenceDeleter(0.1).should_delete(_track(existence=0.05))
    assert not ExistenceDeleter(0.1).should_delete(_track(existence=0.5))
    either = AnyOf(MissedCountDeleter(5), ExistenceDeleter(0.1))
    assert either.should_delete(_track(existence=0.05)) and either.should_delete(_track(misses=5))
    assert not either.should_delete(_track(misses=4, existence=0.5))
    for bad in (lambda: MissedCountDeleter(0), lambda: CovarianceDeleter(-1.0),
                lambda: ExistenceDeleter(1.5), lambda: AnyOf(), lambda: AnyOf(object())):  # fmt: skip
        with pytest.raises(ConfigError):
            bad()


def test_ekf_scores_are_its_own_likelihood_increment():
    radar = RangeBearing("radar", position=[0.0, 0.0], sigma_range=0.5, sigma_bearing=0.01)
    ekf = ExtendedKalmanFilter(ConstantVelocity(ndim=2, q=0.1), [radar])
    b = Gaussian([10.0, 0.0, 0.0, 0.0], np.eye(4))
    z = Measurement(0.0, "radar", [10.3, 0.02])
    scores = scan_likelihoods(
        [0], [b], [z], {"radar": radar}, ekf, p_detect=1.0, clutter_density=1.0,
        gate_probability=1.0,
    )  # fmt: skip
    _, ll = ekf.update_with_likelihood(b, [z])
    assert scores.log_likelihood[0, 0] == pytest.approx(float(ll), rel=1e-12)
    assert scores.log_missed[0] == -np.inf  # P_D P_G = 1


class PlainKF(KalmanFilter):
    """The same filter, seen as one the batch path does not trust (methods overridden)."""

    def predict(self, belief, dt, rng=None):
        return super().predict(belief, dt, rng)

    def update_with_likelihood(self, belief, measurements, rng=None):
        return super().update_with_likelihood(belief, measurements, rng)


def test_batched_filter_calls_equal_one_call_per_track():
    from fusetrack.association import batchable, predict_many, update_pairs

    rng = np.random.default_rng(5)
    beliefs = []
    for _ in range(6):
        a = rng.standard_normal((4, 4))
        beliefs.append(Gaussian(rng.normal(0, 5, 4), a @ a.T + np.eye(4)))
    zs = [Measurement(1.0, "pos", rng.normal(0, 5, 2)) for _ in range(6)]
    zs[2] = Measurement(1.0, "pos", [1.0, 2.0], covariance=[[2.0, 0.3], [0.3, 1.0]])
    plain = PlainKF(KF.motion, [POS])
    assert batchable(KF, beliefs) and not batchable(plain, beliefs)
    assert not batchable(KF, [Particles.uniform(np.zeros((3, 4)))])
    for got, ref in zip(
        predict_many(KF, beliefs, 0.7, None), predict_many(plain, beliefs, 0.7, None)
    ):
        np.testing.assert_allclose(got.mean, ref.mean, rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(got.cov, ref.cov, rtol=1e-13, atol=1e-13)
    for (got, ll), (ref, ref_ll) in zip(
        update_pairs(KF, beliefs, zs, None), update_pairs(plain, beliefs, zs, None)
    ):
        np.testing.assert_allclose(got.mean, ref.mean, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(got.cov, ref.cov, rtol=1e-12, atol=1e-12)
        assert ll == pytest.approx(ref_ll, rel=1e-12)
