"""fusetrack.management (see DESIGN.md)."""

from .fusion_scheduler import FusionScheduler as FusionScheduler
from .fusion_scheduler import IntakeStats as IntakeStats
from .fusion_scheduler import Packet as Packet
