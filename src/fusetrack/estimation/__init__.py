"""fusetrack.estimation: model parameters from the filters' log-likelihood.

* :func:`log_likelihood` / :class:`LogLikelihood` -- ``log p(z_1:T | model)`` of any
  :class:`~fusetrack.core.LikelihoodFilter` (exact for the Kalman filter, the particle filter's
  estimate), whole-run Numba kernels for linear-Gaussian models;
* :func:`pmmh` -- particle marginal Metropolis-Hastings (Andrieu, Doucet & Holenstein 2010);
* :func:`fit_noise` -- the maximum-likelihood fit of noise parameters with standard errors from
  the observed Fisher information.
"""

from .likelihood import LogLikelihood as LogLikelihood
from .likelihood import log_likelihood as log_likelihood
from .pmmh import PMMHResult as PMMHResult
from .pmmh import pmmh as pmmh
from .pmmh import proposal_covariance as proposal_covariance
from .series import Series as Series
from .series import prepare_series as prepare_series

__all__ = [
    "LogLikelihood",
    "PMMHResult",
    "Series",
    "log_likelihood",
    "pmmh",
    "prepare_series",
    "proposal_covariance",
]
