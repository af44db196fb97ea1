"""subset_mse's Cholesky path against the pseudo-inverse for every subset (Ercan et al. 2013,
Sec. 5: MSE(S) = Tr(Sigma_x - Sigma_Zx' Sigma_Z^+ Sigma_Zx)), including cameras that see nothing
and subsets whose Sigma_Z is singular, where the pseudo-inverse must take over."""

import itertools

import numpy as np
import pytest

from fusetrack.core import ConfigError
from fusetrack.management import SelectionMoments, subset_mse
from fusetrack.management.camera_selection import _subset_gain_kernel, _subset_mse_pinv


def _moments(seed: int, n: int = 9, blind: tuple[int, ...] = ()) -> SelectionMoments:
    """Weak-perspective-shaped moments (Eqs. 15-16) with random visibility; ``blind`` cameras see
    no particle (P{eta} = 0: zero rows)."""
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, 2))
    sigma_x = np.array([[40.0, 6.0], [6.0, 25.0]])
    p1 = rng.uniform(0.2, 1.0, n)
    p1[list(blind)] = 0.0
    p2 = np.minimum.outer(p1, p1) * rng.uniform(0.6, 1.0, (n, n))
    p2 = (p2 + p2.T) / 2
    np.fill_diagonal(p2, p1)
    cz = p2 * (a @ sigma_x @ a.T + np.diag(rng.uniform(0.5, 5.0, n)))
    czx = p1[:, None] * (a @ sigma_x)
    return SelectionMoments(np.zeros(2), sigma_x, p1, p2, {"weak": czx}, {"weak": cz})


def _all_subsets(n: int, k: int) -> np.ndarray:
    return np.array(list(itertools.combinations(range(n), k)), dtype=np.intp)


@pytest.mark.parametrize("blind", [(), (2,), (0, 5, 8)])
def test_every_subset_matches_the_pseudo_inverse(blind):
    mom = _moments(1, blind=blind)
    trace = float(np.trace(mom.sigma_x))
    for k in (1, 3, 5):
        s = _all_subsets(9, k)
        got = subset_mse(mom, s, "weak")
        want = _subset_mse_pinv(mom.cov_zx["weak"], mom.cov_z["weak"], s, trace)
        np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-10 * trace)
        solved = ~np.isnan(_subset_gain_kernel(mom.cov_zx["weak"], mom.cov_z["weak"], s, 1e6))
        assert solved.all()  # blind cameras are left out exactly, not sent to the pinv


def test_one_camera_by_hand():
    mom = _moments(2)
    czx, cz = mom.cov_zx["weak"][3], mom.cov_z["weak"][3, 3]
    expected = np.trace(mom.sigma_x) - czx @ czx / cz
    assert subset_mse(mom, np.array([3]), "weak")[0] == pytest.approx(expected, rel=1e-13)


def test_singular_subsets_fall_back_to_the_pseudo_inverse():
    mom = _moments(3)
    s = np.array([[0, 0], [4, 4], [1, 2]], dtype=np.intp)  # a camera twice: Sigma_Z singular
    gains = _subset_gain_kernel(mom.cov_zx["weak"], mom.cov_z["weak"], s, 1e6)
    assert np.isnan(gains[:2]).all() and np.isfinite(gains[2])
    got = subset_mse(mom, s, "weak")
    np.testing.assert_allclose(got[:2], subset_mse(mom, s[:2, :1], "weak"), rtol=1e-9)


def test_a_camera_index_outside_the_network_is_refused():
    with pytest.raises(ConfigError, match="subsets"):
        subset_mse(_moments(4), np.array([[0, 9]]), "weak")
