"""fusetrack.perception (see DESIGN.md)."""

from . import source_localisation as source_localisation
from .audio_beamforming import Beamformer as Beamformer
from .audio_beamforming import MicrophoneArray as MicrophoneArray
from .harmonic_features import CompressedPsd as CompressedPsd
from .harmonic_features import NodeFeatures as NodeFeatures
from .harmonic_features import node_features as node_features
