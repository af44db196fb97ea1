"""What no filter can beat on a Zhai 2007 model (issue 19, item 3): the rows printed beside
every table, and the claims that label a paper number below them *impossible on the printed
model*.

Three kinds of row, all on the runs' own truths and measurements:

* **posterior mean**: a bootstrap filter with many particles (``n``; its estimate, the mean of
  the resampled particles, converges to the posterior mean ``E[x_t | z_1:t]``, which minimises
  every step's mean-square error among all estimators that see the same measurements and
  prior; Anderson & Moore 1979, Sec. 2.3). It is an achievable estimate, so it bounds the optimum
  from above; its agreement with the bootstrap at ``n / 5`` or fewer particles shows it has
  converged.
* **PCRB**: the posterior Cramér-Rao bound (Tichavský, Muravchik & Nehorai 1998;
  :func:`~fusetrack.evaluation.posterior_crlb`), a lower bound on every estimator's mean-square
  error, averaged over truths drawn from the model (where the regularity conditions hold).
* **trivial estimators**: one measurement inverted on its own (the cube root of ``z = x^3 + v``),
  or the prior mean carried forward; a filter the paper reports worse than these is of no use.

Paper tables give the mean and the variance over runs of the per-run RMSE; the root mean square
over runs, ``sqrt(mean^2 + var)``, is what a mean-square bound bounds (:func:`paper_rms`), and
ours is compared the same way (:func:`rms_over_runs`). A paper number below the posterior
mean's by more than three standard errors cannot come from the model as printed. The judging
(statistics, verdicts, claims) is generic and lives in :mod:`fusetrack.evaluation.best_possible`;
it is re-exported here under the names the Zhai experiments use.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...core import Gaussian, MotionModel, SensorModel
from ...evaluation import (
    IMPOSSIBLE,
    MARGIN_SE,
    NOT_FROM_MODEL,
    POSSIBLE,
    best_table,
    converged_claim,
    mean_with_se,
    paper_rms,
    possible_claim,
    posterior_crlb,
    rms_over_runs,
    rmse_bound,
)
from ...evaluation import best_possible_verdict as verdict
from ...filters import ProposalParticleFilter
from .common import Array, Steps, timed_sis

BEST_N = {"full": 10_000, "quick": 2_000}
"""Particles of the posterior-mean bootstrap at full size and with ``--quick``."""


def best_n(quick: bool) -> int:
    """The posterior-mean bootstrap's particle count for this run size."""
    return BEST_N["quick" if quick else "full"]


def posterior_mean(
    motion: MotionModel,
    sensors: Sequence[SensorModel],
    prior: Gaussian,
    zs: Steps,
    dt: float,
    n: int,
    rng: np.random.Generator,
) -> tuple[Array, float]:
    """Estimates ``(T, d)`` of a bootstrap filter with ``n`` particles (the posterior mean's
    approximation) and its seconds."""
    filt = ProposalParticleFilter(motion, list(sensors), n_particles=n)
    est, secs, _ = timed_sis(filt, prior, zs, dt, rng)
    return est, secs


@dataclass(frozen=True)
class Regularised:
    """``motion`` with ``delta * I`` added to its process-noise covariance, so that a model
    whose noise is rank-deficient (Zhai 2007 Eq. 34's ``Gamma Q Gamma^T``) has a PCRB: the
    bound of the regularised model tends to the degenerate model's as ``delta -> 0`` (the
    recursion is continuous in ``Q`` while ``J`` stays invertible)."""

    motion: Any
    delta: float

    def __getattr__(self, name: str) -> Any:
        return getattr(self.motion, name)

    def noise_cov(self, dt: float) -> Array:
        Q = np.asarray(self.motion.noise_cov(dt), dtype=float)
        return Q + self.delta * np.eye(Q.shape[0])

    def jacobian(self, x: Any, dt: float) -> Array:
        return np.asarray(self.motion.jacobian(x, dt), dtype=float)


def pcrb_rms(
    motion: MotionModel,
    sensors: Sequence[SensorModel],
    trajectories: Array,
    dt: float,
    prior_cov: Array,
    index: Sequence[int],
) -> Array:
    """The PCRB on the root-mean-square error of the components ``index``, per step ``(T,)``.

    ``trajectories`` ``(R, T + 1, d)`` start at ``x_0`` (drawn from the prior) with no
    measurement there; steps ``1..T`` carry one measurement of every sensor, as in the runs."""
    T1 = trajectories.shape[1]
    mask = np.ones((T1, len(sensors)))
    mask[0] = 0.0
    bound = posterior_crlb(motion, list(sensors), trajectories, dt, prior_cov, mask=mask)
    return np.asarray(rmse_bound(bound, index))[1:]


def simulate_many(
    step: Callable[[Array, np.random.Generator], Array],
    x0: Array,
    steps: int,
    rng: np.random.Generator,
) -> Array:
    """``(R, steps + 1, d)`` truths from ``x0`` ``(R, d)``, one vectorised ``step`` per time."""
    xs = [np.asarray(x0, dtype=float)]
    for _ in range(steps):
        xs.append(np.asarray(step(xs[-1], rng), dtype=float))
    return np.stack(xs, axis=1)


__all__ = [
    "BEST_N",
    "IMPOSSIBLE",
    "MARGIN_SE",
    "NOT_FROM_MODEL",
    "POSSIBLE",
    "Regularised",
    "best_n",
    "best_table",
    "converged_claim",
    "mean_with_se",
    "paper_rms",
    "pcrb_rms",
    "possible_claim",
    "posterior_mean",
    "rms_over_runs",
    "simulate_many",
    "verdict",
]
