"""fusetrack.estimation: model parameters from the filters' log-likelihood.

* :func:`log_likelihood` / :class:`LogLikelihood` -- ``log p(z_1:T | model)`` of any
  :class:`~fusetrack.core.LikelihoodFilter` (exact for the Kalman filter, the particle filter's
  estimate), whole-run Numba kernels for linear-Gaussian models;
* :func:`pmmh` -- particle marginal Metropolis-Hastings (Andrieu, Doucet & Holenstein 2010);
* :func:`maximum_likelihood` -- the maximum-likelihood fit of noise parameters with standard
  errors from the observed Fisher information.
"""

from .likelihood import LogLikelihood as LogLikelihood
from .likelihood import log_likelihood as log_likelihood
from .ml import MLFit as MLFit
from .ml import maximum_likelihood as maximum_likelihood
from .ml import observed_information as observed_information
from .pmmh import PMMHResult as PMMHResult
from .pmmh import pmmh as pmmh
from .pmmh import proposal_covariance as proposal_covariance
from .series import Series as Series
from .series import prepare_series as prepare_series

__all__ = [
    "LogLikelihood",
    "MLFit",
    "PMMHResult",
    "Series",
    "log_likelihood",
    "maximum_likelihood",
    "observed_information",
    "pmmh",
    "prepare_series",
    "proposal_covariance",
]
