"""The per-covariance caches of the Gaussian transition mechanics give what the uncached
computation gives, to the bit, and hand out nothing a caller could corrupt.

The reference is the straightforward route written out here: correlation, Cholesky, whitened
residual (the full-rank branch of :func:`gaussian_logpdf`), and ``np.linalg.cholesky`` for
:func:`psd_factor`.
"""

import math

import numpy as np

from fusetrack.filters.proposals import is_gaussian_transition
from fusetrack.motion import ConstantVelocity, ScalarBenchmark
from fusetrack.motion._common import gaussian_logpdf, psd_factor


def _reference_logpdf(resid, cov):
    d = cov.shape[-1]
    sd = np.sqrt(np.diag(cov))
    corr = cov / np.outer(sd, sd)
    chol = np.linalg.cholesky(corr)
    z = (resid / sd) @ np.linalg.inv(chol).T
    logdet = 2.0 * float(np.sum(np.log(np.diag(chol))) + np.sum(np.log(sd)))
    return -0.5 * (d * math.log(2.0 * math.pi) + logdet + np.sum(np.square(z), axis=-1))


def test_logpdf_equals_the_uncached_route_on_repeated_calls():
    cov = np.array([[2.0, 0.6], [0.6, 0.5]])
    resid = np.array([[0.0, 0.0], [1.0, -2.0], [0.3, 0.1]])
    want = _reference_logpdf(resid, cov)
    for _ in range(3):  # the first call fills the cache, the others read it
        assert np.array_equal(gaussian_logpdf(resid, cov), want)
    # hand value at 0: -log(2 pi) - 0.5 log det, det = 1 - 0.36 = 0.64
    assert math.isclose(
        gaussian_logpdf(resid, cov)[0], -math.log(2 * math.pi) - 0.5 * math.log(0.64)
    )
    # another covariance with the same shape is another entry, not the cached one
    cov2 = np.array([[8.0]])
    assert np.array_equal(
        gaussian_logpdf(np.array([[1.0]]), cov2), _reference_logpdf(np.array([[1.0]]), cov2)
    )


def test_singular_cov_still_takes_the_degenerate_route():
    cov = np.array([[1.0, 1.0], [1.0, 1.0]])  # rank 1: support is the line x = y
    on, off = gaussian_logpdf(np.array([[0.5, 0.5], [1.0, -1.0]]), cov, np.array([1.0, 1.0]))
    assert math.isfinite(on) and off == -np.inf


def test_psd_factor_is_a_fresh_copy_of_the_cholesky_factor():
    cov = np.array([[4.0, 2.0], [2.0, 3.0]])
    g = psd_factor(cov)
    assert np.array_equal(g, np.linalg.cholesky(cov))
    g[:] = 0.0  # a caller writing into it does not corrupt the next call
    assert np.array_equal(psd_factor(cov), np.linalg.cholesky(cov))


def test_is_gaussian_transition_cached_and_uncached_agree():
    assert is_gaussian_transition(ScalarBenchmark(), 1.0)
    assert is_gaussian_transition(ScalarBenchmark(), 1.0)  # cached answer, same
    assert is_gaussian_transition(ConstantVelocity(2, q=0.5), 0.1)
    assert not is_gaussian_transition(ConstantVelocity(2, q=0.0), 0.1)  # Q = 0: no density
