"""What no position estimate can beat on the simulated NFER tag (issue 19, item 3), beside
Table 5.1 in ``nott2009-radio-accuracy``.

The tag reports ``z = p + b(p) + w`` rounded to 0.098 m (:class:`~fusetrack.sensors.
NferTagSimulator`): ``b`` a building's smooth bias field (a Gaussian field of std ``bias_std``
per axis, correlation length 2 m, new per building), ``w`` white Gaussian of std ``sigma``.
Rounding a reading only removes information (a function of ``z``), so both bounds below,
computed without it, stay below what any estimator of the rounded reading can reach.

* **One reading, no survey** (:func:`reading_mmse`): an estimator that knows the model but not
  the building. At any fixed point the field's marginal is ``N(0, diag(bias_std²))``, so the
  likelihood of ``p`` is ``N(z; p, Σ)`` with ``Σ = diag(bias_std² + sigma²)``; with a flat prior
  over the floor the posterior is ``N(z, Σ)``: the reading itself is the posterior mean and
  ``Σ`` its mean-square error. The tag attains it (up to the rounding's ``q²/12``).
* **A surveyed building** (:func:`known_field_crlb`): even told the whole field ``b``, an
  estimator faces the white noise through the map ``p -> p + b(p)``: Fisher information
  ``A^T diag(sigma²)^-1 A`` with ``A = I + ∂b/∂p`` at the true point (Kay 1993, Vol. I,
  Eq. 3.31), the floor that no calibration can go below.

A mean error is compared with ``E|N(0, C)|`` (:func:`~fusetrack.evaluation.expected_norm`): the
reading's error is Gaussian with covariance ``Σ`` (without the rounding), and an efficient
estimator's covariance is at least the CRLB.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...core import ConfigError, invalid
from ...evaluation import gaussian_information
from ...sensors import NferTagSimulator

Array = NDArray[np.float64]
STEP = 1e-4
"""Central-difference step (m) of the bias field's Jacobian: the field varies over 2 m."""


def reading_mmse(tag: NferTagSimulator) -> Array:
    """``(2, 2)`` mean-square error of the best position estimate from one unrounded reading of
    an unsurveyed building: ``diag(bias_std² + sigma²)`` (the bias counts only for the
    ``"field"`` model)."""
    var = np.asarray(tag.sigma, float) ** 2
    if tag.model == "field":
        var = var + np.asarray(tag.bias_std, float) ** 2
    return np.diag(var)


def bias_jacobian(bias: Callable[[Array], Array], points: ArrayLike) -> Array:
    """``(n, 2, 2)``: ``∂b/∂p`` of a field ``bias`` (``(..., 2) -> (..., 2)``) at ``points``
    ``(n, 2)`` by central differences (column ``j``: the derivative along axis ``j``)."""
    p = np.asarray(points, float)
    if p.ndim != 2 or p.shape[1] != 2:
        raise ConfigError(invalid("points.shape", p.shape, "(n, 2) floor positions (m)"))
    step = STEP * np.eye(2)
    cols = [(bias(p + step[j]) - bias(p - step[j])) / (2 * STEP) for j in range(2)]
    return np.stack(cols, axis=-1)


def known_field_crlb(bias: Callable[[Array], Array], sigma: ArrayLike, points: ArrayLike) -> Array:
    """``(n, 2, 2)``: CRLB of ``p`` at ``points`` from one reading ``p + b(p) + w``, the field
    ``bias`` known, ``w ~ N(0, diag(sigma²))``."""
    s = np.asarray(sigma, float)
    if s.shape != (2,) or np.any(~(s > 0)):
        raise ConfigError(invalid("sigma", sigma, "two white-noise stds > 0 (m)"))
    A = np.eye(2) + bias_jacobian(bias, points)
    return np.asarray(np.linalg.inv(gaussian_information(A / s[:, None], np.ones(len(A)))))


__all__ = ["STEP", "bias_jacobian", "known_field_crlb", "reading_mmse"]
