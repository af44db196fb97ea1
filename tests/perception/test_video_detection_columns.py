"""Camera detection function: column counts, post-filters, mixture fit (Kushwaha 2010, Eqs. 23-27, 35)."""

import numpy as np
import pytest

from fusetrack.core.errors import ShapeError
from fusetrack.perception.video_detection import (
    DetectionPostFilter,
    VideoDetector,
    column_bins,
    detection_from_mask,
    fit_angle_mixture,
)
from fusetrack.sensors.camera_geometry import PinholeCamera
from fusetrack.world.road_video import RoadRenderer, Vehicle


def test_column_counts_into_bins():
    angles = np.linspace(0.5, -0.5, 8)  # 8 columns over a 1 rad field of view, left to right
    bins = column_bins(angles, 1.0, 4)
    assert list(bins) == [3, 3, 2, 2, 1, 1, 0, 0]
    mask = np.zeros((5, 8), np.uint8)
    mask[:3, 0] = 255  # 3 pixels in column 0 -> bin 3
    mask[:, 7] = 1  # 5 pixels in column 7 -> bin 0
    assert list(detection_from_mask(mask, bins, 4)) == [5.0, 0.0, 0.0, 3.0]
    with pytest.raises(ShapeError):
        detection_from_mask(mask[:, :7], bins, 4)


def test_post_filter_equations():
    pf = DetectionPostFilter(alpha=0.5, taps=1)
    lam1 = np.array([4.0, 0.0, 2.0])
    assert np.allclose(pf(lam1), lam1)  # no background yet
    assert np.allclose(pf.background, 0.5 * lam1)  # Eq. 25
    lam2 = np.array([4.0, 6.0, 0.0])
    assert np.allclose(pf(lam2), [2.0, 6.0, 0.0])  # Eq. 26: minus b_{t-1}, clipped at 0
    blur = DetectionPostFilter(alpha=0.5, taps=7)
    spike = np.zeros(21)
    spike[10] = 7.0
    assert np.allclose(blur(spike)[7:14], 1.0)  # Eq. 27: 7-tap box


def test_mixture_fit_two_blobs():
    a = np.linspace(-0.5, 0.5, 160)
    lam = 100 * np.exp(-0.5 * ((a + 0.2) / 0.02) ** 2) + 50 * np.exp(
        -0.5 * ((a - 0.25) / 0.03) ** 2
    )
    mix = fit_angle_mixture(lam, a)
    assert mix.means.size == 2
    assert mix.means == pytest.approx([-0.2, 0.25], abs=0.005)
    assert mix.sigmas == pytest.approx([0.02, 0.03], rel=0.2)
    assert mix.weights == pytest.approx([0.57, 0.43], abs=0.05)
    assert fit_angle_mixture(np.zeros(160), a).empty


def test_rendered_vehicle_bearing_is_recovered():
    rng = np.random.default_rng(0)
    yaw = np.arctan2(8.0, 17.5)
    cam = PinholeCamera.from_pose((0.0, 2.0, 3.0), yaw)
    renderer = RoadRenderer(cam, rng, clutter=0.0)
    det = VideoDetector(cam.column_angles(), cam.hfov)
    for _ in range(15):
        det.learn_background(renderer.render([]))
    for x in (9.5, 14.5, 22.0):
        _, mix = det.process(renderer.render([Vehicle((x, 8.5), 0.0)]))
        true = np.arctan2(8.5 - 2.0, x) - yaw
        best = mix.means[np.argmax(mix.weights)]
        assert abs(best - true) < np.deg2rad(2.0)
