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

__all__ = [
    "REGISTRY",
    "ExperimentInfo",
    "claim_kinds",
    "describe",
    "options_model",
    "run_experiment",
    "validate_options",
]
