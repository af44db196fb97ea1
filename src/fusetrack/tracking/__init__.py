"""Multi-target tracking assembled from parts: a filter per track, an associator, an initiator
and a deleter, pure (``state = tracker.step(state, time, measurements, rng)``)."""

from .deleters import AnyOf, CovarianceDeleter, Deleter, ExistenceDeleter, MissedCountDeleter
from .existence import predict_existence, update_existence
from .initiators import (
    Initiator,
    InverseMeasurementPrior,
    MofNInitiator,
    SinglePointInitiator,
)
from .mixing import combine_hypotheses
from .scoring import ScoredScan, gate_threshold, mahalanobis_squared, score_scan
from .state import LiveTrack, TrackerState
from .tracker import MultiTargetTracker

__all__ = [
    "AnyOf",
    "CovarianceDeleter",
    "Deleter",
    "ExistenceDeleter",
    "Initiator",
    "InverseMeasurementPrior",
    "LiveTrack",
    "MissedCountDeleter",
    "MofNInitiator",
    "MultiTargetTracker",
    "ScoredScan",
    "SinglePointInitiator",
    "TrackerState",
    "combine_hypotheses",
    "gate_threshold",
    "mahalanobis_squared",
    "predict_existence",
    "score_scan",
    "update_existence",
]
