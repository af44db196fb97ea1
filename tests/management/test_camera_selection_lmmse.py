"""The LMMSE camera-selection metric of Ercan et al. 2013 (Eqs. 10-16) and the selection rules."""

import itertools

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.management.camera_selection import (
    SelectionMoments,
    brute_force_selection,
    closest_selection,
    fixed_selection,
    greedy_selection,
    information_form_mse,
    random_selection,
    selection_moments,
    subset_mse,
)
from fusetrack.sensors.perspective_camera import ring_of_cameras
from fusetrack.world.occlusion import OccluderPriors
from fusetrack.world.room import square_room

NOISE = {"sigma_theta": 0.01, "sigma_pos": 1.0, "sigma_read": 2.0}


def setup(n_particles=400, spread=3.0, centre=(50.0, 50.0), seed=0, occluders=10):
    rng = np.random.default_rng(seed)
    room = square_room(100.0)
    pos = [(0, 0), (50, 0), (100, 0), (100, 50), (100, 100), (50, 100), (0, 100), (0, 50)]
    cams = ring_of_cameras(pos, [45, 90, 135, 180, 225, 270, 315, 0], 90.0, **NOISE)
    x = np.asarray(centre) + spread * rng.standard_normal((n_particles, 2))
    w = rng.random(n_particles)
    pri = OccluderPriors(
        rng.uniform(10, 90, (occluders, 2)), np.broadcast_to(9 * np.eye(2), (occluders, 2, 2))
    )
    return cams, room, x, w / w.sum(), pri


def test_weak_perspective_mse_equals_information_form_when_always_seen():
    cams, room, x, w, _ = setup()
    mom = selection_moments(cams, room, x, w, None, 3.33, "none", ("weak",))
    assert np.allclose(mom.p_visible, 1.0)  # no occluders, every particle in every view
    sel = np.array([0, 3, 6])
    d_bar, _ = cams.depth_lateral(mom.mu_x[None, :])
    var = (cams.sigma_theta**2 + cams.sigma_read**2 / cams.focals**2) * d_bar**2 + cams.sigma_pos**2
    expected = information_form_mse(mom.sigma_x, cams.normals[sel], var[sel])
    assert subset_mse(mom, sel, "weak")[0] == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("model", ["perspective", "weak"])
def test_mse_never_increases_when_a_camera_is_added(model):
    cams, room, x, w, pri = setup(spread=15.0)
    mom = selection_moments(cams, room, x, w, pri, 3.33, "gaussian")
    rng = np.random.default_rng(1)
    for _ in range(40):
        k = int(rng.integers(1, 7))
        s = rng.choice(8, size=k, replace=False)
        extra = next(i for i in range(8) if i not in s)
        a = subset_mse(mom, s, model)[0]
        b = subset_mse(mom, np.append(s, extra), model)[0]
        assert b <= a + 1e-9 * max(1.0, a)
        assert 0 <= b <= np.trace(mom.sigma_x) + 1e-9


def test_perspective_close_to_weak_for_a_tight_prior_far_from_cameras():
    cams, room, x, w, _ = setup(spread=0.5)
    mom = selection_moments(cams, room, x, w, None, 3.33, "none")
    for s in ([0], [0, 6], [1, 3, 5]):
        p, q = subset_mse(mom, s, "perspective")[0], subset_mse(mom, s, "weak")[0]
        assert p == pytest.approx(q, rel=0.05)


def test_greedy_equals_brute_force_where_it_must_and_is_close_otherwise():
    cams, room, x, w, pri = setup(spread=12.0, seed=3)
    mom = selection_moments(cams, room, x, w, pri, 3.33, "gaussian")
    for model in ("perspective", "weak"):
        assert greedy_selection(mom, 1, model) == brute_force_selection(mom, 1, model)
        assert greedy_selection(mom, 8, model) == list(range(8))
        for k in (2, 3, 4):
            g, b = greedy_selection(mom, k, model), brute_force_selection(mom, k, model)
            eg, eb = subset_mse(mom, np.array([g, b]), model)
            assert eb <= eg + 1e-12
            assert eg <= 1.2 * eb
            best = min(subset_mse(mom, np.array(list(itertools.combinations(range(8), k))), model))
            assert eb == pytest.approx(best)


def test_visibility_probabilities_are_probabilities():
    cams, room, x, w, pri = setup(spread=20.0, occluders=30)
    mom = selection_moments(cams, room, x, w, pri, 3.33, "gaussian")
    assert np.all((mom.p_visible >= 0) & (mom.p_visible <= 1))
    assert np.allclose(mom.p_both, mom.p_both.T)
    assert np.allclose(np.diag(mom.p_both), mom.p_visible)
    assert np.all(mom.p_both <= np.minimum.outer(mom.p_visible, mom.p_visible) + 1e-12)


def test_singular_measurement_covariance_is_handled():
    """A camera that sees no particle has a zero row: pseudo-inverse, no NaN, no gain."""
    mom = SelectionMoments(
        np.zeros(2), np.eye(2), np.array([1.0, 0.0]), np.array([[1.0, 0.0], [0.0, 0.0]]),
        {"weak": np.array([[1.0, 0.0], [0.0, 0.0]])}, {"weak": np.array([[2.0, 0.0], [0.0, 0.0]])},
    )  # fmt: skip
    e = subset_mse(mom, np.array([[0, 1], [0, 0]])[:1], "weak")
    assert np.isfinite(e).all() and e[0] == pytest.approx(2.0 - 0.5)


def test_heuristics_and_bad_k():
    cams, *_ = setup()
    assert fixed_selection([0, 6, 4, 2], 2) == [0, 6]
    assert closest_selection(cams.positions, np.array([99.0, 1.0]), 1) == [2]
    r = random_selection(8, 3, np.random.default_rng(0))
    assert len(set(r)) == 3 and all(0 <= i < 8 for i in r)
    cams, room, x, w, _ = setup()
    mom = selection_moments(cams, room, x, w, None, 3.33, "none")
    for bad in (0, 9):
        with pytest.raises(ConfigError, match="k="):
            greedy_selection(mom, bad)
        with pytest.raises(ConfigError, match="k="):
            brute_force_selection(mom, bad)


def test_bad_cloud_is_refused_naming_the_field():
    """A NaN particle, a negative or NaN weight and weights summing to 0 are clear errors, not
    NaN moments."""
    cams, room, x, w, pri = setup()
    ok = selection_moments(cams, room, x, w, pri, 3.33, "gaussian")
    assert np.all(np.isfinite(ok.cov_z["perspective"]))
    bad = x.copy()
    bad[7, 0] = np.nan
    with pytest.raises(ConfigError, match=r"x\[7\]=\[nan, .*\] is invalid"):
        selection_moments(cams, room, bad, w, pri, 3.33, "gaussian")
    for weights in (np.r_[-1.0, w[1:]], np.r_[np.nan, w[1:]], np.zeros_like(w)):
        with pytest.raises(ConfigError, match="finite weights >= 0 with a positive sum"):
            selection_moments(cams, room, x, weights, pri, 3.33, "gaussian")
