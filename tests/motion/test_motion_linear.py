"""Random walk, constant velocity, constant acceleration: matrices, moments, densities, errors."""

from __future__ import annotations

import numpy as np
import pytest
from _motion_helpers import assert_moments, numerical_jacobian
from scipy.stats import multivariate_normal

from fusetrack.core import ConfigError, MotionModel, ShapeError
from fusetrack.motion import (
    ConstantAcceleration,
    ConstantVelocity,
    RandomWalk,
    kinematic_noise,
    kinematic_transition,
)

# ----------------------------------------------------------------------------- hand-computed


def test_cv_2d_matrices_hand_computed_dt_half():
    dt, q = 0.5, 2.0
    cv = ConstantVelocity(ndim=2, q=q)
    np.testing.assert_array_equal(
        cv.transition_matrix(dt),
        [[1, 0, 0.5, 0], [0, 1, 0, 0.5], [0, 0, 1, 0], [0, 0, 0, 1]],
    )
    a, b, c = q * dt**3 / 3, q * dt**2 / 2, q * dt  # 1/12, 1/4, 1
    np.testing.assert_allclose(
        cv.noise_cov(dt),
        [[a, 0, b, 0], [0, a, 0, b], [b, 0, c, 0], [0, b, 0, c]],
        rtol=1e-15,
    )
    np.testing.assert_allclose(cv.noise_cov(dt)[0, 0], 1 / 12, rtol=1e-15)


def test_cv_discrete_noise_hand_computed_dt_2():
    cv = ConstantVelocity(ndim=1, q=3.0, noise="discrete")
    # g = [dt^2/2, dt] = [2, 2]; Q = 3 g g^T
    np.testing.assert_allclose(cv.noise_cov(2.0), [[12.0, 12.0], [12.0, 12.0]], rtol=1e-15)


def test_cv_3d_layout_positions_then_velocities():
    cv = ConstantVelocity(ndim=3, q=1.0)
    assert cv.dim == 6
    assert cv.position_index == (0, 1, 2) and cv.velocity_index == (3, 4, 5)
    assert cv.state_names == ("x", "y", "z", "vx", "vy", "vz")
    f, q = cv.transition_matrix(2.0), cv.noise_cov(2.0)
    for ax in range(3):
        assert f[ax, 3 + ax] == 2.0
        assert q[ax, 3 + ax] == pytest.approx(2.0)  # dt^2/2
        assert q[ax, ax] == pytest.approx(8 / 3)  # dt^3/3
    off = np.ones((6, 6), bool)
    for ax in range(3):
        off[np.ix_([ax, 3 + ax], [ax, 3 + ax])] = False
    assert not np.any(q[off]) and not np.any((f - np.eye(6))[off])


def test_ca_1d_matrices_hand_computed_dt_2():
    ca = ConstantAcceleration(ndim=1, q=1.0)
    np.testing.assert_array_equal(ca.transition_matrix(2.0), [[1, 2, 2], [0, 1, 2], [0, 0, 1]])
    # dt^5/20, dt^4/8, dt^3/6, dt^3/3, dt^2/2, dt at dt = 2
    expected = [[1.6, 2.0, 4 / 3], [2.0, 8 / 3, 2.0], [4 / 3, 2.0, 2.0]]
    np.testing.assert_allclose(ca.noise_cov(2.0), expected, rtol=1e-15)
    cad = ConstantAcceleration(ndim=1, q=0.5, noise="discrete")  # g = [2, 2, 1]
    np.testing.assert_allclose(
        cad.noise_cov(2.0), 0.5 * np.array([[4, 4, 2], [4, 4, 2], [2, 2, 1]]), rtol=1e-15
    )


def test_ca_2d_layout():
    ca = ConstantAcceleration(ndim=2)
    assert ca.dim == 6 and ca.position_index == (0, 1) and ca.velocity_index == (2, 3)
    assert ca.state_names == ("x", "y", "vx", "vy", "ax", "ay")
    f = ca.transition_matrix(1.0)
    assert f[0, 4] == 0.5 and f[1, 5] == 0.5 and f[2, 4] == 1.0 and f[0, 5] == 0.0


