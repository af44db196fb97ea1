"""The textured box target (Kushwaha 2010 LCR, spec A-V-18): slab ray-casting against hand-computed
projections."""

import cv2
import numpy as np
import pytest

from fusetrack.core import ConfigError
from fusetrack.sensors import (
    EllipsoidCamera,
    PinholeCamera,
    axis_angle_quaternion,
    look_at,
    quaternion_to_rotation,
)
from fusetrack.world import BoxTarget, render_box
from fusetrack.world.box_target import DARK_SQUARE, FACE_COLOURS

IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


def _camera(centre, target, f=100.0, size=(100, 100)):
    K = np.array([[f, 0, size[0] / 2], [0, f, size[1] / 2], [0, 0, 1.0]])
    c = np.asarray(centre, float)
    return EllipsoidCamera("c", PinholeCamera(K, look_at(c, np.asarray(target, float)), c, *size))


def test_cube_seen_from_above_is_the_hand_computed_square_of_its_top_face():
    # camera 5 m above the origin, f = 100 px, principal point (50, 50); a unit cube at
    # (0.03, 0.03, 0): its top face (depth 4.5 m) spans x, y in [-0.47, 0.53] m, i.e. pixels
    # 50 + 100 / 4.5 * [-0.47, 0.53] = [39.56, 61.78] -> 40..61, 22 per side; the side faces are
    # hidden behind it (the bottom corners project inside)
    cam = _camera((0.0, 0.0, 5.0), (0.0, 0.0, 0.0))
    box = BoxTarget((0.5, 0.5, 0.5), checker=0.1)
    img = np.zeros((100, 100, 3), np.uint8)
    mask = render_box(img, cam, box, (0.03, 0.03, 0.0), IDENTITY)
    rows, cols = np.nonzero(mask)
    # columns grow along +x; rows along -y (the camera's "down" is -y): 50 - 22.22 y for
    # y in [-0.47, 0.53] -> [38.22, 60.44] -> rows 39..60
    assert mask.sum() == 22 * 22
    assert (cols.min(), cols.max()) == (40, 61)
    assert (rows.min(), rows.max()) == (39, 60)
    # the centre ray hits the top face (+z, cyan) at body (-0.03, -0.03): checker cells
    # (-1, -1), even parity -> the face colour, unshaded (the ray is along the normal)
    np.testing.assert_array_equal(img[50, 50], FACE_COLOURS[5].astype(np.uint8))
    # one pixel right: body x = 0.045 - 0.03 = 0.015 -> cell (0, -1), odd parity -> dark
    np.testing.assert_allclose(img[50, 51], FACE_COLOURS[5] * DARK_SQUARE, atol=1.0)
    assert not img[~mask].any()  # nothing drawn outside the mask


def test_rotated_box_fills_the_convex_hull_of_its_projected_corners():
    cam = _camera((6.0, -4.0, 2.8), (0.0, 0.0, 1.0), f=200.0, size=(160, 120))
    box = BoxTarget((0.3, 0.22, 0.18))
    x = np.array([0.2, 0.3, 1.1])
    q = axis_angle_quaternion([0.3, 1.0, 0.2], 0.9)
    img = np.zeros((120, 160, 3), np.uint8)
    mask = render_box(img, cam, box, x, q)
    uv = cam.project(x + box.corners() @ quaternion_to_rotation(q).T)
    hull = cv2.convexHull(uv.astype(np.float32))
    vv, uu = np.mgrid[0:120, 0:160]
    inside = np.array(
        [
            cv2.pointPolygonTest(hull, (float(u), float(v)), False) >= 0
            for u, v in zip(uu.ravel(), vv.ravel())
        ]
    ).reshape(mask.shape)
    iou = (inside & mask).sum() / (inside | mask).sum()
    assert mask.sum() > 200 and iou > 0.95, iou
    # every drawn pixel is a face colour times a brightness in [0.55 x dark square, 1], and at
    # most three faces (those turned towards the camera) are drawn
    px = img[mask].astype(float)
    scale = px @ FACE_COLOURS.T / np.sum(FACE_COLOURS**2, axis=1)  # least-squares brightness
    resid = np.linalg.norm(px[:, None, :] - scale[..., None] * FACE_COLOURS, axis=-1)
    face = resid.argmin(axis=1)
    best = scale[np.arange(len(px)), face]
    assert resid.min(axis=1).max() < 2.0
    assert best.min() > 0.55 * DARK_SQUARE - 0.01 and best.max() < 1.01
    assert 2 <= len(set(face)) <= 3


def test_box_behind_the_camera_or_out_of_view_draws_nothing():
    cam = _camera((0.0, 0.0, 5.0), (0.0, 0.0, 0.0))
    img = np.zeros((100, 100, 3), np.uint8)
    box = BoxTarget()
    assert not render_box(img, cam, box, (0.0, 0.0, 8.0), IDENTITY).any()  # behind
    assert not render_box(img, cam, box, (40.0, 0.0, 0.0), IDENTITY).any()  # far to the side
    assert not img.any()


def test_model_ellipsoid_has_the_box_volume_and_bad_sizes_are_refused():
    box = BoxTarget((0.3, 0.2, 0.1))
    a, b, c = box.semi_axes
    assert 4.0 / 3.0 * np.pi * a * b * c == pytest.approx(8 * 0.3 * 0.2 * 0.1)
    assert a / b == pytest.approx(1.5)
    with pytest.raises(ConfigError, match="half_sizes"):
        BoxTarget((0.3, -0.2, 0.1))
