"""EKF and UKF reduce to the KF on linear models, and match FilterPy on a nonlinear one."""

from __future__ import annotations

import numpy as np
import pytest
from filterpy.kalman import ExtendedKalmanFilter as FpEKF
from filterpy.kalman import MerweScaledSigmaPoints
from filterpy.kalman import UnscentedKalmanFilter as FpUKF

from fusetrack.core import Gaussian, Measurement
from fusetrack.filters import ExtendedKalmanFilter, KalmanFilter, UnscentedKalmanFilter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import Bearing, PositionFix, RangeBearing


def _linear_run(filt, steps):
    belief = Gaussian(np.array([0.0, 1.0, 1.0, -0.5]), np.diag([2.0, 1.0, 0.5, 0.5]))
    out = []
    for dt, ms in steps:
        belief = filt.update(filt.predict(belief, dt), ms)
        out.append(belief)
    return out


@pytest.mark.parametrize(
    ("cls", "kw"),
    [
        (ExtendedKalmanFilter, {}),
        (UnscentedKalmanFilter, {}),
        (UnscentedKalmanFilter, {"alpha": 0.5, "beta": 2.0, "kappa": 0.0}),
    ],
)
def test_nonlinear_filters_equal_kf_on_linear_models(cls, kw):
    rng = np.random.default_rng(4)
    motion = ConstantVelocity(q=0.3)
    sensors = [
        PositionFix("gps", cov=[[0.5, 0.1], [0.1, 0.3]], bias=[0.2, -0.1]),
        PositionFix("x-only", cov=[[0.2]], position_index=(0,)),
    ]
    steps = []
    for k in range(30):
        ms = [Measurement(k, "gps", rng.standard_normal(2) + np.array([k, 1 - 0.5 * k]))]
        if k % 3 == 0:
            ms.append(Measurement(k, "x-only", rng.standard_normal(1) + k))
        steps.append((float(rng.uniform(0.1, 2.0)), ms))
    ref = _linear_run(KalmanFilter(motion, sensors), steps)
    got = _linear_run(cls(motion, sensors, **kw), steps)
    for a, b in zip(ref, got):
        np.testing.assert_allclose(b.mean, a.mean, rtol=0, atol=1e-10)
        np.testing.assert_allclose(b.cov, a.cov, rtol=0, atol=1e-10)


def _range_bearing_problem(n_steps=25):
    """A target passing a radar, with the bearing crossing +-pi (tests the angle wrapping)."""
    rng = np.random.default_rng(5)
    motion = ConstantVelocity(q=0.05)
    radar = RangeBearing("radar", position=[0.0, 0.0], sigma_range=0.3, sigma_bearing=0.02)
    x = np.array([-10.0, 3.0, 0.8, -0.25])
    truth, zs, dts = [], [], []
    for _ in range(n_steps):
        dt = float(rng.uniform(0.5, 1.5))
        x = motion.sample(x, dt, rng)
        truth.append(x)
        zs.append(radar.simulate(x, rng))
        dts.append(dt)
    x0 = np.array([-10.5, 3.2, 0.7, -0.2])
    p0 = np.diag([1.0, 1.0, 0.1, 0.1])
    return motion, radar, x0, p0, dts, zs


def test_range_bearing_problem_crosses_the_branch_cut():
    _, _, _, _, _, zs = _range_bearing_problem()
    bearings = np.array([z[1] for z in zs])
    assert np.any(bearings > 2.5) and np.any(bearings < -2.5)


