"""Reproduced experiments and the demo; ``REGISTRY`` names them (modules load only when run)."""

from .registry import (
    REGISTRY,
    ExperimentInfo,
    claim_kinds,
    describe,
    options_model,
    run_experiment,
    validate_options,
)
from .verdicts import PAPERS, paper_verdicts

__all__ = [
    "PAPERS",
    "REGISTRY",
    "ExperimentInfo",
    "claim_kinds",
    "describe",
    "options_model",
    "paper_verdicts",
    "run_experiment",
    "validate_options",
]
