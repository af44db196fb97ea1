"""Resampling schemes: unbiased copy counts, the variance ordering, and the Numba inverse CDF."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from fusetrack.core import ConfigError, get_resampler
from fusetrack.core.resampling import inverse_cdf, inverse_cdf_reference

SCHEMES = ["multinomial", "stratified", "systematic", "residual"]
N = 8
REPS = 10_000
# Weights with a zero, a dominant particle, and values whose N*w_i are not integers.
W = np.array([0.31, 0.0, 0.02, 0.17, 0.065, 0.2, 0.11, 0.125])


def _counts(scheme, weights: np.ndarray, reps: int, seed: int) -> np.ndarray:
    """Copy counts ``(reps, N)`` from ``reps`` independent resamplings (one batched call)."""
    idx = scheme(np.broadcast_to(weights, (reps, weights.size)).copy(), np.random.default_rng(seed))
    assert idx.shape == (reps, weights.size)
    return np.stack([np.bincount(row, minlength=weights.size) for row in idx])


def _bias_z(counts: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """z-scores of the mean copy counts against ``N w_i``, using the multinomial variance
    ``N w_i (1 - w_i)`` (an upper bound for every unbiased scheme here) as the yardstick."""
    n = weights.size
    sd = np.sqrt(np.maximum(n * weights * (1 - weights), 1e-12) / counts.shape[0])
    return (counts.mean(axis=0) - n * weights) / sd


@pytest.mark.parametrize("name", SCHEMES)
def test_expected_copies_are_n_times_weight(name):
    counts = _counts(get_resampler(name), W, REPS, seed=1)
    assert np.all(counts.sum(axis=1) == N)
    assert np.all(counts[:, 1] == 0)  # a zero-weight particle is never copied
    z = _bias_z(counts, W)
    assert np.max(np.abs(z)) < 4.5, z


def test_the_bias_check_catches_a_biased_scheme():
    """Midpoint 'resampling' (u_k = (k + 1/2) / N, no randomness) copies round(N w_i)-ish times:
    the same check must reject it."""

    def midpoint(w, rng):
        n = w.shape[-1]
        return inverse_cdf(w, np.broadcast_to((np.arange(n) + 0.5) / n, w.shape))

    z = _bias_z(_counts(midpoint, W, REPS, seed=1), W)
    assert np.max(np.abs(z)) > 4.5


def test_variance_ordering():
    """Residual and stratified copy-count variances are at most the multinomial's (Douc &
    Cappé 2005); the multinomial's matches ``N w_i (1 - w_i)``."""
    var = {name: _counts(get_resampler(name), W, REPS, seed=2).var(axis=0) for name in SCHEMES}
    exact = N * W * (1 - W)
    np.testing.assert_allclose(var["multinomial"], exact, rtol=0.06, atol=1e-3)
    for name in ("residual", "stratified"):
        assert np.all(var[name] <= var["multinomial"] * 1.06 + 1e-3), (name, var[name])
        assert var[name].sum() < 0.8 * var["multinomial"].sum()
    assert var["systematic"].sum() < 0.8 * var["multinomial"].sum()


@pytest.mark.parametrize("name", SCHEMES)
def test_rows_are_independent_sets(name):
    """Leading axes are separate runs: a row only ever picks its own particles' weights."""
    w = np.zeros((3, 5))
    w[0, 0] = w[1, 2] = w[2, 4] = 1.0
    idx = get_resampler(name)(w, np.random.default_rng(0))
    assert np.all(idx[0] == 0) and np.all(idx[1] == 2) and np.all(idx[2] == 4)


def test_unknown_scheme_names_the_choices():
    with pytest.raises(ConfigError, match="systematic"):
        get_resampler("magic")


@settings(max_examples=60, deadline=None)
@given(
    w=arrays(
        np.float64,
        st.tuples(st.integers(1, 3), st.integers(1, 40)),
        elements=st.sampled_from([0.0, 1e-300, 1e-12, 0.1, 0.3, 1.0, 2.5, 7.0]),
    ),
    seed=st.integers(0, 2**32 - 1),
)
def test_numba_inverse_cdf_equals_reference(w, seed):
    w = w.copy()
    w[:, -1] += 1e-3  # every row needs some weight
    rng = np.random.default_rng(seed)
    u = np.sort(rng.random((w.shape[0], 2 * w.shape[1] + 1)), axis=-1)
    u[:, -1] = np.nextafter(1.0, 0.0)  # the largest uniform below 1
    np.testing.assert_array_equal(inverse_cdf(w, u), inverse_cdf_reference(w, u))


def test_trailing_zero_weights_are_never_selected():
    w = np.array([[0.1, 0.2, 0.3, 0.4, 0.0, 0.0], [1 / 3, 1 / 3, 1 / 3, 0.0, 0.0, 0.0]])
    u = np.broadcast_to(np.array([0.0, 0.5, 0.999999999999, np.nextafter(1.0, 0.0)]), (2, 4))
    idx = inverse_cdf(w, np.ascontiguousarray(u))
    assert idx[0].max() == 3 and idx[1].max() == 2
    np.testing.assert_array_equal(idx, inverse_cdf_reference(w, u))


def test_systematic_equals_inverse_cdf_of_shifted_grid():
    """The fused systematic merge gives the indices of the explicit ``u_k = (k + u0) / N``."""
    rng = np.random.default_rng(6)
    w = rng.random((4, 1001)) ** 3
    w[:, 500:520] = 0.0
    idx = get_resampler("systematic")(w, np.random.default_rng(7))
    u0 = np.random.default_rng(7).random((4, 1))
    u = (np.arange(1001) + u0) / 1001
    np.testing.assert_array_equal(idx, inverse_cdf_reference(w, u))
    np.testing.assert_array_equal(idx, inverse_cdf(w, u))
