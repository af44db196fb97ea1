"""The joint-expectation perspective metric (spec §8 item 13's variant of Ercan et al. 2013,
Eqs. 11-13): it equals the printed metric when visibility does not depend on the particle, and
its per-particle visibilities sum to the printed P{eta}."""

import numpy as np
import pytest

from fusetrack.management.camera_selection import (
    selection_moments,
    subset_mse,
    visibility_per_particle,
    visibility_probabilities,
)
from fusetrack.sensors.perspective_camera import ring_of_cameras
from fusetrack.world.occlusion import OccluderPriors
from fusetrack.world.room import square_room

NOISE = {"sigma_theta": 0.01, "sigma_pos": 1.0, "sigma_read": 2.0}
MODELS = ("perspective", "perspective-joint")


def setup(spread, seed=0, occluders=10):
    rng = np.random.default_rng(seed)
    room = square_room(100.0)
    pos = [(0, 0), (50, 0), (100, 0), (100, 50), (100, 100), (50, 100), (0, 100), (0, 50)]
    cams = ring_of_cameras(pos, [45, 90, 135, 180, 225, 270, 315, 0], 90.0, **NOISE)
    x = np.array([50.0, 50.0]) + spread * rng.standard_normal((300, 2))
    w = rng.random(300)
    pri = OccluderPriors(
        rng.uniform(10, 90, (occluders, 2)), np.broadcast_to(9 * np.eye(2), (occluders, 2, 2))
    )
    return cams, room, x, w / w.sum(), pri


def test_joint_equals_printed_when_every_particle_is_seen():
    cams, room, x, w, _ = setup(spread=3.0)
    mom = selection_moments(cams, room, x, w, None, 3.33, "none", MODELS)
    assert np.allclose(mom.p_visible, 1.0)
    for key in ("cov_zx", "cov_z"):
        got, want = getattr(mom, key)["perspective-joint"], getattr(mom, key)["perspective"]
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())


def test_per_particle_visibility_sums_to_the_printed_probabilities():
    cams, room, x, w, pri = setup(spread=15.0)
    p1, p2 = visibility_probabilities(cams, room, x, w, pri, 3.33, "gaussian")
    pl1, pl2 = visibility_per_particle(cams, room, x, pri, 3.33, "gaussian")
    np.testing.assert_allclose(pl1 @ w, p1, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(pl2 @ w, p2, rtol=1e-12, atol=1e-15)
    assert 0.2 < p1.min() < 0.99  # wide cloud and occluders: visibility really varies


def test_joint_metric_differs_when_visibility_depends_on_the_particle_and_stays_sane():
    cams, room, x, w, pri = setup(spread=15.0)
    mom = selection_moments(cams, room, x, w, pri, 3.33, "gaussian", MODELS)
    subsets = np.array([[0, 3], [1, 5], [2, 4, 6]], dtype=object)
    trace = np.trace(mom.sigma_x)
    for s in subsets:
        joint = subset_mse(mom, np.array(s), "perspective-joint")[0]
        assert 0.0 < joint < trace  # a reading never makes the estimate worse than the prior
    a = subset_mse(mom, np.array([0, 3]), "perspective")[0]
    b = subset_mse(mom, np.array([0, 3]), "perspective-joint")[0]
    assert a != pytest.approx(b, rel=1e-3)
