"""The practitioner's denoisers that zhai2007-denoising compares with PF-DWT (issue 5)."""

import numpy as np
import pandas as pd

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


def test_denoising_best_possible_section_and_claims():
    """The exact posterior mean's ISNR beside the paper's: a paper ISNR more than 3 s.e. above
    it is impossible (higher is better), one below it possible; the section shows the table."""
    from fusetrack.experiments.zhai2007 import denoising as dn

    def rows(method, values, image="cameraman"):
        return pd.DataFrame(
            {"image": image, "q1": 1000.0, "method": method, "isnr_db": values, "clip": True}
        )

    ours = pd.concat(
        [rows(m, [4.0, 4.2], im) for im in ("lena", "cameraman")
         for m in ("PF", "PF + TI hard", "PF + TI soft", "median 3x3")]
    )  # fmt: skip
    best = pd.concat(
        [rows(dn.best_method(m), v, im) for im in ("lena", "cameraman")
         for m, v in (("PF", [4.0, 4.2]), ("PF + TI hard", [5.2, 5.4]), ("PF + TI soft", [3.0, 3.2]))]
    )  # fmt: skip
    claims, text = dn.best_possible_section(ours, best)
    by_id = {c.id: c for c in claims}
    assert set(by_id) == {f"BP_{i}_{m.replace(' ', '_')}" for i, m in dn.PAPER}
    assert by_id["BP_lena_PF"].holds  # 3.20 below 4.1
    assert by_id["BP_cameraman_PF_+_TI_hard"].holds  # 5.47 within 3 s.e. (0.3) of 5.3
    assert not by_id["BP_lena_PF_+_TI_hard"].holds  # 6.71 far above 5.3: impossible
    assert "impossible" in by_id["BP_cameraman_PF_+_TI_soft"].ours  # 3.50 above 3.1 + 0.3
    assert "### The best possible on the printed model" in text
    assert "cameraman: trivial, median 3x3" in text and "exact posterior mean" in text
