"""Source localisation from raw acoustic features: estimators, not recursive filters.

* :func:`localise` -- several harmonic sources from beamforms and compressed PSDs by Gibbs
  sampling with slice-sampled conditionals (Kushwaha 2010, Ch. IV, Alg. 1);
* :func:`energy_localise` -- energy-based localisation, the chapter's baseline (Eq. 18).
"""

from .energy import energy_localise as energy_localise
from .harmonic import BeamformModel as BeamformModel
from .harmonic import LocalisationResult as LocalisationResult
from .harmonic import localise as localise
from .harmonic import match_error as match_error
from .harmonic_beamform import AcousticNetwork as AcousticNetwork
from .harmonic_beamform import SourceBeamform as SourceBeamform
from .harmonic_frequencies import FrequencyModel as FrequencyModel
from .harmonic_frequencies import estimate_frequencies as estimate_frequencies
from .harmonic_frequencies import harmonic_powers as harmonic_powers
