"""fusetrack.management (see DESIGN.md)."""

from .camera_selection import brute_force_selection as brute_force_selection
from .camera_selection import greedy_selection as greedy_selection
from .camera_selection import selection_moments as selection_moments
from .camera_selection import subset_mse as subset_mse
from .fusion_scheduler import FusionScheduler as FusionScheduler
from .fusion_scheduler import IntakeStats as IntakeStats
from .fusion_scheduler import Packet as Packet
