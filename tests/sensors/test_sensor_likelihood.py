"""log_likelihood against scipy, wrapped residuals, broadcasting of z against particles."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import multivariate_normal, norm

from fusetrack.sensors import AzimuthPolar, Bearing, PositionFix, Range, RangeBearing, SensorBase

CASES: list[tuple[SensorBase, int]] = [
    (Bearing("bearing", [1.0, 2.0], 0.2, heading=0.4), 4),
    (AzimuthPolar("azpol", [0.5, -1.0, 2.0], 0.1, 0.2), 6),
    (Range("range3", [1.0, 2.0, -1.0], 0.3), 6),
    (RangeBearing("rb", [3.0, -2.0], 0.3, 0.05), 4),
    (PositionFix("tag", [[0.2, 0.05], [0.05, 0.1]], bias=[0.3, -0.1]), 4),
    (PositionFix("tag_diag", np.diag([0.1, 0.2, 0.3]), position_index=(0, 2, 4)), 6),
]


@pytest.mark.parametrize(("sensor", "d"), CASES, ids=[c[0].sensor_id for c in CASES])
def test_log_likelihood_equals_scipy_on_the_wrapped_residual(sensor: SensorBase, d: int) -> None:
    rng = np.random.default_rng(3)
    x = rng.uniform(-5.0, 5.0, size=(7, 50, d))
    z = sensor.predict(rng.uniform(-5.0, 5.0, size=d)) + rng.normal(size=sensor.dim)
    ll = sensor.log_likelihood(z, x)
    assert ll.shape == (7, 50)
    r = sensor.residual(z, sensor.predict(x))
    mvn = multivariate_normal(mean=np.zeros(sensor.dim), cov=sensor.noise_cov())
    expected = mvn.logpdf(r.reshape(-1, sensor.dim)).reshape(7, 50)
    np.testing.assert_allclose(ll, expected, rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize(("sensor", "d"), CASES, ids=[c[0].sensor_id for c in CASES])
def test_z_broadcasts_against_particle_batches(sensor: SensorBase, d: int) -> None:
    rng = np.random.default_rng(4)
    x = rng.uniform(-5.0, 5.0, size=(3, 20, d))  # 3 runs x 20 particles
    z = sensor.predict(rng.uniform(-5.0, 5.0, size=(3, d))) + 0.1  # one measurement per run
    ll = sensor.log_likelihood(z[:, None, :], x)
    assert ll.shape == (3, 20)
    for run in range(3):
        np.testing.assert_allclose(ll[run], sensor.log_likelihood(z[run], x[run]), rtol=1e-12)
    # and one row per particle
    zz = sensor.predict(x) + 0.05
    ll2 = sensor.log_likelihood(zz, x)
    assert ll2.shape == (3, 20)
    np.testing.assert_allclose(ll2[1, 5], sensor.log_likelihood(zz[1, 5], x[1, 5]), rtol=1e-12)


def test_bearing_wraps_around_pi() -> None:
    s = Bearing("b", [0.0, 0.0], 0.05)
    a = -math.pi + 0.01  # predicted bearing just above -pi
    x = np.array([math.cos(a), math.sin(a)])
    z = np.array([math.pi - 0.01])  # measured just below +pi
    r = s.residual(z, s.predict(x))
    assert r == pytest.approx([-0.02], abs=1e-12)
    assert s.log_likelihood(z, x) == pytest.approx(norm(0.0, 0.05).logpdf(0.02), rel=1e-12)
    # the other way round
    b = math.pi - 0.01
    x2 = np.array([math.cos(b), math.sin(b)])
    assert s.residual([-math.pi + 0.01], s.predict(x2)) == pytest.approx([0.02], abs=1e-12)


def test_range_bearing_wraps_only_the_bearing() -> None:
    s = RangeBearing("rb", [0.0, 0.0], 1.0, 0.1)
    r = s.residual([10.0, math.pi - 0.01], [2.0, -math.pi + 0.01])
    assert r == pytest.approx([8.0, -0.02], abs=1e-12)


def test_azimuth_wraps_polar_does_not() -> None:
    s = AzimuthPolar("ap", [0.0, 0.0, 0.0], 0.1, 0.1)
    r = s.residual([math.pi - 0.01, 3.0], [-math.pi + 0.01, 0.1])
    assert r == pytest.approx([-0.02, 2.9], abs=1e-12)


def test_likelihood_is_maximal_at_the_truth() -> None:
    s = RangeBearing("rb", [0.0, 0.0], 0.5, 0.02)
    truth = np.array([3.0, 4.0])
    grid = truth + np.stack(np.meshgrid(np.linspace(-1, 1, 21), np.linspace(-1, 1, 21)), -1)
    ll = s.log_likelihood(s.predict(truth), grid)
    assert np.unravel_index(np.argmax(ll), ll.shape) == (10, 10)


def test_nan_measurement_gives_nan() -> None:
    s = Bearing("b", [0.0, 0.0], 0.1)
    assert np.isnan(s.log_likelihood([np.nan], np.ones((4, 2)))).all()


def test_wrong_measurement_size_raises() -> None:
    from fusetrack.core import ShapeError

    with pytest.raises(ShapeError, match=r"z\.shape"):
        RangeBearing("rb", [0.0, 0.0], 1.0, 0.1).log_likelihood([1.0, 2.0, 3.0], np.ones(2))
    with pytest.raises(ShapeError, match=r"x\.shape"):
        Bearing("b", [0.0, 0.0], 0.1, position_index=(2, 3)).predict(np.ones((5, 3)))


def test_log_likelihood_is_fast_for_many_particles() -> None:
    """The particle filter's hot path: 200k particles should take milliseconds, not seconds."""
    import time

    s = Bearing("b", [0.0, 0.0], 0.1)
    x = np.random.default_rng(0).normal(size=(200_000, 4))
    s.log_likelihood([0.3], x)
    t0 = time.perf_counter()
    s.log_likelihood([0.3], x)
    assert time.perf_counter() - t0 < 0.5
