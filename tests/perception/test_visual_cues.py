"""Visual cues of the multi-cue tracker (Zhai 2007, Eqs. 85-89) and the aid-window front end."""

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.perception.visual_cues import (
    MultiCueFrontEnd,
    correlation_map,
    hsi_histogram,
    kl_divergence,
    kld_map,
    rgb_to_hsi,
)


def test_hsi_of_primaries_and_grey():
    img = np.array(
        [
            [
                [255, 0, 0],
                [255, 255, 0],
                [0, 255, 0],
                [0, 255, 255],
                [0, 0, 255],
                [255, 0, 255],
                [90, 90, 90],
            ]
        ],
        np.uint8,
    )
    h, s, i = rgb_to_hsi(img)
    np.testing.assert_allclose(h[0, :6], [0, 60, 120, 180, 240, 300], atol=1e-6)
    np.testing.assert_allclose(s[0], [1, 1, 1, 1, 1, 1, 0], atol=1e-12)
    np.testing.assert_allclose(i[0], [1 / 3, 2 / 3, 1 / 3, 2 / 3, 1 / 3, 2 / 3, 90 / 255])


def test_kl_divergence_by_hand():
    d = kl_divergence(np.array([0.5, 0.5]), np.array([0.25, 0.75]), eps=0.0)
    assert float(d) == pytest.approx(0.5 * np.log(2) + 0.5 * np.log(2 / 3))
    assert float(kl_divergence(np.array([0.3, 0.7]), np.array([0.3, 0.7]))) == pytest.approx(
        0, abs=1e-12
    )


def test_kld_map_equals_brute_force():
    rng = np.random.default_rng(0)
    bins = rng.integers(0, 20, (15, 13))
    target = np.bincount(rng.integers(0, 20, 30), minlength=20) / 30
    m = kld_map(bins, target, (5, 3))
    assert m.shape == (11, 11)
    for i, j in [(0, 0), (4, 7), (10, 10)]:
        q = np.bincount(bins[i : i + 5, j : j + 3].ravel(), minlength=20) / 15
        occ = target > 0
        p = target[occ] + 1e-6
        assert m[i, j] == pytest.approx(np.sum(p * np.log(p / (q[occ] + 1e-6))))


def test_template_half_life():
    fe = MultiCueFrontEnd(half_life=5.0)
    a = fe.alpha
    assert (1 - a) ** 5 == pytest.approx(0.5)  # a patch's weight halves in n_h frames (Eq. 86)
    assert MultiCueFrontEnd(half_life=None).alpha == 1.0


def _scene(shift, bright=False):
    rng = np.random.default_rng(3)
    bg = rng.integers(60, 120, (90, 110, 3)).astype(np.uint8)
    patch = rng.integers(0, 255, (15, 11, 3)).astype(np.uint8)
    patch[..., 0] = 230
    img = bg.copy()
    r, c = 40 + shift[1], 50 + shift[0]
    img[r - 7 : r + 8, c - 5 : c + 6] = patch
    if bright:
        img[r - 18 : r - 8, c + 6 : c + 16] = 255
    return img


def test_each_cue_finds_the_target():
    fe = MultiCueFrontEnd((15, 11), half_window=10, correlation="normalised")
    fe.adapt(_scene((0, 0)), np.array([50.0, 40.0]))
    zs = fe.measure(_scene((4, -3)), np.array([50.0, 40.0]))
    for z in zs:
        np.testing.assert_allclose(z, [54, 37], atol=1.0)


def test_plain_correlation_prefers_bright_patches():
    img0 = _scene((0, 0))
    plain = MultiCueFrontEnd((15, 11), 10, ("grey",), correlation="plain")
    ncc = MultiCueFrontEnd((15, 11), 10, ("grey",), correlation="normalised")
    for fe in (plain, ncc):
        fe.adapt(img0, np.array([50.0, 40.0]))
    img = _scene((2, 1), bright=True)
    z_plain = plain.measure(img, np.array([50.0, 40.0]))[0]
    z_ncc = ncc.measure(img, np.array([50.0, 40.0]))[0]
    np.testing.assert_allclose(z_ncc, [52, 41], atol=1.0)
    assert np.hypot(*(z_plain - [52, 41])) > 3


def test_correlation_is_eq_85():
    region = np.arange(20.0).reshape(4, 5)
    t = np.array([[1.0, 0.0], [0.0, 2.0]])
    out = correlation_map(region, t)
    assert out[1, 2] == pytest.approx((region[1, 2] + 2 * region[2, 3]) / 4)


def test_bad_configuration():
    with pytest.raises(ConfigError, match="cues"):
        MultiCueFrontEnd(cues=("smell",))
    with pytest.raises(ConfigError, match="box"):
        MultiCueFrontEnd(box=(10, 11))
    assert hsi_histogram(np.zeros((3, 3, 3), np.uint8)).sum() == pytest.approx(1.0)
