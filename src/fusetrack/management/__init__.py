"""Sensor management: camera selection and triggering, sensor activation, fusion scheduling."""

from .camera_selection import SELECTION_METHODS as SELECTION_METHODS
from .camera_selection import SelectionMoments as SelectionMoments
from .camera_selection import brute_force_selection as brute_force_selection
from .camera_selection import closest_selection as closest_selection
from .camera_selection import fixed_selection as fixed_selection
from .camera_selection import greedy_selection as greedy_selection
from .camera_selection import random_selection as random_selection
from .camera_selection import selection_moments as selection_moments
from .camera_selection import subset_mse as subset_mse
from .camera_triggering import AcousticTracker as AcousticTracker
from .camera_triggering import CooperationPolicy as CooperationPolicy
from .camera_triggering import run_cooperation as run_cooperation
from .camera_triggering import run_periodic_batch as run_periodic_batch
from .fusion_scheduler import FusionScheduler as FusionScheduler
from .fusion_scheduler import IntakeStats as IntakeStats
from .fusion_scheduler import Packet as Packet
from .intensity_activation import activation_radius as activation_radius
from .intensity_activation import active_sensors as active_sensors
from .intensity_activation import intensity_weights as intensity_weights
from .network_traffic import PROTOCOLS as PROTOCOLS
from .network_traffic import NetworkConfig as NetworkConfig
from .network_traffic import simulate_traffic as simulate_traffic
