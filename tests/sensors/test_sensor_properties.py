"""Property tests: any batch shape, any angles."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import array_shapes, arrays

from fusetrack.sensors import (
    AzimuthPolar,
    Bearing,
    PositionFix,
    Range,
    RangeBearing,
    SensorBase,
    wrap,
)

SENSORS: list[SensorBase] = [
    Bearing("b", [1.0, -2.0], 0.1, heading=2.0),
    AzimuthPolar("ap", [0.0, 1.0, 2.0], 0.1, 0.2, heading=-3.0),
    Range("r", [1.0, 2.0, 3.0], 0.5),
    RangeBearing("rb", [0.0, 0.0], 0.5, 0.1, heading=math.pi),
    PositionFix("tag", [[0.2, 0.05], [0.05, 0.1]], bias=[0.1, 0.2]),
]
FAST = settings(max_examples=40, deadline=None)
coords = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)
angles = st.floats(-1e4, 1e4, allow_nan=False, allow_infinity=False)


@FAST
@given(
    sensor=st.sampled_from(SENSORS),
    shape=array_shapes(min_dims=0, max_dims=3, max_side=4),
    data=st.data(),
)
def test_shapes_for_any_batch(
    sensor: SensorBase, shape: tuple[int, ...], data: st.DataObject
) -> None:
    d = 6
    x = data.draw(arrays(np.float64, (*shape, d), elements=coords))
    zp = sensor.predict(x)
    assert zp.shape == (*shape, sensor.dim)
    assert sensor.jacobian(x).shape == (*shape, sensor.dim, d)
    assert sensor.fisher_information(x).shape == (*shape, d, d)
    assert sensor.detection_probability(x).shape == shape
    z = data.draw(arrays(np.float64, (sensor.dim,), elements=coords))
    ll = sensor.log_likelihood(z, x)
    assert ll.shape == shape
    assert np.all(np.isfinite(ll) | (ll == -np.inf))
    assert np.all(ll <= sensor.log_likelihood(zp, x) + 1e-9)  # the prediction is the mode
    sim = sensor.simulate(x, np.random.default_rng(0))
    assert sim.shape == zp.shape
    for k, is_angle in enumerate(sensor.angular):
        if is_angle:
            assert np.all((zp[..., k] >= -math.pi) & (zp[..., k] < math.pi))


@FAST
@given(
    sensor=st.sampled_from([s for s in SENSORS if any(s.angular)]),
    z=arrays(np.float64, array_shapes(min_dims=1, max_dims=3, max_side=5), elements=angles),
    zp=angles,
)
def test_angle_residuals_are_wrapped(sensor: SensorBase, z: np.ndarray, zp: float) -> None:
    zz = np.broadcast_to(z[..., None], (*z.shape, sensor.dim))
    r = sensor.residual(zz, np.full(sensor.dim, zp))
    for k, is_angle in enumerate(sensor.angular):
        rk = r[..., k]
        if is_angle:
            assert np.all((rk >= -math.pi) & (rk < math.pi))
            # congruent to z - zp modulo 2 pi
            np.testing.assert_allclose(np.exp(1j * rk), np.exp(1j * (z - zp)), atol=1e-8)
        else:
            np.testing.assert_allclose(rk, z - zp)


@FAST
@given(a=arrays(np.float64, array_shapes(min_dims=0, max_dims=2), elements=angles))
def test_wrap_range_and_congruence(a: np.ndarray) -> None:
    w = wrap(a)
    assert w.shape == a.shape
    assert np.all((w >= -math.pi) & (w < math.pi))
    np.testing.assert_allclose(np.exp(1j * w), np.exp(1j * a), atol=1e-8)


@FAST
@given(
    heading=st.floats(-10, 10),
    bearing=st.floats(-math.pi, math.pi),
    dist=st.floats(0.1, 100),
    noise=st.floats(-0.5, 0.5),
)
def test_bearing_log_likelihood_depends_only_on_wrapped_error(
    heading: float, bearing: float, dist: float, noise: float
) -> None:
    s = Bearing("b", [0.0, 0.0], 0.2, heading=heading)
    x = dist * np.array([math.cos(bearing), math.sin(bearing)])
    z = np.array([float(wrap(bearing - heading + noise))])
    expected = -0.5 * (noise / 0.2) ** 2 - math.log(0.2 * math.sqrt(2 * math.pi))
    assert math.isclose(float(s.log_likelihood(z, x)), expected, rel_tol=1e-6, abs_tol=1e-6)
