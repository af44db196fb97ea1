"""PF-DWT denoiser (Zhai 2007, Sec. 6.2) on a small synthetic image."""

import numpy as np
import pytest
from scipy.special import voigt_profile

from fusetrack.perception.pf_dwt import (
    RasterParticleFilter,
    _log_lik,
    add_mixed_noise,
    isnr,
    ti_threshold,
    voigt_log_table,
    wavelet_threshold,
)


def _image(n=48):
    i, j = np.mgrid[0:n, 0:n]
    return 100.0 + 60.0 * np.sin(i / 7.0) * np.cos(j / 9.0) + 40.0 * (j > n // 2)


def test_isnr_of_identity_is_zero_and_of_truth_is_infinite_direction():
    img = _image()
    noisy = img + 5.0
    assert isnr(img, noisy, noisy) == pytest.approx(0.0)
    assert isnr(img, noisy, img + 2.5) == pytest.approx(10 * np.log10(4.0))


def test_voigt_table_matches_scipy_and_has_cauchy_tails():
    table, x0, dx = voigt_log_table(np.sqrt(200.0), 5.0)
    for r in (-37.3, 0.0, 12.6, 250.0):
        assert _log_lik(r, table, x0, dx, 5.0) == pytest.approx(
            np.log(voigt_profile(r, np.sqrt(200.0), 5.0)), abs=2e-3
        )
    far = 1e5
    assert _log_lik(far, table, x0, dx, 5.0) == pytest.approx(
        np.log(5.0 / np.pi / far**2), rel=1e-6
    )


def test_pf_removes_impulsive_noise_and_thresholding_helps():
    img = _image()
    noisy = add_mixed_noise(img, np.random.default_rng(3))
    pf = RasterParticleFilter(n_particles=60)(noisy, seed=1)
    assert np.all(np.isfinite(pf))
    gain_pf = isnr(img, noisy, pf)
    assert gain_pf > 3.0  # the heavy-tailed noise is mostly gone
    resid = pf - img
    noise = noisy - img
    kurt = lambda e: np.mean(e**4) / np.mean(e**2) ** 2 - 3.0  # noqa: E731
    assert kurt(resid) < kurt(noise)
    assert isnr(img, noisy, ti_threshold(pf, "hard", level=2, shifts=2)) > gain_pf - 0.5


def test_wavelet_threshold_zero_threshold_is_identity():
    img = _image(32)
    np.testing.assert_allclose(
        wavelet_threshold(img, "hard", level=2, threshold=0.0), img, atol=1e-9
    )


def test_raster_posterior_mean_of_one_pixel_matches_quadrature_by_hand():
    """A 2 x 2 image has one filtered pixel: its prior mean is h . (median-3x3 neighbours)
    and its estimate the posterior mean of N(m, q1) times the Voigt likelihood, by scipy quad."""
    from scipy import integrate

    from fusetrack.perception import raster_posterior_mean

    pf = RasterParticleFilter(q1=1000.0)
    y = np.array([[100.0, 120.0], [90.0, 300.0]])  # an outlier at (1, 1)
    got = raster_posterior_mean(pf, y)
    m = pf.h[0] * 100.0 + pf.h[1] * 120.0 + pf.h[2] * 100.0  # median3: [[100, 120], [100, 120]]

    def f(x, p):
        return x**p * np.exp(-0.5 * (x - m) ** 2 / 1000.0) * voigt_profile(300.0 - x, 200**0.5, 5)

    lim = (m - 400.0, m + 400.0)
    want = (
        integrate.quad(f, *lim, args=(1,), points=[300.0], limit=200)[0]
        / integrate.quad(f, *lim, args=(0,), points=[300.0], limit=200)[0]
    )
    assert got[1, 1] == pytest.approx(want, abs=1e-4)
    assert m < got[1, 1] < m + 15.0  # the outlier barely moves it: the Cauchy tail explains it
    np.testing.assert_array_equal(got[0], [100.0, 120.0])  # first row: the 3 x 3 median


def test_particle_filter_tends_to_the_exact_posterior_mean():
    """The PF stage at 100 particles is further from the exact recursion than at 3000."""
    from fusetrack.perception import raster_posterior_mean

    img = _image(32)
    noisy = add_mixed_noise(img, np.random.default_rng(5))
    exact = raster_posterior_mean(RasterParticleFilter(), noisy)
    gap = [
        np.sqrt(np.mean((RasterParticleFilter(n_particles=n)(noisy, seed=2) - exact) ** 2))
        for n in (100, 3000)
    ]
    assert gap[1] < 0.5 * gap[0] and gap[1] < 1.0, gap


def test_raster_posterior_mean_rejects_bad_input():
    from fusetrack.core import ConfigError, ShapeError
    from fusetrack.perception import raster_posterior_mean

    with pytest.raises(ShapeError, match="noisy"):
        raster_posterior_mean(RasterParticleFilter(), np.zeros(5))
    with pytest.raises(ConfigError, match="nodes"):
        raster_posterior_mean(RasterParticleFilter(), np.zeros((4, 4)), nodes=2)
