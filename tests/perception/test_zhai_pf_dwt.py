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
