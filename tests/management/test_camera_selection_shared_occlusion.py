"""Camera selection and the likelihood share one occlusion probability (Ercan et al. 2013, Eq. 7),
including the shortened rectangles; and the selection's behaviour on bad input."""

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.experiments.ercan2013.scenes import l_scene
from fusetrack.experiments.ercan2013.simulation import run_tracking
from fusetrack.management.camera_selection import (
    brute_force_selection,
    greedy_selection,
    selection_moments,
    subset_mse,
    visibility_probabilities,
)
from fusetrack.sensors.occlusion_aware_camera import OcclusionAwareLikelihood
from fusetrack.sensors.perspective_camera import ring_of_cameras
from fusetrack.world.occlusion import (
    OccluderPriors,
    occlusion_probability,
    occlusion_probability_reference,
)
from fusetrack.world.room import square_room

D = 3.33
NOISE = {"sigma_theta": 0.01, "sigma_pos": 1.0, "sigma_read": 2.0}


def crowded_l_room(seed: int = 0):
    """The L room with occluder priors packed around the particles, so that the shortened
    rectangles change the probabilities (an occluder within D of a particle)."""
    rng = np.random.default_rng(seed)
    scene = l_scene()
    x = scene.room.sample_free(rng, 25)
    near = x[rng.integers(0, len(x), 15)] + rng.normal(0, 2.0, (15, 2))
    far = scene.room.sample_free(rng, 15)
    cov = np.array([np.diag(v) for v in rng.uniform(1.0, 9.0, (30, 2))])
    return scene, x, OccluderPriors(np.concatenate([near, far]), cov)


@pytest.mark.parametrize("exclusion", [0.0, D])
def test_kernel_equals_reference_with_shortened_rectangles(exclusion):
    scene, x, pri = crowded_l_room(1)
    fast = occlusion_probability(scene.cameras.positions, x, pri, D, exclusion)
    ref = occlusion_probability_reference(scene.cameras.positions, x, pri, D, exclusion)
    assert np.abs(fast - ref).max() < 1e-6


@pytest.mark.parametrize("exclusion", [0.0, D])
def test_selection_visibility_equals_the_likelihood_pattern_probability(exclusion):
    """For a one-particle cloud, P{eta_i = 1} and P{eta_i = 1, eta_j = 1} of the selection metric
    are p(eta | u) of the likelihood (floor 0) for 'camera i sees' and 'cameras i and j see'."""
    scene, x, pri = crowded_l_room(2)
    cams = scene.cameras
    lik = OcclusionAwareLikelihood(cams, scene.room, D, "gaussian", exclusion=exclusion)
    pairs = [(0, 1), (2, 5), (3, 4), (6, 7), (8, 11), (9, 10)]
    checked = 0
    for xl in x:
        p1, p2 = visibility_probabilities(
            cams, scene.room, xl[None], np.ones(1), pri, D, "gaussian", exclusion
        )
        for sel in [(i,) for i in range(len(cams))] + pairs:
            s = np.array(sel)
            sub = cams.subset(s)
            z = sub.image_coordinate(xl[None, None, :])[0]  # zero residual
            log_g = -0.5 * np.sum(np.log(2 * np.pi * sub.noise_var(xl[None, None, :])[0]))
            with np.errstate(invalid="ignore"):
                log_l = lik.log_likelihood(z, s, xl[None], pri)[0]
            p_lik = float(np.exp(log_l - log_g)) if np.isfinite(log_l) else 0.0
            p_sel = p1[sel[0]] if len(sel) == 1 else p2[sel]
            assert p_sel == pytest.approx(p_lik, abs=1e-6)
            checked += p_lik > 0
    assert checked > 30


def test_shortened_rectangles_raise_visibility_near_crowded_particles():
    scene, x, pri = crowded_l_room(3)
    w = np.full(len(x), 1 / len(x))
    args = (scene.cameras, scene.room, x, w, pri, D, "gaussian")
    p_printed, _ = visibility_probabilities(*args, 0.0)
    p_short, _ = visibility_probabilities(*args, D)
    assert np.all(p_short >= p_printed - 1e-12)
    assert (p_short - p_printed).max() > 0.01
    mom = selection_moments(*args, ("weak",), exclusion=D)
    assert np.allclose(mom.p_visible, p_short)


