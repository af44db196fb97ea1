"""Evaluation: metrics, Cramér–Rao bounds, the Monte Carlo runner, plots and reports."""

from .crlb import (
    axis_bounds,
    deterministic_crlb,
    position_rmse_bound,
    posterior_crlb,
    posterior_information,
    rmse_bound,
    velocity_rmse_bound,
)
from .metrics import (
    average,
    chi2_interval,
    nees,
    nis,
    ospa,
    ospa_components,
    ospa_over_time,
    position_error,
    rmse,
    track_loss_onset,
    track_loss_rate,
)
from .montecarlo import ENGINES, run_monte_carlo, run_seed
from .report import Claim, Outcome, RunContext, write_outputs

__all__ = [
    "ENGINES",
    "Claim",
    "Outcome",
    "RunContext",
    "average",
    "axis_bounds",
    "chi2_interval",
    "deterministic_crlb",
    "nees",
    "nis",
    "ospa",
    "ospa_components",
    "ospa_over_time",
    "position_error",
    "position_rmse_bound",
    "posterior_crlb",
    "posterior_information",
    "rmse",
    "rmse_bound",
    "run_monte_carlo",
    "run_seed",
    "track_loss_onset",
    "track_loss_rate",
    "velocity_rmse_bound",
    "write_outputs",
]