def test_random_walk_matrices():
    rw = RandomWalk(dim=3, q=2.0)
    assert rw.dim == 3 and rw.position_index == (0, 1, 2) and rw.velocity_index is None
    np.testing.assert_array_equal(rw.transition_matrix(0.7), np.eye(3))
    np.testing.assert_allclose(rw.noise_cov(0.25), 0.5 * np.eye(3), rtol=1e-15)


def test_generic_block_matches_filterpy():
    common = pytest.importorskip("filterpy.common")
    for dt in (0.1, 1.0, 2.5):
        for order in (2, 3):
            np.testing.assert_allclose(
                kinematic_noise(order, dt, "continuous"),
                common.Q_continuous_white_noise(dim=order, dt=dt, spectral_density=1.0),
                rtol=1e-12,
            )
            np.testing.assert_allclose(
                kinematic_noise(order, dt, "discrete"),
                common.Q_discrete_white_noise(dim=order, dt=dt, var=1.0),
                rtol=1e-12,
            )


@pytest.mark.parametrize("order", [1, 2, 3])
def test_continuous_noise_is_an_exact_discretisation(order):
    # Q(a + b) = F(b) Q(a) F(b)^T + Q(b): stepping twice equals stepping once (any dt).
    a, b = 0.3, 1.7
    fb = kinematic_transition(order, b)
    lhs = kinematic_noise(order, a + b)
    rhs = fb @ kinematic_noise(order, a) @ fb.T + kinematic_noise(order, b)
    np.testing.assert_allclose(lhs, rhs, rtol=1e-12)
    np.testing.assert_allclose(
        kinematic_transition(order, a) @ kinematic_transition(order, b),
        kinematic_transition(order, a + b),
        rtol=1e-15,
    )


# ----------------------------------------------------------------------------- behaviour

ALL_LINEAR = [
    RandomWalk(1, 0.4),
    RandomWalk(2, 1.5),
    ConstantVelocity(1, 2.0),
    ConstantVelocity(2, 0.5),
    ConstantVelocity(3, 1.0, "discrete"),
    ConstantAcceleration(1, 0.3, "discrete"),
    ConstantAcceleration(2, 1.0),
    ConstantAcceleration(3, 0.2),
]


@pytest.mark.parametrize("model", ALL_LINEAR, ids=repr)
def test_is_a_motion_model_and_mean_is_f_x(model):
    assert isinstance(model, MotionModel)
    x = np.random.default_rng(1).normal(size=(3, 5, model.dim))
    f = model.transition_matrix(0.8)
    np.testing.assert_allclose(model.mean(x, 0.8), np.einsum("ij,...j->...i", f, x), atol=1e-13)


@pytest.mark.parametrize("model", ALL_LINEAR, ids=repr)
def test_jacobian_equals_finite_differences(model):
    x = np.random.default_rng(2).normal(size=(4, model.dim))
    j = model.jacobian(x, 0.6)
    assert j.shape == (4, model.dim, model.dim)
    np.testing.assert_allclose(j, numerical_jacobian(lambda y: model.mean(y, 0.6), x), atol=1e-8)


@pytest.mark.parametrize(
    "model",
    [
        ConstantVelocity(2, 0.7),
        ConstantVelocity(1, 2.0, "discrete"),
        ConstantAcceleration(1, 0.5),
        ConstantAcceleration(2, 0.5, "discrete"),
        RandomWalk(2, 3.0),
    ],
    ids=repr,
)
def test_sample_moments_match_mean_and_noise_cov(model):
    rng = np.random.default_rng(12345)
    dt = 1.3
    x0 = np.linspace(-1.0, 2.0, model.dim)
    s = model.sample(np.broadcast_to(x0, (100_000, model.dim)), dt, rng)
    assert_moments(s, model.mean(x0, dt), model.noise_cov(dt))


def test_sample_moments_reject_a_wrong_q():
    # The tolerance of assert_moments is tight enough to tell dt^3/3 from dt^3/2 or dt^3/4.
    rng = np.random.default_rng(7)
    cv = ConstantVelocity(1, 1.0)
    s = cv.sample(np.zeros((100_000, 2)), 1.3, rng)
    for wrong in (ConstantVelocity(1, 1.0, "discrete"), ConstantVelocity(1, 1.1)):
        with pytest.raises(AssertionError):
            assert_moments(s, np.zeros(2), wrong.noise_cov(1.3))


