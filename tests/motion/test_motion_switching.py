"""Markov-switching sets of motion models: mode chain, per-mode dynamics, shared state, errors."""

from __future__ import annotations

import numpy as np
import pytest
from _motion_helpers import numerical_jacobian

from fusetrack.core import ConfigError, ShapeError
from fusetrack.motion import (
    ConstantAcceleration,
    ConstantVelocity,
    CoordinatedTurn,
    CoordinatedTurnRate,
    MarkovSwitching,
    RandomWalk,
)

P3 = np.array([[0.8, 0.15, 0.05], [0.2, 0.7, 0.1], [0.0, 0.4, 0.6]])


def _same_dim_set() -> MarkovSwitching:
    return MarkovSwitching(
        (ConstantVelocity(2, 0.1), CoordinatedTurn(0.3, 0.1), CoordinatedTurn(-0.3, 0.1)), P3
    )


def _mixed_dim_set() -> MarkovSwitching:
    return MarkovSwitching(
        (ConstantVelocity(2, 0.5), CoordinatedTurnRate(0.5, 0.02)), [[0.9, 0.1], [0.2, 0.8]]
    )


def test_sample_modes_frequencies_match_transition_matrix():
    ms = _same_dim_set()
    rng = np.random.default_rng(0)
    n = 60_000
    for i in range(3):
        nxt = ms.sample_modes(np.full(n, i), rng)
        assert nxt.shape == (n,) and nxt.dtype == np.intp
        freq = np.bincount(nxt, minlength=3) / n
        se = np.sqrt(P3[i] * (1 - P3[i]) / n)
        np.testing.assert_array_less(np.abs(freq - P3[i]), 5 * se + 1e-12)
    assert not np.any(ms.sample_modes(np.full(n, 2), rng) == 0)  # probability 0 never drawn


def test_sample_modes_long_run_visits_stationary_distribution():
    ms = _same_dim_set()
    rng = np.random.default_rng(1)
    modes = np.zeros(20_000, dtype=int)
    for _ in range(30):
        modes = ms.sample_modes(modes, rng)
    w, v = np.linalg.eig(P3.T)
    pi = np.real(v[:, np.argmin(np.abs(w - 1))])
    pi /= pi.sum()
    np.testing.assert_allclose(np.bincount(modes, minlength=3) / modes.size, pi, atol=0.015)


def test_sample_modes_keeps_shape_and_is_seeded():
    ms = _same_dim_set()
    m = np.array([[0, 1], [2, 2]])
    a = ms.sample_modes(m, np.random.default_rng(5))
    assert a.shape == (2, 2)
    np.testing.assert_array_equal(a, ms.sample_modes(m, np.random.default_rng(5)))
    assert ms.sample_modes(1, np.random.default_rng(0)).shape == ()


def test_per_mode_dynamics_equal_the_models():
    ms = _same_dim_set()
    rng = np.random.default_rng(2)
    x = rng.normal(size=(9, 4))
    modes = np.arange(9) % 3
    mean = ms.mean(x, 0.7, modes)
    jac = ms.jacobian(x, 0.7, modes)
    xn = ms.sample(x, 0.7, rng, modes)
    ld = ms.log_density(xn, x, 0.7, modes)
    for r in range(9):
        model = ms.models[modes[r]]
        np.testing.assert_allclose(mean[r], model.mean(x[r], 0.7))
        np.testing.assert_allclose(jac[r], model.jacobian(x[r], 0.7))
        np.testing.assert_allclose(ld[r], model.log_density(xn[r], x[r], 0.7))
    np.testing.assert_allclose(ms.noise_cov(0.7, modes)[4], ms.models[1].noise_cov(0.7))
    assert ms.noise_cov(0.7).shape == (3, 4, 4)


def test_modes_broadcast_over_leading_axes():
    ms = _same_dim_set()
    rng = np.random.default_rng(3)
    x = rng.normal(size=(2, 5, 4))  # runs x particles
    per_particle = np.array([0, 1, 2, 1, 0])
    out = ms.mean(x, 1.0, per_particle)
    assert out.shape == (2, 5, 4)
    np.testing.assert_allclose(out[1, 2], ms.models[2].mean(x[1, 2], 1.0))
    assert ms.mean(x, 1.0, 1).shape == (2, 5, 4)
    np.testing.assert_allclose(ms.mean(x, 1.0, 1), ms.models[1].mean(x, 1.0))
    # one state, several modes: output takes the modes' shape
    assert ms.mean(x[0, 0], 1.0, np.array([0, 1, 2])).shape == (3, 4)
    assert ms.jacobian(x, 1.0, per_particle).shape == (2, 5, 4, 4)
    assert ms.log_density(x, x, 1.0, per_particle).shape == (2, 5)
    assert ms.noise_cov(1.0, per_particle).shape == (5, 4, 4)


