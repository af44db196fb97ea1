"""Reproduced experiments and the demo; ``REGISTRY`` names them (modules load only when run)."""

from .registry import (
    REGISTRY,
    ExperimentInfo,
    describe,
    options_model,
    run_experiment,
    validate_options,
)

__all__ = [
    "REGISTRY",
    "ExperimentInfo",
    "describe",
    "options_model",
    "run_experiment",
    "validate_options",
]
