"""Data association: the per-scan associator interface, gating and scan scores, GNN, JPDA,
track-oriented MHT, MCMCDA, likelihood peaks."""

from .base import Association as Association
from .base import Associator as Associator
from .base import ScanLikelihoods as ScanLikelihoods
from .base import SingleHypothesis as SingleHypothesis
from .base import hypotheses_of as hypotheses_of
from .clusters import gate_clusters as gate_clusters
from .gating import check_gate_probability as check_gate_probability
from .gating import gate_probability as gate_probability
from .gating import gate_threshold as gate_threshold
from .gating import gaussian_log_density as gaussian_log_density
from .gating import innovation as innovation
from .gating import mahalanobis_distance as mahalanobis_distance
from .gating import mahalanobis_gate as mahalanobis_gate
from .gating import predicted_measurement as predicted_measurement
from .gating import scan_likelihoods as scan_likelihoods
from .gnn import GlobalNearestNeighbour as GlobalNearestNeighbour
from .jpda import JointProbabilisticDataAssociation as JointProbabilisticDataAssociation
from .marginals import belief_propagation_marginals as belief_propagation_marginals
from .marginals import exact_marginals as exact_marginals
from .marginals import joint_events as joint_events
from .mcmcda import MCMCDA as MCMCDA
from .mcmcda import AssociationState as AssociationState
from .mcmcda import HypothesisSampler as HypothesisSampler
from .mcmcda import MCMCDAConfig as MCMCDAConfig
from .mcmcda import MCMCDAStats as MCMCDAStats
from .mht import MHTState as MHTState
from .mht import TrackHypothesis as TrackHypothesis
from .mht import TrackOrientedMHT as TrackOrientedMHT
from .mht import best_global_hypothesis as best_global_hypothesis
from .mht import n_scan_prune as n_scan_prune
from .peaks import likelihood_peaks as likelihood_peaks
from .scores import gated_pairs as gated_pairs
from .scores import log_likelihood_ratios as log_likelihood_ratios
from .scores import validate_scores as validate_scores
