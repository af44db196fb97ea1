"""fusetrack.filters: recursive Bayesian filters and the loop that runs them (see DESIGN.md).

One import per line, re-exported with ``as``: add new filters by adding lines.
"""

from .cpf_sp import CPFSPProposal as CPFSPProposal
from .detection_fusion import DetectionFusion as DetectionFusion
from .detection_fusion import FusionBelief as FusionBelief
from .detection_pf import DetectionParticleFilter as DetectionParticleFilter
from .grid import DirectionalGridBelief as DirectionalGridBelief
from .grid import GridFilter as GridFilter
from .grid import GridSpec as GridSpec
from .grid import SensorLikelihoods as SensorLikelihoods
from .grid_proposals import DiscretisationProposal as DiscretisationProposal
from .grid_proposals import GalerkinProposal as GalerkinProposal
from .imm import IMMBelief as IMMBelief
from .imm import InteractingMultipleModel as InteractingMultipleModel
from .kalman import ExtendedKalmanFilter as ExtendedKalmanFilter
from .kalman import GaussianFilter as GaussianFilter
from .kalman import KalmanFilter as KalmanFilter
from .kalman import SensorMoments as SensorMoments
from .kalman import UnscentedKalmanFilter as UnscentedKalmanFilter
from .mcmc_moves import IndependenceMove as IndependenceMove
from .mcmc_moves import MHPriorMove as MHPriorMove
from .mcmc_moves import RandomWalkMove as RandomWalkMove
from .multiple_model import MultipleModelParticleFilter as MultipleModelParticleFilter
from .multiple_model import RegimeState as RegimeState
from .multiple_model import RegimeSwitchingProposal as RegimeSwitchingProposal
from .particle import AuxiliaryParticleFilter as AuxiliaryParticleFilter
from .particle import BootstrapFilter as BootstrapFilter
from .particle import ParticleFilter as ParticleFilter
from .particle import RegularizedParticleFilter as RegularizedParticleFilter
from .projected_planes import Direct3DFilter as Direct3DFilter
from .projected_planes import PlanesBelief as PlanesBelief
from .projected_planes import ProjectedPlanesTracker as ProjectedPlanesTracker
from .projected_planes import SirBelief as SirBelief
from .runner import run_filter as run_filter
from .sis import PriorProposal as PriorProposal
from .sis import ProposalParticleFilter as ProposalParticleFilter
from .sis import SISBelief as SISBelief
from .sp_pekf import SPPEKFBank as SPPEKFBank
from .sp_pekf import SPPEKFProposal as SPPEKFProposal
from .stats import FilterStats as FilterStats
from .stats import ValidatedMeasurement as ValidatedMeasurement
from .stats import as_sensor_map as as_sensor_map
from .stats import validate_measurement as validate_measurement
from .waypoint_asir import ASIRBelief as ASIRBelief
from .waypoint_asir import WaypointASIR as WaypointASIR
