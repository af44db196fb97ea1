"""The practitioner's denoisers that zhai2007-denoising compares with PF-DWT (issue 5)."""

import numpy as np

from fusetrack.experiments.zhai2007.denoising import practitioner_denoisers
from fusetrack.perception.pf_dwt import isnr


def test_every_denoiser_improves_a_noisy_smooth_image_on_the_grey_scale():
    yy, xx = np.mgrid[0:64, 0:64]
    clean = 128.0 + 60.0 * np.sin(xx / 9.0) * np.cos(yy / 11.0)
    clean[20:40, 20:40] = 230.0  # an edge
    noisy = clean + 15.0 * np.random.default_rng(0).standard_normal(clean.shape)
    for name, f in practitioner_denoisers().items():
        out = f(noisy)
        assert out.shape == clean.shape and np.all(np.isfinite(out)), name
        # same grey scale as the input (a [0, 1] result would lose ~40 dB)
        assert abs(out.mean() - clean.mean()) < 5.0, name
        assert isnr(clean, noisy, out) > 1.0, name
