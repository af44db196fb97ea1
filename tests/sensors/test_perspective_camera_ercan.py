"""The noisy perspective camera (Ercan et al. 2013, Eqs. 1-2, App. B)."""

import math

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.sensors.perspective_camera import CameraArray, PerspectiveCamera


def cam(**kw):
    base = dict(sensor_id="c", position=np.array([2.0, -1.0]), yaw=0.7, fov=math.pi / 2, focal=300.0,
                sigma_theta=0.01, sigma_pos=1.0, sigma_read=2.0)  # fmt: skip
    base.update(kw)
    return PerspectiveCamera(**base)


def test_depth_and_lateral_match_appendix_b():
    c = cam()
    x = np.array([9.0, 6.0])
    d, h = c.as_array().depth_lateral(x[None, :])
    theta = math.pi + c.yaw  # App. B: theta = pi + yaw
    h_paper = math.sin(theta) * (x[0] - 2) - math.cos(theta) * (x[1] + 1)
    d_paper = -math.cos(theta) * (x[0] - 2) - math.sin(theta) * (x[1] + 1)
    assert d[0] == pytest.approx(d_paper)
    assert h[0] == pytest.approx(h_paper)
    assert c.predict(x)[0] == pytest.approx(300 * h_paper / d_paper)


def test_noise_variance_is_first_order_error_propagation():
    """Eq. 2 = (dz/dtheta)^2 s_th^2 + |dz/dc|^2 s_pos^2 + s_read^2, derivatives by finite differences."""
    c = cam()
    x = np.array([8.0, 4.0])

    def z(yaw, pos):
        return cam(yaw=yaw, position=pos).predict(x)[0]

    e = 1e-6
    dz_dyaw = (z(c.yaw + e, c.position) - z(c.yaw - e, c.position)) / (2 * e)
    dz_dc = [
        (z(c.yaw, c.position + e * np.eye(2)[k]) - z(c.yaw, c.position - e * np.eye(2)[k]))
        / (2 * e)
        for k in range(2)
    ]
    expected = dz_dyaw**2 * 0.01**2 + (dz_dc[0] ** 2 + dz_dc[1] ** 2) * 1.0 + 4.0
    assert c.noise_cov(x)[0, 0] == pytest.approx(expected, rel=1e-5)


def test_field_of_view_and_simulate_nan_outside():
    c = cam(position=np.zeros(2), yaw=0.0)
    inside, behind, beside = [10.0, 5.0], [-10.0, 0.0], [1.0, 5.0]
    assert c.in_fov(np.array([inside, behind, beside])).tolist() == [True, False, False]
    z = c.simulate(np.array([inside, behind]), np.random.default_rng(0))
    assert np.isfinite(z[0, 0]) and np.isnan(z[1, 0])


def test_likelihood_is_gaussian_in_the_reading():
    c = cam()
    x = np.array([8.0, 4.0])
    zhat, var = c.predict(x)[0], c.noise_cov(x)[0, 0]
    ll = c.log_likelihood(np.array([zhat + 3.0]), x)
    assert ll == pytest.approx(-0.5 * (9.0 / var + math.log(2 * math.pi * var)))


@pytest.mark.parametrize("field,value", [("fov", 4.0), ("sigma_theta", -1.0), ("position", [1.0])])
def test_bad_camera_configuration(field, value):
    with pytest.raises((ConfigError, ValueError)):
        cam(**{field: value})


def test_camera_array_subset_and_ids():
    arr = CameraArray.from_cameras([cam(sensor_id="a"), cam(sensor_id="b", yaw=2.0)])
    assert arr.subset([1]).ids == ("b",)
    with pytest.raises(ConfigError):
        arr.subset([2])
    with pytest.raises(ConfigError):
        CameraArray.from_cameras([cam(sensor_id="a"), cam(sensor_id="a")])


def test_grid_of_points_takes_the_numba_pass_with_the_same_bits():
    """``depth_lateral`` of points ``(L, 1, 2)`` and ``noise_var_of`` of ``(L, N)`` run as Numba
    passes; they must give NumPy's broadcast formulas bit for bit, including points on a camera
    (d = 0: the depth clamp), behind it (d < 0) and NaN."""
    cams = CameraArray.from_cameras([cam(sensor_id=f"c{i}", yaw=0.5 * i, position=np.array([i, -i / 2]))
                           for i in range(5)])  # fmt: skip
    x = np.random.default_rng(2).uniform(-30.0, 30.0, (400, 2))
    x[:5] = cams.positions
    x[5] = np.nan
    d, h = cams.depth_lateral(x[:, None, :])
    rel = x[:, None, :] - cams.positions
    c, s = np.cos(cams.yaws), np.sin(cams.yaws)
    d_np, h_np = c * rel[..., 0] + s * rel[..., 1], -s * rel[..., 0] + c * rel[..., 1]
    assert np.array_equal(d, d_np, equal_nan=True) and np.array_equal(h, h_np, equal_nan=True)
    dd = np.maximum(d_np, 1e-6)
    r2 = (h_np / dd) ** 2
    f2 = cams.focals**2
    var_np = f2 * (1 + r2) ** 2 * cams.sigma_theta**2 + f2 * (1 + r2) / dd**2 * cams.sigma_pos**2
    var_np = var_np + cams.sigma_read**2
    assert np.array_equal(cams.noise_var_of(d, h), var_np, equal_nan=True)
    assert (d == 0).sum() == 5 and (d < 0).any() and np.isnan(d[5]).all()
    # one point (shape (2,)) takes the NumPy path; noise_var composes the two passes
    assert np.array_equal(cams.depth_lateral(x[7])[0], d[7])
    assert np.array_equal(cams.noise_var(x[:9, None, :]), var_np[:9], equal_nan=True)
