"""Helpers shared by the motion-model tests (finite differences, sample-moment checks)."""

from __future__ import annotations

import numpy as np


def numerical_jacobian(f, x: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """Central differences of ``f`` at every row of ``x`` ``(..., d)``: ``(..., d, d)``."""
    d = x.shape[-1]
    cols = []
    for j in range(d):
        e = np.zeros(d)
        e[j] = h
        cols.append((f(x + e) - f(x - e)) / (2 * h))
    return np.stack(cols, axis=-1)


def assert_moments(samples: np.ndarray, mean: np.ndarray, cov: np.ndarray, z: float = 5.0) -> None:
    """Sample mean and covariance agree with ``mean``/``cov`` within ``z`` standard errors.

    Standard errors of a Gaussian sample: mean ``sqrt(C_ii / n)``; covariance entry
    ``sqrt((C_ii C_jj + C_ij^2) / n)``. Entries that are exactly zero in ``cov`` must come out
    within ``z`` standard errors of zero as well (which catches a wrong structure).
    """
    n = samples.shape[0]
    m_hat = samples.mean(axis=0)
    c_hat = np.cov(samples, rowvar=False)
    var = np.diag(cov)
    np.testing.assert_array_less(np.abs(m_hat - mean), z * np.sqrt(var / n) + 1e-12)
    se = np.sqrt((np.outer(var, var) + cov**2) / n)
    np.testing.assert_array_less(np.abs(c_hat - cov), z * se + 1e-12)