@pytest.mark.parametrize(
    "model", [ConstantVelocity(2, 0.7), ConstantAcceleration(3, 1.2), RandomWalk(3, 0.1)], ids=repr
)
def test_log_density_equals_scipy(model):
    rng = np.random.default_rng(3)
    dt = 0.9
    x = rng.normal(size=(6, model.dim))
    xn = model.sample(x, dt, rng) + 0.3 * rng.normal(size=(6, model.dim))
    m, cov = model.mean(x, dt), model.noise_cov(dt)
    expected = [multivariate_normal(m[i], cov).logpdf(xn[i]) for i in range(6)]
    np.testing.assert_allclose(model.log_density(xn, x, dt), expected, rtol=1e-10)


@pytest.mark.parametrize(
    "model", [ConstantVelocity(2, 0.7, "discrete"), ConstantAcceleration(1, 2.0, "discrete")]
)
def test_log_density_of_singular_q_is_the_degenerate_gaussian(model):
    rng = np.random.default_rng(4)
    dt = 1.1
    x = rng.normal(size=(5, model.dim))
    xn = model.sample(x, dt, rng)  # on the support
    m, cov = model.mean(x, dt), model.noise_cov(dt)
    expected = [multivariate_normal(m[i], cov, allow_singular=True).logpdf(xn[i]) for i in range(5)]
    got = model.log_density(xn, x, dt)
    assert np.all(np.isfinite(got))
    np.testing.assert_allclose(got, expected, rtol=1e-8)
    off = xn.copy()
    off[:, 0] += 0.01  # a position change without the matching velocity change
    assert np.all(model.log_density(off, x, dt) == -np.inf)


def test_samples_of_a_singular_q_stay_on_its_support_when_cholesky_succeeds():
    """Found by test_motion_properties: at this dt ``cholesky(Q)`` succeeds on the rank-3 ``Q``
    and its factor leaks ~1e-7 into the null space; the density must not call that off-support."""
    model = ConstantVelocity(3, 2.0, "discrete")
    dt = 2.3579288105783665
    np.linalg.cholesky(model.noise_cov(dt))  # does not raise: the factor is not exactly rank 3
    rng = np.random.default_rng(2316982925)
    x = rng.normal(size=6)
    xn = model.sample(x, dt, rng)
    assert np.isfinite(model.log_density(xn, x, dt))
    many = np.random.default_rng(0).normal(size=(20000, 6))
    assert np.all(np.isfinite(model.log_density(model.sample(many, dt, rng), many, dt)))
    off = xn.copy()
    off[0] += 1e-4 * np.sqrt(model.noise_cov(dt).max())  # position without the velocity change
    assert model.log_density(off, x, dt) == -np.inf


def test_dt_zero_is_the_identity_and_log_density_raises():
    cv = ConstantVelocity(2, 1.0)
    x = np.array([[1.0, 2.0, 3.0, 4.0]])
    np.testing.assert_array_equal(cv.transition_matrix(0.0), np.eye(4))
    np.testing.assert_array_equal(cv.mean(x, 0.0), x)
    np.testing.assert_array_equal(cv.sample(x, 0.0, np.random.default_rng(0)), x)
    with pytest.raises(ConfigError, match=r"dt=0\.0"):
        cv.log_density(x, x, 0.0)
    with pytest.raises(ConfigError, match="q > 0"):
        ConstantVelocity(2, 0.0).log_density(x, x, 1.0)


def test_single_state_and_scalar_log_density():
    cv = ConstantVelocity(1, 1.0)
    x = np.array([0.0, 1.0])
    assert cv.mean(x, 1.0).shape == (2,)
    assert cv.sample(x, 1.0, np.random.default_rng(0)).shape == (2,)
    assert cv.jacobian(x, 1.0).shape == (2, 2)
    assert np.shape(cv.log_density(x, x, 1.0)) == ()


def test_x_next_broadcasts_against_x():
    cv = ConstantVelocity(2, 1.0)
    x = np.random.default_rng(5).normal(size=(7, 4))
    xn = np.zeros(4)
    ld = cv.log_density(xn, x, 1.0)
    assert ld.shape == (7,)
    np.testing.assert_allclose(ld[2], cv.log_density(xn, x[2], 1.0))


