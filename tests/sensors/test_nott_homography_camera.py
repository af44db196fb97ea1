"""Nott 2009 camera geometry: homographies from P, the V8/V4/V2 measurement and its Jacobian."""

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.sensors import HomographyCamera
from fusetrack.sensors.camera_geometry import (
    apply_homography,
    back_project,
    default_camera,
    ground_homography,
    invert_homography,
    plane_homography,
    project_points,
)

P = default_camera().P
STATES = np.array(
    [[3.0, 5.0, 1.75, 0.5, 0.2, 0.1], [6.0, 12.0, 1.6, 0.6, 0.0, 0.0], [1.5, 2.0, 1.8, 0.45, -1, 1]]
)


def test_default_camera_matches_the_spec():
    spec = [
        [500, 309.0963, -82.8221, -414.6413],
        [0, 102.4127, -545.0795, 2419.8416],
        [0, 0.9659, -0.2588, 5.7355],
    ]
    assert np.allclose(P, spec, atol=1e-3)


@pytest.mark.parametrize("height", [0.0, 1.75, 0.9])
def test_plane_homography_equals_direct_projection(height):
    rng = np.random.default_rng(0)
    xy = rng.uniform([1, 1], [8, 14], (50, 2))
    direct = project_points(P, np.column_stack([xy, np.full(50, height)]))
    assert np.abs(apply_homography(plane_homography(P, height), xy) - direct).max() < 1e-9
    assert np.abs(back_project(plane_homography(P, height), direct) - xy).max() < 1e-9


@pytest.mark.parametrize("variant", ["corners", "head_foot", "foot"])
def test_jacobian_matches_finite_differences(variant):
    cam = HomographyCamera("cam", camera_matrix=P, variant=variant)
    J = cam.jacobian(STATES)
    eps = 1e-6
    num = np.zeros_like(J)
    for i in range(6):
        d = np.zeros(6)
        d[i] = eps
        num[..., i] = (cam.predict(STATES + d) - cam.predict(STATES - d)) / (2 * eps)
    assert np.abs(J - num).max() < 1e-6
    assert np.all(J[..., 4:] == 0)  # velocities do not enter the camera


def test_corner_measurement_is_the_bounding_box_of_the_rectangle():
    cam = HomographyCamera("cam", camera_matrix=P, variant="corners")
    x = STATES[0]
    z = cam.predict(x)
    xf, yf, h, w = x[:4]
    corners = np.array(
        [[xf - w / 2, yf, 0], [xf + w / 2, yf, 0], [xf - w / 2, yf, h], [xf + w / 2, yf, h]]
    )
    assert np.allclose(z, project_points(P, corners).ravel())
    # zero-roll camera: bottom corners share a row, u_min left, v_max at the feet
    assert z[1] == pytest.approx(z[3]) and z[0] < z[2] and z[1] > z[5]


def test_fitted_head_homography_makes_height_unobservable():
    cam = HomographyCamera(
        "cam",
        foot_homography=ground_homography(P),
        head_homography=plane_homography(P, 1.75),
        variant="head_foot",
    )
    full = HomographyCamera("cam", camera_matrix=P, variant="head_foot")
    x = STATES[0].copy()
    x[2] = 1.75
    assert np.allclose(cam.predict(x), full.predict(x))
    assert np.all(cam.jacobian(x)[:, 2] == 0) and np.any(full.jacobian(x)[:, 2] != 0)


def test_visibility_and_simulation():
    cam = HomographyCamera("cam", camera_matrix=P, variant="foot")
    x = np.array(
        [[4.5, 6.0, 1.75, 0.5, 0, 0], [4.5, -20.0, 1.75, 0.5, 0, 0], [40.0, 6.0, 1.75, 0.5, 0, 0]]
    )
    assert cam.visible(x).tolist() == [True, False, False]
    z = cam.simulate(x, np.random.default_rng(0))
    assert np.isfinite(z[0]).all() and np.isnan(z[1:]).all()


def test_bad_configuration_names_the_field():
    with pytest.raises(ConfigError, match="variant"):
        HomographyCamera("cam", camera_matrix=P, variant="bogus")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="head_homography"):
        HomographyCamera("cam", foot_homography=ground_homography(P), variant="corners")
    with pytest.raises(ConfigError, match="camera_matrix"):
        HomographyCamera("cam")
    with pytest.raises(ConfigError, match="non-singular"):
        invert_homography(np.ones((3, 3)))
