"""Ellipsoid projection and quaternions (Kushwaha 2010, Ch. V, Eqs. 65, 72)."""

import numpy as np

from fusetrack.sensors.camera_geometry import PinholeCamera
from fusetrack.sensors.ellipsoid_camera import (
    EllipsoidCamera,
    axis_angle_quaternion,
    ellipse_area,
    ellipsoid_matrix,
    intersect_rays,
    look_at,
    project_ellipsoid,
    quaternion_multiply,
    quaternion_to_rotation,
    rotation_to_quaternion,
    shape_matrix,
)
from fusetrack.world.ellipsoid_scene import EllipsoidTarget, render_target


def _camera(centre=(5.0, 0.0, 1.0), target=(0.0, 0.0, 1.0), size=(160, 120), f=200.0):
    K = np.array([[f, 0, size[0] / 2], [0, f, size[1] / 2], [0, 0, 1.0]])
    c = np.asarray(centre, float)
    return EllipsoidCamera("c", PinholeCamera(K, look_at(c, np.asarray(target)), c, *size))


def test_eq72_quarter_turn_about_z_and_round_trip():
    q = axis_angle_quaternion([0, 0, 1], np.pi / 2)
    np.testing.assert_allclose(quaternion_to_rotation(q) @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    rng = np.random.default_rng(0)
    for _ in range(200):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        R = quaternion_to_rotation(q)
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
        assert np.isclose(np.linalg.det(R), 1.0)
        back = rotation_to_quaternion(R)
        assert min(np.abs(back - q).max(), np.abs(back + q).max()) < 1e-9


def test_quaternion_product_composes_rotations():
    a = axis_angle_quaternion([0, 0, 1], 0.3)
    b = axis_angle_quaternion([1, 0, 0], 1.1)
    np.testing.assert_allclose(
        quaternion_to_rotation(quaternion_multiply(a, b)),
        quaternion_to_rotation(a) @ quaternion_to_rotation(b),
        atol=1e-12,
    )


def test_sphere_projects_to_the_exact_circle_on_the_axis():
    # sphere of radius r at distance D on the optical axis: image radius f r / sqrt(D^2 - r^2)
    cam = _camera()
    r, D, f = 0.3, 5.0, 200.0
    yc, B = cam.ellipse(np.array([0.0, 0.0, 1.0]), [0, 0, 0, 1.0], (r, r, r))
    np.testing.assert_allclose(yc, [80, 60], atol=1e-9)
    radius = f * r / np.sqrt(D**2 - r**2)
    np.testing.assert_allclose(B * radius**2, np.eye(2), atol=1e-9)


def test_projected_ellipse_matches_the_rendered_silhouette():
    cam = _camera(centre=(3.0, -2.0, 2.5))
    target = EllipsoidTarget()
    q = axis_angle_quaternion([0.3, 1.0, 0.2], 0.9)
    x = np.array([0.2, 0.3, 1.1])
    img = np.zeros((120, 160, 3), np.uint8)
    mask = render_target(img, cam, target, x, q)
    yc, B = cam.ellipse(x, q, target.semi_axes)
    vv, uu = np.mgrid[0:120, 0:160]
    d = np.stack([uu - yc[0], vv - yc[1]], -1)
    inside = np.einsum("...i,ij,...j->...", d, B, d) <= 1
    iou = (inside & mask).sum() / (inside | mask).sum()
    assert iou > 0.95
    assert abs(ellipse_area(B) - mask.sum()) / mask.sum() < 0.05


def test_behind_the_camera_gives_nan_and_does_not_participate():
    cam = _camera()
    yc, B = cam.ellipse(np.array([8.0, 0.0, 1.0]), [0, 0, 0, 1.0], (0.3, 0.2, 0.4))
    assert np.all(np.isnan(yc))
    assert not cam.participates(yc, B)


def test_rays_through_projections_meet_at_the_point():
    x = np.array([0.4, -0.3, 1.2])
    cams = [_camera(centre=c) for c in [(5, 0, 1), (0, 5, 2), (-4, -3, 3)]]
    rays = np.array([c.ray(c.project(x)) for c in cams])
    est = intersect_rays(np.array([c.centre for c in cams]), rays)
    np.testing.assert_allclose(est, x, atol=1e-9)


def test_one_shape_for_many_centres_equals_the_shape_repeated_per_centre():
    # the shared-shape path inverts M once; the per-centre path inverts each copy: same bits
    cam = _camera()
    rng = np.random.default_rng(7)
    x = np.array([0.0, 0.0, 1.0]) + 0.3 * rng.normal(size=(50, 3))
    q = axis_angle_quaternion([0.3, -1.0, 0.5], 0.8)
    M = ellipsoid_matrix((0.3, 0.2, 0.5), q)
    yc, B = project_ellipsoid(cam.P, x, M)
    yc_ref, B_ref = project_ellipsoid(cam.P, x, np.repeat(M[None], 50, axis=0))
    np.testing.assert_array_equal(yc, yc_ref)
    np.testing.assert_array_equal(B, B_ref)
    yc_cam, B_cam = cam.ellipse(x, q, (0.3, 0.2, 0.5))
    np.testing.assert_array_equal(yc_cam, yc_ref)
    np.testing.assert_array_equal(B_cam, B_ref)


def test_remembered_shape_matrix_equals_a_fresh_one_and_is_read_only():
    q = axis_angle_quaternion([1.0, 2.0, 0.5], 0.4)
    first = shape_matrix((0.3, 0.2, 0.5), q)
    again = shape_matrix(np.array([0.3, 0.2, 0.5]), q.copy())
    assert again is first
    np.testing.assert_array_equal(first, ellipsoid_matrix((0.3, 0.2, 0.5), q))
    assert not first.flags.writeable
    other = shape_matrix((0.3, 0.2, 0.5), axis_angle_quaternion([1.0, 2.0, 0.5], 0.41))
    assert not np.array_equal(other, first)
    qs = np.stack([q, q])  # several orientations are not remembered, only computed
    np.testing.assert_array_equal(shape_matrix((0.3, 0.2, 0.5), qs)[1], first)