def test_seeded_sampling_is_reproducible():
    cv = ConstantVelocity(3, 1.0)
    x = np.zeros((10, 6))
    a = cv.sample(x, 1.0, np.random.default_rng(99))
    b = cv.sample(x, 1.0, np.random.default_rng(99))
    np.testing.assert_array_equal(a, b)


# ----------------------------------------------------------------------------- errors


@pytest.mark.parametrize("ndim", [0, 4, -1, 2.0, True, "2"])
def test_bad_ndim(ndim):
    with pytest.raises(ConfigError, match=r"ndim=.* expected an integer in 1\.\.3"):
        ConstantVelocity(ndim=ndim)
    with pytest.raises(ConfigError, match="ndim="):
        ConstantAcceleration(ndim=ndim)


def test_bad_random_walk_dim():
    with pytest.raises(ConfigError, match=r"dim=4 .* 1\.\.3"):
        RandomWalk(dim=4)


@pytest.mark.parametrize("q", [-1.0, float("nan"), float("inf"), "x"])
def test_bad_q(q):
    with pytest.raises(ConfigError, match="q="):
        ConstantVelocity(q=q)
    with pytest.raises(ConfigError, match="q="):
        RandomWalk(q=q)


def test_bad_noise():
    with pytest.raises(ConfigError, match=r"noise='white'.*'continuous' or 'discrete'"):
        ConstantVelocity(noise="white")
    with pytest.raises(ConfigError, match="noise"):
        kinematic_noise(1, 1.0, "discrete")


@pytest.mark.parametrize("dt", [-0.1, float("nan"), float("inf"), "soon", None])
def test_bad_dt(dt):
    cv = ConstantVelocity()
    with pytest.raises(ConfigError, match="dt="):
        cv.transition_matrix(dt)
    with pytest.raises(ConfigError, match="dt="):
        cv.mean(np.zeros(4), dt)
    with pytest.raises(ConfigError, match="dt="):
        cv.noise_cov(dt)


def test_wrong_state_dimension_names_expected_d():
    cv = ConstantVelocity(ndim=3)
    with pytest.raises(ShapeError, match=r"x\.shape=\(10, 4\).*d=6"):
        cv.mean(np.zeros((10, 4)), 1.0)
    with pytest.raises(ShapeError, match=r"x_next\.shape=\(5,\).*d=6"):
        cv.log_density(np.zeros(5), np.zeros(6), 1.0)
    with pytest.raises(ShapeError, match="d=6"):
        cv.jacobian(np.float64(1.0), 1.0)


def test_rng_must_be_a_generator():
    with pytest.raises(ConfigError, match="rng="):
        ConstantVelocity().sample(np.zeros(4), 1.0, 0)


def test_models_are_frozen_and_comparable():
    cv = ConstantVelocity(2, 1.0)
    assert cv == ConstantVelocity(2, 1.0) and cv != ConstantVelocity(2, 2.0)
    with pytest.raises(AttributeError):
        cv.q = 3.0


@pytest.mark.parametrize("dt", [1e-3, 1 / 64, 10.0])
def test_log_density_of_badly_scaled_q_stays_full_rank(dt):
    # CA continuous Q(dt) = T Q(1) T with T = diag(dt^2.5, dt^1.5, dt^0.5): the exact density is
    # that of T^-1 r under Q(1), minus log|det T|, although Q(dt) spans ~dt^-4 orders of magnitude.
    ca = ConstantAcceleration(ndim=1, q=0.3)
    t = np.diag([dt**2.5, dt**1.5, dt**0.5])
    rng = np.random.default_rng(8)
    x = rng.normal(size=(5, 3))
    xn = ca.sample(x, dt, rng)
    r = xn - ca.mean(x, dt)
    expected = multivariate_normal(np.zeros(3), ca.noise_cov(1.0)).logpdf(
        r @ np.linalg.inv(t).T
    ) - np.log(np.linalg.det(t))
    np.testing.assert_allclose(ca.log_density(xn, x, dt), expected, rtol=1e-8)
