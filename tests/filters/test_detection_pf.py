"""The grid-free detection-function particle filter: a pure Filter; its sensor model."""

import numpy as np
import pytest

from fusetrack.core.errors import MeasurementError
from fusetrack.core.measurement import Measurement
from fusetrack.core.models import Filter, LikelihoodFilter
from fusetrack.filters.detection_pf import DetectionParticleFilter, position_estimate
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors.bearing_detection import DetectionFunctionSensor
from fusetrack.sensors.detection_function import AngularSampling

BEAMS = AngularSampling.beams(36)


def _sensors():
    return {
        "A": DetectionFunctionSensor("A", (0.0, 0.0), 0.0, sampling=BEAMS),
        "V": DetectionFunctionSensor("V", (10.0, 0.0), np.pi / 2, fov=np.pi / 2),
    }


def test_camera_mixture_peaks_at_its_bearing_and_is_neutral_outside_the_view():
    cam = _sensors()["V"]
    z = DetectionFunctionSensor.mixture_value([1.0], [0.0], [0.05])
    on, off, outside = cam.likelihood(z, np.array([[10.0, 5.0], [12.0, 5.0], [10.0, -5.0]]))
    assert on > 5 * off
    assert outside == pytest.approx((1 + cam.floor) / cam.fov)
    with pytest.raises(MeasurementError):
        cam.likelihood(np.ones(4), np.zeros((1, 2)))


def test_two_bearings_localise_the_target_and_the_filter_is_pure():
    target = np.array([6.0, 6.0])
    sensors = _sensors()
    values = np.exp(-0.5 * ((BEAMS.angles - np.arctan2(6.0, 6.0)) / 0.1) ** 2)
    cam_bearing = np.arctan2(6.0, -4.0) - np.pi / 2
    zs = [
        Measurement(0.0, "A", values),
        Measurement(0.0, "V", DetectionFunctionSensor.mixture_value([1.0], [cam_bearing], [0.05])),
    ]
    pf = DetectionParticleFilter(ConstantVelocity(ndim=2, q=0.01), sensors, 20000)
    assert isinstance(pf, Filter) and isinstance(pf, LikelihoodFilter)
    rng = np.random.default_rng(0)
    b0 = pf.initial_belief(rng.uniform(2, 10, (20000, 2)), 0.1, rng)
    b1 = pf.update(pf.predict(b0, 0.1, rng), zs, rng)
    assert np.all(b0.log_weights == b0.log_weights[0])  # the input belief is untouched
    mean, cov = position_estimate(b1)
    assert np.linalg.norm(mean - target) < 0.8 and np.trace(cov) < 4.0  # prior: 10.7
    b2, ll = pf.update_with_likelihood(pf.predict(b1, 0.1, rng), zs, rng)
    assert np.isfinite(ll) and np.linalg.norm(position_estimate(b2)[0] - target) < 0.8
    with pytest.raises(MeasurementError, match="sensor_id"):
        pf.update(b1, [Measurement(0.0, "nobody", values)])


@pytest.mark.parametrize("heading", [0.3, -2.0])  # theta + pi below 0 / above 2 pi
@pytest.mark.parametrize("sampling", [BEAMS, AngularSampling.camera_bins(1.0, 160)])
def test_one_pass_log_likelihood_is_the_log_of_the_likelihood(sampling, heading):
    """The kernel path of a sampled detection function gives log(likelihood), for wrapped beams
    and for bins held at their ends, over batched particles, and 0 (the neutral value) for a flat
    function. To 1e-12, not bit for bit: on a CPU with AVX-512, NumPy's bearings (``arctan2``)
    and ``log`` come from its SIMD kernels, which differ from the kernel's libm in the last ulps
    (up to 8e-14 here on an AMD znver4, 2026-12-04; equal bit for bit on session 18's machine)."""
    rng = np.random.default_rng(0)
    sensor = DetectionFunctionSensor("A", (5.0, 4.0), heading, sampling=sampling)
    z = 1.0 + rng.random(sampling.size)
    x = rng.normal(10.0, 8.0, (3, 500, 4))
    expected = np.log(np.maximum(sensor.likelihood(z, x[..., :2]), 1e-300))
    got = sensor.log_likelihood(z, x)
    assert got.shape == (3, 500)
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12)
    assert np.all(sensor.log_likelihood(np.full(sampling.size, 2.0), x) == 0.0)
