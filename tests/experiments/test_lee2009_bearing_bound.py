"""Lee 2009 Ch. 3's bound (:mod:`fusetrack.experiments.lee2009.bearing_bound`): hand-computed
cases, the turn's Jacobian, and more camera fixes never raising it."""

import math

import numpy as np
import pytest

from fusetrack.core import ConfigError
from fusetrack.experiments.lee2009 import bearing_bound as bb
from fusetrack.experiments.lee2009 import camera_triggering as ct


def test_one_bearing_on_a_static_object_by_hand():
    """Sensor at the origin, object standing at (r, 0): one step from the prior, then one
    bearing. Prediction: each position variance s_r^2 + s_v^2 dt^2; the bearing's information
    1 / (sigma^2 r^2) is across the line of sight (y) only, so
    P_yy = p / (1 + p / (sigma^2 r^2)) and P_xx = p."""
    r, sigma, s_r, s_v, dt = 20.0, math.radians(2.0), 0.1, 0.02, 1.0
    truth = np.array([[r, 0.0, 0.0, 0.0], [r, 0.0, 0.0, 0.0]])
    ms = bb.position_bound(
        truth, np.zeros(1), dt, (0.0, 0.0), sigma, np.ones(2, bool), np.zeros(2, bool),
        bb.start_cov(s_r, s_v), s_r,
    )  # fmt: skip
    p = s_r**2 + s_v**2 * dt**2
    info = 1.0 / (sigma**2 * r**2)
    assert ms[0] == pytest.approx(2 * s_r**2)  # the start: the prior, no measurement
    assert ms[1] == pytest.approx(p + p / (1.0 + p * info), rel=1e-10)


def test_a_camera_fix_by_hand():
    """A fix of std s_r on a predicted variance p per axis: p s_r^2 / (p + s_r^2) per axis
    (the bearing adds its own information across the line of sight on top)."""
    s_r, s_v = 0.1, 0.05
    truth = np.array([[10.0, 10.0, 0.0, 0.0]] * 2)
    args = (truth, np.zeros(1), 1.0, (0.0, 0.0), 0.05, np.zeros(2, bool))
    ms = bb.position_bound(*args, np.ones(2, bool), bb.start_cov(s_r, s_v), s_r)
    p = s_r**2 + s_v**2
    assert ms[1] == pytest.approx(2 * p * s_r**2 / (p + s_r**2), rel=1e-10)


def test_turn_jacobian_matches_the_map():
    """The scheduled turn's Jacobian predicts the map's response to a small perturbation."""
    x = np.array([[40.0, 30.0, 0.2, -0.1], [0.0, 0.0, 0.0, 0.0]])
    F = bb.transition_jacobians(x, np.array([1.0]), 1.0)[0]
    dx = np.array([1e-6, -2e-6, 3e-7, 1e-7])
    model = bb.step_model(1.0)
    moved = model.mean(x[0] + dx, 1.0) - model.mean(x[0], 1.0)
    np.testing.assert_allclose(moved, F @ dx, rtol=1e-4, atol=1e-12)
    assert not np.allclose(F, bb.transition_jacobians(x, np.zeros(1), 1.0)[0])


def test_more_camera_fixes_never_raise_the_bound():
    truth = ct.truth_e31("apart", 1.0)
    alphas = ct.schedule_alphas(ct.schedule_e31(1.0), 1.0, ct.T_33)
    sigma = math.sqrt(5.0) * ct.DEG
    ms = {
        p: bb.periodic_bound_ms(truth, alphas, 1.0, (0.0, 0.0), sigma, p, 0.1, 0.02)
        for p in (0, 1, 10)
    }
    assert np.all(ms[1] < ms[10]) and np.all(ms[10] < ms[0])
    # a fix at every step: about the fix's own variance (2 x 0.1^2) shared with the prediction
    assert np.all(ms[1] < 2 * 0.1**2)


def test_schedules_turn_at_the_stated_steps():
    """E3.1: one-step turns (step 50 -> 51 among them); E3.3: O3 turns for 50 steps."""
    truth = ct.truth_e31("spec", 1.0)
    assert truth.shape == (200, 3, 4)
    assert ct.schedule_alphas(ct.schedule_e31(1.0), 1.0, 200)[50].tolist() == [-1.0, 1.0, -1.0]
    assert np.count_nonzero(ct.schedule_alphas(ct.schedule_e33(1.0), 1.0, 200)[:, 2]) == 50


def test_bad_noise_is_named():
    with pytest.raises(ConfigError, match="sigma"):
        bb.position_bound(np.zeros((2, 4)) + 1, np.zeros(1), 1.0, (0.0, 0.0), 0.0,
                          np.ones(2, bool), np.ones(2, bool), bb.start_cov(0.1, 0.1), 0.1)  # fmt: skip
    assert np.isnan(
        bb.run_bound_ms(np.ones((3, 1, 4)), np.zeros((2, 1)), 1.0, (0.0, 0.0), 0.0,
                        np.ones((3, 1), bool), np.ones((3, 1), bool), np.zeros((3, 1), bool), 0.1, 0.02)
    ).all()  # fmt: skip
