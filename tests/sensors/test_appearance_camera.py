"""The smart camera's appearance sensor model (Kushwaha 2010, Ch. V) and frames as measurements."""

from functools import lru_cache

import numpy as np
import pytest

from fusetrack.core import Measurement
from fusetrack.core.errors import MeasurementError
from fusetrack.perception.appearance import appearance_model_from_views, features_from_rgb
from fusetrack.sensors.appearance import N_HS, FeatureImage, bhattacharyya, region_histograms
from fusetrack.sensors.appearance_camera import (
    RHO_FLOOR,
    AppearanceCamera,
    colour_log_likelihood,
    reference_histogram,
)
from fusetrack.world.ellipsoid_scene import (
    EllipsoidTarget,
    Trajectory,
    corner_cameras,
    cube_viewpoints,
    reference_views,
    render_frames,
)


@lru_cache(maxsize=1)
def _camera():
    target = EllipsoidTarget()
    views = cube_viewpoints()
    model = appearance_model_from_views(*reference_views(target, views), views)
    cam = corner_cameras(focal=200.0)[0]
    x = np.array([4.0, 4.0, 1.2])
    q = np.array([0.0, 0.0, 0.0, 1.0])
    truth = Trajectory(x[None], np.zeros((1, 3)), q[None])
    frame = features_from_rgb(
        render_frames([cam], target, truth, np.random.default_rng(0)).images[0][0]
    )
    return AppearanceCamera(cam, model, target.semi_axes), frame, x, q


def test_the_true_position_is_the_most_likely_and_far_ones_hit_the_floor():
    sensor, frame, x, q = _camera()
    rng = np.random.default_rng(1)
    near = x + 0.02 * rng.standard_normal((50, 3))
    far = x + np.array([2.5, -2.5, 0.0]) + 0.02 * rng.standard_normal((50, 3))
    ll_true = sensor.log_likelihood(frame, x[None], q)[0]
    assert ll_true > np.log(0.8)  # rho of the right view at the right place: near 1
    assert ll_true >= sensor.log_likelihood(frame, near, q).max() - 0.05
    ll_far = sensor.log_likelihood(frame, far, q)
    assert ll_far.max() < ll_true - 0.3
    assert np.all(ll_far >= np.log(RHO_FLOOR))
    assert sensor.participates(x, q)
    assert sensor.sensor_id == sensor.camera.sensor_id


def test_pixel_hypotheses_use_the_ellipse_predicted_at_x0():
    sensor, frame, x, q = _camera()
    yc, _ = sensor.predicted_region(x, q)
    pixels = yc + np.array([[0.0, 0.0], [15.0, 0.0], [0.0, -15.0]])
    ll = sensor.log_likelihood_pixels(frame, pixels, x, q)
    # at the predicted centre the pixel and the 3-D hypotheses are the same region
    np.testing.assert_allclose(ll[0], sensor.log_likelihood(frame, x[None], q)[0], rtol=1e-12)
    assert ll[0] > ll[1:].max()
    rho = sensor.view_similarities(frame, x, q)
    assert rho.shape == (len(sensor.model.viewpoints),) and np.isclose(np.log(rho.max()), ll[0])


def test_colour_likelihood_is_minus_lambda_one_minus_rho():
    bins = np.zeros((20, 20), np.int32)
    bins[:, 10:] = 5
    frame = FeatureImage(bins, bins)
    shape = np.eye(2) / 16.0  # circle of radius 4 px
    ref = reference_histogram(frame, np.array([5.0, 10.0]), shape)
    assert ref[0] == 1.0
    pixels = np.array([[5.0, 10.0], [10.0, 10.0], [15.0, 10.0]])
    ll = colour_log_likelihood(frame, pixels, shape, ref, lam=20.0)
    p = region_histograms(bins, pixels, np.broadcast_to(shape, (3, 2, 2)), N_HS)
    np.testing.assert_allclose(ll, -20.0 * (1.0 - bhattacharyya(p, ref)), rtol=0, atol=0)
    assert ll[0] == 0.0 and ll[0] > ll[1] > ll[2]


def test_a_frame_travels_as_a_measurement_value():
    _, frame, _, _ = _camera()
    m = Measurement(3.0, "cam0", frame)
    assert m.value is frame and m.is_finite
    with pytest.raises(MeasurementError, match="covariance"):
        Measurement(3.0, "cam0", frame, covariance=np.eye(2))
    assert Measurement(1.0, "x", [1, 2]).value.dtype == float  # vectors are still converted