def test_run_tracking_passes_the_exclusion_to_selection(monkeypatch):
    import fusetrack.experiments.ercan2013.simulation as sim

    seen = []
    real = sim.selection_moments

    def spy(*args, **kwargs):
        seen.append(kwargs["exclusion"])
        return real(*args, **kwargs)

    monkeypatch.setattr(sim, "selection_moments", spy)
    cfg = {"scene": "L", "method": "greedy", "k": 2, "steps": 6, "particles": 60, "period": 5}
    run_tracking({**cfg, "exclusion": 1.0}, 0)
    run_tracking({**cfg, "exclusion": 0.0}, 0)
    assert seen == [pytest.approx(D), pytest.approx(D), 0.0, 0.0]


def test_negative_exclusion_is_refused():
    scene, x, pri = crowded_l_room(4)
    with pytest.raises(ConfigError, match="exclusion"):
        occlusion_probability(scene.cameras.positions, x, pri, D, -1.0)


# ---- bad input --------------------------------------------------------------------------------


def room_with_a_blind_camera():
    """Four cameras in a 100 x 100 room; camera 4 sits on the wall and looks out of the room."""
    room = square_room(100.0)
    cams = ring_of_cameras(
        [(0, 0), (100, 0), (100, 100), (50, 0)], [45, 135, 225, 270], 90.0, **NOISE
    )
    rng = np.random.default_rng(5)
    x = np.array([50.0, 50.0]) + 8.0 * rng.standard_normal((300, 2))
    return room, cams, x, np.full(300, 1 / 300)


@pytest.mark.parametrize("model", ["perspective", "weak"])
def test_camera_that_sees_no_particle_adds_nothing_and_is_picked_last(model):
    room, cams, x, w = room_with_a_blind_camera()
    pri = OccluderPriors(np.array([[30.0, 30.0]]), 4.0 * np.eye(2)[None])
    mom = selection_moments(cams, room, x, w, pri, D, "gaussian")
    assert mom.p_visible[3] == 0.0 and np.all(mom.p_both[3] == 0.0)
    assert np.all(mom.cov_zx[model][3] == 0.0)
    e = subset_mse(mom, np.array([[0, 1], [0, 1]]), model)[0]
    assert subset_mse(mom, np.array([0, 1, 3]), model)[0] == pytest.approx(e, rel=1e-9)
    assert np.isfinite(subset_mse(mom, np.array([3]), model)).all()
    assert subset_mse(mom, np.array([3]), model)[0] == pytest.approx(np.trace(mom.sigma_x))
    for k in (1, 2, 3):
        assert 3 not in greedy_selection(mom, k, model)
        assert 3 not in brute_force_selection(mom, k, model)
    assert greedy_selection(mom, 4, model) == [0, 1, 2, 3]  # forced: all cameras


def test_camera_behind_a_wall_has_zero_visibility_in_the_l_room():
    """A particle in one arm of the L is hidden by the walls from the cameras of the other arm:
    the selection gives those cameras P{eta = 1} = 0, whatever the occluder priors."""
    scene = l_scene()
    cams, room = scene.cameras, scene.room
    x = np.array([[180.0, 20.0], [182.0, 22.0]])  # far end of the bottom arm
    hidden = cams.in_fov(x[:, None, :]).T & room.sight_blocked_grid(cams.positions, x)
    assert hidden.any(axis=1).sum() >= 1  # some camera looks this way but a wall is in between
    for mode, occ in (("none", None), ("perfect", np.zeros((0, 2))), ("gaussian", None)):
        pri = OccluderPriors(np.array([[50.0, 150.0]]), np.eye(2)[None]) if occ is None else occ
        p1, p2 = visibility_probabilities(cams, room, x, np.full(2, 0.5), pri, D, mode)
        blocked = np.flatnonzero(hidden.all(axis=1))
        assert np.all(p1[blocked] == 0.0) and np.all(p2[blocked] == 0.0)


def test_selection_size_larger_than_the_number_of_cameras():
    room, cams, x, w = room_with_a_blind_camera()
    mom = selection_moments(cams, room, x, w, None, D, "none")
    for pick in (greedy_selection, brute_force_selection):
        with pytest.raises(ConfigError, match=r"k=5.*\[1, 4\]"):
            pick(mom, 5)
    with pytest.raises(ConfigError, match="k=13"):
        run_tracking({"scene": "L", "method": "greedy", "k": 13, "steps": 2}, 0)
