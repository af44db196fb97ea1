"""Reproduced experiments and the demo; ``REGISTRY`` names them (modules load only when run)."""

from .registry import REGISTRY, ExperimentInfo, describe, run_experiment

__all__ = ["REGISTRY", "ExperimentInfo", "describe", "run_experiment"]
