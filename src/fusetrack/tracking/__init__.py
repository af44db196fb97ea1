"""Multi-target tracking assembled from parts: a filter per track, an associator, an initiator
and a deleter, pure (``state = tracker.step(state, time, measurements, rng)``):
:class:`MultiTargetTracker` (GNN, JPDA, any single-scan associator), :class:`MHTTracker`
(track-oriented MHT, a belief per hypothesis leaf), :class:`MCMCDATracker` (online MCMCDA on
position reports), :class:`PHDTracker` (a GM-PHD intensity's labelled components),
:class:`PMBTracker` (the track-oriented Poisson multi-Bernoulli filter :class:`PMBFilter`,
Williams 2015) and :class:`SingleTargetTracker` (any filter as a one-track tracker), all behind
one interface (:class:`Tracker`: ``initial_state / step``)."""

from .deleters import AnyOf, CovarianceDeleter, Deleter, ExistenceDeleter, MissedCountDeleter
from .existence import predict_existence, update_existence, update_existences
from .initiators import (
    Initiator,
    InverseMeasurementPrior,
    MofNInitiator,
    SinglePointInitiator,
)
from .mcmcda_tracker import MCMCDATracker, MCMCDATrackerState
from .mht_tracker import MHTTracker, MHTTrackerState
from .mixing import combine_hypotheses, combine_stacked
from .phd_initiator import PHDBirthState, PHDInitiator
from .phd_tracker import PHDTracker, PHDTrackerState
from .pmb import PMBDensity, PMBFilter
from .pmb_tracker import PMBTracker, PMBTrackerState, cardinality_distribution
from .protocol import Tracker, TrackView, belief_summary
from .single_target import SingleTargetState, SingleTargetTracker
from .state import LiveTrack, TrackerState, TrackerStats
from .tracker import MultiTargetTracker

__all__ = [
    "AnyOf",
    "CovarianceDeleter",
    "Deleter",
    "ExistenceDeleter",
    "Initiator",
    "InverseMeasurementPrior",
    "LiveTrack",
    "MCMCDATracker",
    "MCMCDATrackerState",
    "MHTTracker",
    "MHTTrackerState",
    "MissedCountDeleter",
    "MofNInitiator",
    "MultiTargetTracker",
    "PHDBirthState",
    "PHDInitiator",
    "PHDTracker",
    "PHDTrackerState",
    "PMBDensity",
    "PMBFilter",
    "PMBTracker",
    "PMBTrackerState",
    "SinglePointInitiator",
    "SingleTargetState",
    "SingleTargetTracker",
    "TrackView",
    "Tracker",
    "TrackerState",
    "TrackerStats",
    "belief_summary",
    "cardinality_distribution",
    "combine_hypotheses",
    "combine_stacked",
    "predict_existence",
    "update_existence",
    "update_existences",
]
