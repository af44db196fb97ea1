"""Blobs, bottom points, occlusion rules and homography fitting (Nott 2009, Secs. 4.4-4.5, 5.2.2)."""

import numpy as np
import pytest

from fusetrack.perception.video import (
    DegenerateGeometryError,
    detect_occlusion,
    dlt,
    find_blobs,
    fit_homography,
    largest_blob,
    reprojection_errors,
)
from fusetrack.sensors.camera_geometry import apply_homography, default_camera, ground_homography


def _person(mask, u, v_top, v_bot, half=8):
    mask[v_top : v_bot + 1, u - half : u + half + 1] = True


def test_fragmented_silhouette_still_gives_the_foot():
    m = np.zeros((120, 160), bool)
    _person(m, 60, 20, 100)
    m[55:57, 40:80] = False  # a gap splits the body in two
    m[40:52, 78:84] = True  # a hand, separate
    frags = find_blobs(m, min_area=20, merge_gap=None)
    assert len(frags) >= 2
    big = largest_blob(frags)
    assert abs(big.foot[0] - 60) < 3 and abs(big.foot[1] - 100) < 3
    merged = find_blobs(m, min_area=20)
    assert len(merged) == 1 and merged[0].box[1] == 20 and merged[0].box[3] == 100
    assert merged[0].head == pytest.approx((60.0, 20.0))


def test_occlusion_rules():
    m = np.zeros((120, 200), bool)
    _person(m, 50, 20, 100)
    _person(m, 150, 25, 95)
    two = find_blobs(m)
    assert len(two) == 2 and not detect_occlusion(two, 2).occluded
    m2 = np.zeros((120, 200), bool)
    _person(m2, 100, 20, 100, half=14)  # two people merged into one blob
    dec = detect_occlusion(find_blobs(m2), 2)
    assert dec.occluded and dec.reason == "fewer blobs than tags"
    # gating: the only blob is far from where the subject should be (walked behind a wall)
    dec = detect_occlusion(two[:1], 1, predicted_foot=(150, 95), innovation_cov=np.eye(2) * 4)
    assert dec.occluded and "gate" in dec.reason
    # height rule: the gated blob is far shorter than the predicted person
    m3 = np.zeros((120, 200), bool)
    _person(m3, 50, 80, 100)
    dec = detect_occlusion(
        find_blobs(m3),
        1,
        predicted_foot=(50, 100),
        innovation_cov=np.eye(2) * 4,
        predicted_height=80,
    )
    assert dec.occluded and "shorter" in dec.reason


def test_dlt_recovers_a_known_homography_and_improves_with_more_points():
    H = ground_homography(default_camera().P)
    H = H / H[2, 2]
    rng = np.random.default_rng(1)
    w = rng.uniform([1, 1], [8, 14], (6, 2))
    est, svr = dlt(w, apply_homography(H, w))
    assert np.abs(est - H).max() / np.abs(H).max() < 1e-8 and svr < 1e-6
    grid = np.array([[x, y] for x in range(1, 9) for y in range(1, 15)], float)
    errs = []
    for n in (8, 200):
        e = []
        for s in range(10):
            r = np.random.default_rng(s)
            ww = r.uniform([1, 1], [8, 14], (n, 2))
            est = fit_homography(ww, apply_homography(H, ww) + r.standard_normal((n, 2))).H
            e.append(np.median(reprojection_errors(est, grid, apply_homography(H, grid))))
        errs.append(np.mean(e))
    assert errs[1] < errs[0] / 2


def test_a_straight_walk_is_refused_and_a_diverse_one_accepted():
    H = ground_homography(default_camera().P)
    rng = np.random.default_rng(2)
    s = np.linspace(0, 1, 60)
    line = np.column_stack([1.5 + 6.5 * s, 2.0 + 4.3 * s]) + 0.02 * rng.standard_normal((60, 2))
    with pytest.raises(DegenerateGeometryError, match="spread"):
        fit_homography(line, apply_homography(H, line))
    wide = rng.uniform([1, 1], [8, 14], (60, 2))
    assert fit_homography(wide, apply_homography(H, wide)).rms_px < 1e-6
    with pytest.raises(DegenerateGeometryError, match=">= 4"):
        fit_homography(wide[:3], apply_homography(H, wide[:3]))
