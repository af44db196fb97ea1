"""HS/LBP region histograms and Bhattacharyya similarity (Kushwaha 2010, Ch. V, Eqs. 62, 74-75)."""

import numpy as np

from fusetrack.perception.appearance import appearance_model_from_views, features_from_rgb, hs_bins
from fusetrack.sensors.appearance import (
    N_HS,
    N_LBP,
    bhattacharyya,
    region_histograms,
    region_histograms_reference,
)
from fusetrack.world.ellipsoid_scene import EllipsoidTarget, cube_viewpoints, reference_views


def test_numba_histograms_equal_the_reference():
    rng = np.random.default_rng(1)
    bins = rng.integers(0, N_HS, size=(60, 80)).astype(np.int32)
    centres = rng.uniform([-5, -5], [85, 65], size=(40, 2))
    a = rng.uniform(0.002, 0.05, size=(40, 2))
    shapes = np.zeros((40, 2, 2))
    shapes[:, 0, 0], shapes[:, 1, 1] = a[:, 0], a[:, 1]
    shapes[:, 0, 1] = shapes[:, 1, 0] = 0.3 * np.sqrt(a[:, 0] * a[:, 1])
    np.testing.assert_allclose(
        region_histograms(bins, centres, shapes, N_HS),
        region_histograms_reference(bins, centres, shapes, N_HS),
        atol=1e-12,
    )


def test_epanechnikov_weights_by_hand():
    # 3x3 image, unit circle of radius sqrt(2) at the centre pixel: d = 0 (centre), 1/2 (edges), 1 (corners)
    bins = np.array([[0, 1, 0], [1, 2, 1], [0, 1, 0]], np.int32)
    h = region_histograms(bins, [[1.0, 1.0]], [np.eye(2) / 2.0], 3)[0]
    # weights: centre 1, four edges 0.5 each, corners 0 -> total 3
    np.testing.assert_allclose(h, [0.0, 2.0 / 3.0, 1.0 / 3.0])


def test_colour_free_pixels_go_to_value_bins():
    img = np.array([[[255, 0, 0], [128, 128, 128], [0, 0, 0]]], np.uint8)
    b = hs_bins(img)
    assert b[0, 0] < 64  # saturated red: an HS bin
    assert b[0, 1] == 64 + 4  # grey, value 128 -> value bin 4
    assert b[0, 2] == 64  # black


def test_bhattacharyya_bounds():
    p = np.array([0.2, 0.3, 0.5])
    assert np.isclose(bhattacharyya(p, p), 1.0)
    assert bhattacharyya([1.0, 0.0], [0.0, 1.0]) == 0.0


def test_reference_view_matches_itself_best():
    target = EllipsoidTarget()
    views = cube_viewpoints()
    images, centres, shapes = reference_views(target, views)
    model = appearance_model_from_views(images, centres, shapes, views)
    assert model.hs.shape == (26, N_HS) and model.lbp.shape == (26, N_LBP)
    np.testing.assert_allclose(model.hs.sum(1), 1.0)
    for j in (0, 5, 13, 25):
        rho = model.all_views(features_from_rgb(images[j]), centres[j], shapes[j])
        assert int(np.argmax(rho)) == j
        assert np.isclose(rho[j], 1.0)