def test_mixed_dimensions_share_the_largest_state():
    ms = _mixed_dim_set()
    assert ms.dim == 5 and ms.position_index == (0, 1) and ms.velocity_index == (2, 3)
    assert ms.state_names == ("x", "y", "vx", "vy", "omega")
    rng = np.random.default_rng(4)
    x = rng.normal(size=(6, 5))
    modes = np.array([0, 0, 0, 1, 1, 1])
    m = ms.mean(x, 1.0, modes)
    np.testing.assert_allclose(m[:3, :4], ConstantVelocity(2).mean(x[:3, :4], 1.0))
    np.testing.assert_array_equal(m[:3, 4], x[:3, 4])  # CV mode carries omega unchanged
    np.testing.assert_allclose(m[3:], CoordinatedTurnRate().mean(x[3:], 1.0))
    s = ms.sample(x, 1.0, rng, modes)
    np.testing.assert_array_equal(s[:3, 4], x[:3, 4])
    assert np.all(s[3:, 4] != x[3:, 4])
    ld = ms.log_density(s, x, 1.0, modes)
    assert np.all(np.isfinite(ld))
    np.testing.assert_allclose(ld[:3], ms.models[0].log_density(s[:3, :4], x[:3, :4], 1.0))
    moved = s.copy()
    moved[:, 4] += 0.05
    ld2 = ms.log_density(moved, x, 1.0, modes)
    assert np.all(ld2[:3] == -np.inf) and np.all(np.isfinite(ld2[3:]))
    q = ms.noise_cov(1.0, np.array([0, 1]))
    assert q[0, 4, 4] == 0.0 and q[1, 4, 4] == pytest.approx(0.02)


@pytest.mark.parametrize("make", [_same_dim_set, _mixed_dim_set])
def test_switching_jacobian_equals_finite_differences(make):
    ms = make()
    rng = np.random.default_rng(5)
    x = rng.normal(size=(6, ms.dim))
    if ms.dim == 5:
        x[:, 4] = [0.0, 0.3, -0.2, 0.0, 1e-5, 0.3]
    modes = np.arange(6) % ms.n_modes
    num = numerical_jacobian(lambda y: ms.mean(y, 0.9, modes), x)
    np.testing.assert_allclose(ms.jacobian(x, 0.9, modes), num, atol=1e-8)


def test_layouts_must_agree():
    with pytest.raises(ConfigError, match=r"models\[0\]\.position_index=\(0, 1\)"):
        MarkovSwitching((ConstantVelocity(2), ConstantVelocity(3)), np.eye(2))
    # CV on 2-D nested in CA 2-D and a 2-D random walk: same positions, same velocities
    ms = MarkovSwitching(
        (RandomWalk(2), ConstantVelocity(2), ConstantAcceleration(2)), np.full((3, 3), 1 / 3)
    )
    assert ms.dim == 6 and ms.velocity_index == (2, 3)


def test_transition_validation():
    models = (ConstantVelocity(2), CoordinatedTurn(0.1))
    with pytest.raises(ShapeError, match=r"transition\.shape=\(3, 3\).*\(2, 2\)"):
        MarkovSwitching(models, np.eye(3))
    with pytest.raises(ConfigError, match=r"transition\[1\]=\[0\.5, 0\.4\].*sums to 1"):
        MarkovSwitching(models, [[1.0, 0.0], [0.5, 0.4]])
    with pytest.raises(ConfigError, match=">= 0"):
        MarkovSwitching(models, [[1.2, -0.2], [0.5, 0.5]])
    with pytest.raises(ConfigError, match="models"):
        MarkovSwitching((), np.zeros((0, 0)))
    with pytest.raises(ConfigError, match=r"models\[1\]"):
        MarkovSwitching((ConstantVelocity(2), "CV"), np.eye(2))
    ms = MarkovSwitching(list(models), [[0.5, 0.5], [0.25, 0.75]])
    assert isinstance(ms.models, tuple)
    with pytest.raises(ValueError):
        ms.transition[0, 0] = 1.0  # read-only


def test_modes_validation():
    ms = _same_dim_set()
    x = np.zeros((4, 4))
    with pytest.raises(ConfigError, match=r"modes=.*0\.\.2"):
        ms.mean(x, 1.0, np.array([0, 1, 3, 0]))
    with pytest.raises(ConfigError, match="modes="):
        ms.mean(x, 1.0, np.array([-1, 0, 0, 0]))
    with pytest.raises(ConfigError, match="integer"):
        ms.mean(x, 1.0, np.array([0.0, 1.0, 1.0, 0.0]))
    with pytest.raises(ShapeError, match=r"modes\.shape"):
        ms.mean(x, 1.0, np.array([0, 1, 1]))
    with pytest.raises(ShapeError, match="d=4"):
        ms.mean(np.zeros((4, 5)), 1.0, 0)
    with pytest.raises(ConfigError, match="rng="):
        ms.sample_modes(np.array([0]), None)
    with pytest.raises(ConfigError, match="dt="):
        ms.sample(x, -1.0, np.random.default_rng(0), 0)
