"""fusetrack.world (see DESIGN.md)."""

from .clocks import HopTranslation as HopTranslation
from .clocks import NodeClock as NodeClock
from .clocks import RbsDomain as RbsDomain
from .harmonic_sources import HarmonicSource as HarmonicSource
from .harmonic_sources import random_sources as random_sources
from .harmonic_sources import received_signals as received_signals
from .occluder_priors import RandomWalkPriorFilter as RandomWalkPriorFilter
from .occlusion import OccluderPriors as OccluderPriors
from .occlusion import disks_block as disks_block
from .occlusion import occlusion_probability as occlusion_probability
from .occlusion import pattern_probability as pattern_probability
from .room import Room as Room
from .room import l_shaped_room as l_shaped_room
from .room import square_room as square_room
from .walkers import Walk as Walk
from .walkers import WaypointWalkers as WaypointWalkers
from .walkers import polyline_walk as polyline_walk
