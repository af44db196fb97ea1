"""fusetrack.perception (see DESIGN.md)."""

from .audio_beamforming import Beamformer as Beamformer
from .audio_beamforming import MicrophoneArray as MicrophoneArray