def test_ekf_matches_filterpy_on_range_bearing():
    motion, radar, x0, p0, dts, zs = _range_bearing_problem()
    ours = ExtendedKalmanFilter(motion, [radar])
    belief = Gaussian(x0, p0)

    fp = FpEKF(dim_x=4, dim_z=2)
    fp.x, fp.P, fp.R = x0.copy(), p0.copy(), radar.noise_cov()
    for k, (dt, z) in enumerate(zip(dts, zs)):
        fp.F, fp.Q = motion.transition_matrix(dt), motion.noise_cov(dt)
        fp.predict()
        fp.update(z, radar.jacobian, radar.predict, residual=radar.residual)
        belief = ours.update(ours.predict(belief, dt), [Measurement(k, "radar", z)])
        np.testing.assert_allclose(belief.mean, fp.x, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(belief.cov, fp.P, rtol=1e-10, atol=1e-10)


def _circular_z_mean(angular):
    ang = np.asarray(angular, bool)

    def z_mean(sigmas, wm):
        z = wm @ sigmas
        z[ang] = np.arctan2(wm @ np.sin(sigmas[:, ang]), wm @ np.cos(sigmas[:, ang]))
        return z

    return z_mean


@pytest.mark.parametrize(("alpha", "beta", "kappa"), [(1.0, 2.0, None), (0.3, 2.0, 0.0)])
def test_ukf_matches_filterpy_on_range_bearing(alpha, beta, kappa):
    motion, radar, x0, p0, dts, zs = _range_bearing_problem()
    ours = UnscentedKalmanFilter(motion, [radar], alpha=alpha, beta=beta, kappa=kappa)
    belief = Gaussian(x0, p0)

    fp_kappa = 3 - 4 if kappa is None else kappa
    points = MerweScaledSigmaPoints(4, alpha=alpha, beta=beta, kappa=fp_kappa)
    np.testing.assert_allclose(ours.wm, points.Wm, atol=1e-15)
    np.testing.assert_allclose(ours.wc, points.Wc, atol=1e-15)
    fp = FpUKF(
        dim_x=4,
        dim_z=2,
        dt=1.0,
        hx=radar.predict,
        fx=lambda x, dt: motion.mean(x, dt),
        points=points,
        z_mean_fn=_circular_z_mean(radar.angular),
        residual_z=radar.residual,
    )
    fp.x, fp.P, fp.R = x0.copy(), p0.copy(), radar.noise_cov()
    for k, (dt, z) in enumerate(zip(dts, zs)):
        fp.Q = motion.noise_cov(dt)
        fp.predict(dt=dt)
        fp.update(z)
        belief = ours.update(ours.predict(belief, dt), [Measurement(k, "radar", z)])
        np.testing.assert_allclose(belief.mean, fp.x, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(belief.cov, 0.5 * (fp.P + fp.P.T), rtol=1e-10, atol=1e-10)


def test_ukf_matches_filterpy_on_bearing_only_pair():
    """Two microphones' bearings stacked in one FilterPy update vs our two sequential updates
    is not the same filter (the UKF is not exact), so compare one sensor at a time."""
    rng = np.random.default_rng(6)
    motion = ConstantVelocity(q=0.02)
    mic = Bearing("mic", position=[2.0, -1.0], sigma=0.03, heading=0.4)
    x0 = np.array([5.0, 5.0, -0.3, 0.1])
    p0 = np.diag([0.5, 0.5, 0.05, 0.05])
    ours = UnscentedKalmanFilter(motion, [mic])
    fp = FpUKF(
        dim_x=4,
        dim_z=1,
        dt=1.0,
        hx=mic.predict,
        fx=lambda x, dt: motion.mean(x, dt),
        points=MerweScaledSigmaPoints(4, alpha=1.0, beta=2.0, kappa=-1.0),
        z_mean_fn=_circular_z_mean(mic.angular),
        residual_z=mic.residual,
    )
    fp.x, fp.P, fp.R = x0.copy(), p0.copy(), mic.noise_cov()
    belief = Gaussian(x0, p0)
    x = x0.copy()
    for k in range(15):
        x = motion.sample(x, 1.0, rng)
        z = mic.simulate(x, rng)
        fp.Q = motion.noise_cov(1.0)
        fp.predict(dt=1.0)
        fp.update(z)
        belief = ours.update(ours.predict(belief, 1.0), [Measurement(k, "mic", z)])
        np.testing.assert_allclose(belief.mean, fp.x, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(belief.cov, 0.5 * (fp.P + fp.P.T), rtol=1e-10, atol=1e-10)


def test_ukf_circular_mean_of_predicted_bearing():
    """Sigma points straddling +-pi: the predicted bearing is near pi, not near 0."""
    mic = Bearing("mic", position=[0.0, 0.0], sigma=0.01)
    ukf = UnscentedKalmanFilter(ConstantVelocity(), [mic])
    mom = ukf.propagate_sensor(mic, np.array([-10.0, 0.0, 0.0, 0.0]), np.diag([1.0, 4.0, 1, 1]))
    assert abs(abs(mom.z_pred[0]) - np.pi) < 1e-12
    assert mom.pzz[0, 0] < 0.1  # spread of bearings around pi, not around 0


def test_ukf_rejects_bad_scaling():
    from fusetrack.core import ConfigError

    with pytest.raises(ConfigError, match="kappa"):
        UnscentedKalmanFilter(ConstantVelocity(), [], kappa=-4.0)
    with pytest.raises(ConfigError, match="alpha"):
        UnscentedKalmanFilter(ConstantVelocity(), [], alpha=0.0)
