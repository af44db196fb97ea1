"""Data association: the per-scan associator interface, MCMCDA, likelihood peaks."""

from .base import Association as Association
from .base import Associator as Associator
from .base import ScanLikelihoods as ScanLikelihoods
from .base import SingleHypothesis as SingleHypothesis
from .base import hypotheses_of as hypotheses_of
from .mcmcda import MCMCDA as MCMCDA
from .mcmcda import AssociationState as AssociationState
from .mcmcda import HypothesisSampler as HypothesisSampler
from .mcmcda import MCMCDAConfig as MCMCDAConfig
from .mcmcda import MCMCDAStats as MCMCDAStats
from .peaks import likelihood_peaks as likelihood_peaks
