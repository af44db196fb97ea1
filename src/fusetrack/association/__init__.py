"""fusetrack.association (see DESIGN.md)."""

from .mcmcda import MCMCDA as MCMCDA
from .mcmcda import AssociationState as AssociationState
from .mcmcda import HypothesisSampler as HypothesisSampler
from .mcmcda import MCMCDAConfig as MCMCDAConfig
from .mcmcda import MCMCDAStats as MCMCDAStats
from .peaks import likelihood_peaks as likelihood_peaks
