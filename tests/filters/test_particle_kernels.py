"""The Numba kernels of the particle filters equal their NumPy references."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from fusetrack.filters import kernels as K

LOGW = st.one_of(st.floats(-800.0, 50.0), st.just(-np.inf))


def _check_update(lw, ll):
    got = K.log_weight_update(lw, ll)
    ref = K.log_weight_update_reference(lw, ll)
    # log-weights v - lse lose absolute accuracy |lse| * eps when v and lse are close
    finite = np.abs(ref[2][np.isfinite(ref[2])])
    scale = max(1.0, float(finite.max(initial=0.0)))
    np.testing.assert_allclose(got[0], ref[0], rtol=1e-12, atol=1e-13 * scale)
    for a, b in zip(got[1:], ref[1:]):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-300)
    return got


@settings(max_examples=80, deadline=None)
@given(
    lw=arrays(np.float64, st.tuples(st.integers(1, 3), st.integers(1, 50)), elements=LOGW),
    scale=st.floats(0.0, 1e4),
    seed=st.integers(0, 2**32 - 1),
)
def test_update_normalises_and_ess_in_range(lw, scale, seed):
    ll = scale * np.random.default_rng(seed).standard_normal(lw.shape)
    new_lw, w, lse, ess = _check_update(lw, ll)
    n = lw.shape[-1]
    ok = np.isfinite(lse)
    assert np.array_equal(ok, np.any(np.isfinite(lw), axis=-1))
    np.testing.assert_allclose(w[ok].sum(axis=-1), 1.0, rtol=1e-12)
    np.testing.assert_allclose(np.exp(new_lw[ok]), w[ok], rtol=1e-12, atol=1e-300)
    assert np.all(ess[ok] >= 1.0 - 1e-12) and np.all(ess[ok] <= n * (1 + 1e-12))
    assert not np.any(np.isnan(new_lw)) and not np.any(np.isnan(w))
    # degenerate rows: raw sums, zero weights, ESS 0, log-evidence -inf
    assert np.all(w[~ok] == 0.0) and np.all(ess[~ok] == 0.0) and np.all(lse[~ok] == -np.inf)


@settings(max_examples=80, deadline=None)
@given(
    w=arrays(
        np.float64, st.tuples(st.integers(1, 3), st.integers(1, 60)), elements=st.floats(0.0, 1e3)
    )
)
def test_ess_kernel_matches_reference(w):
    got, ref = K.effective_sample_size(w), K.effective_sample_size_reference(w)
    np.testing.assert_allclose(got, ref, rtol=1e-12)
    pos = w.sum(axis=-1) > 0
    assert np.all(got[pos] >= 1 - 1e-12) and np.all(got[pos] <= w.shape[-1] * (1 + 1e-12))


def test_update_with_nan_and_inf_likelihoods():
    lw = np.log(np.full((4, 3), 1 / 3))
    ll = np.array(
        [
            [0.0, np.nan, -1.0],  # NaN counts as -inf: that particle dies
            [-np.inf, -np.inf, -np.inf],  # every likelihood vanished
            [np.inf, 0.0, 0.0],  # +inf: the caller must recover
            [-1e300, -1e300, -2e300],  # tiny but finite: log domain copes
        ]
    )
    new_lw, w, lse, ess = _check_update(lw, ll)
    assert w[0, 1] == 0.0 and np.isclose(w[0].sum(), 1.0)
    assert lse[1] == -np.inf and np.all(w[1] == 0) and ess[1] == 0
    assert lse[2] == np.inf and np.all(w[2] == 0)
    np.testing.assert_allclose(w[3], [0.5, 0.5, 0.0])
    normed = K.normalize_log_weights(new_lw[0])
    np.testing.assert_allclose(normed[1], w[0])


@pytest.mark.parametrize("shape", [(7,), (3, 5), (2, 3, 11), (1, 20_000), (3, 2 * K.CHUNK + 17)])
def test_kernels_match_references_on_shapes(shape):
    rng = np.random.default_rng(0)
    lw = rng.standard_normal(shape)
    ll = 40 * rng.standard_normal(shape)
    _, w, _, _ = _check_update(lw, ll)
    for a, b in zip(K.normalize_log_weights(lw), K.normalize_log_weights_reference(lw)):
        np.testing.assert_allclose(a, b, rtol=1e-12)
    x = rng.standard_normal((*shape, 3)) * [1.0, 10.0, 0.1] + [1e4, -3.0, 0.5]
    m, c = K.weighted_mean_cov(x, w)
    m_ref, c_ref = K.weighted_mean_cov_reference(x, w)
    np.testing.assert_allclose(m, m_ref, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(K.weighted_mean(x, w), m)  # the same first pass
    np.testing.assert_allclose(K.weighted_mean_reference(x, w), m_ref, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(c, c_ref, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(
        K.effective_sample_size(w), K.effective_sample_size_reference(w), rtol=1e-12
    )


def test_batched_rows_equal_single_rows():
    rng = np.random.default_rng(4)
    lw, ll = rng.standard_normal((3, 500)), rng.standard_normal((3, 500))
    x = rng.standard_normal((3, 500, 2))
    batch = K.log_weight_update(lw, ll)
    m, c = K.weighted_mean_cov(x, batch[1])
    for r in range(3):
        single = K.log_weight_update(lw[r], ll[r])
        for a, b in zip(single, batch):
            np.testing.assert_array_equal(a, b[r])
        mr, cr = K.weighted_mean_cov(x[r], batch[1][r])
        np.testing.assert_array_equal(mr, m[r])
        np.testing.assert_array_equal(cr, c[r])


def test_weighted_mean_cov_hand_computed():
    x = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 4.0]])
    w = np.array([2.0, 1.0, 1.0])  # unnormalised on purpose
    m, c = K.weighted_mean_cov(x, w)
    np.testing.assert_allclose(m, [0.5, 1.0])
    r = x - m
    np.testing.assert_allclose(c, np.einsum("n,ni,nj->ij", w / 4, r, r))
