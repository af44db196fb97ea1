"""fusetrack.world (see DESIGN.md)."""

from .clocks import HopTranslation as HopTranslation
from .clocks import NodeClock as NodeClock
from .clocks import RbsDomain as RbsDomain
