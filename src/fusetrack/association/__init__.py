"""fusetrack.association (see DESIGN.md)."""

from .mcmcda import MCMCDA as MCMCDA
from .mcmcda import MCMCDAConfig as MCMCDAConfig
from .peaks import likelihood_peaks as likelihood_peaks
