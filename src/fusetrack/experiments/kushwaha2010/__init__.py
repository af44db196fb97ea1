"""Kushwaha 2010 (seed 003): audio + video sensor network — beamforming, grid fusion, MCMCDA, harmonic sources, smart cameras.

Scenarios, constants and experiments of the paper; uses the library and is never imported by it.
"""

from .scene import DT, default_layout

__all__ = ["DT", "default_layout"]
