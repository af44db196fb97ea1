"""Motion models ``x_k = f(x_{k-1}, dt) + w``, ``w ~ N(0, Q(dt))``, vectorised over ``(..., d)``.

State layout: positions first, then velocities, then accelerations (turn rate last).
See ``linear`` (random walk, constant velocity / acceleration), ``turn`` (coordinated turn) and
``switching`` (Markov-switching sets of models).
"""

from .accel_turn import AccelTurn
from .langevin import Langevin
from .linear import (
    ConstantAcceleration,
    ConstantVelocity,
    RandomWalk,
    kinematic_noise,
    kinematic_transition,
)
from .linear_gaussian import LinearGaussianMotion
from .switching import MarkovSwitching
from .turn import CoordinatedTurn, CoordinatedTurnRate

__all__ = [
    "AccelTurn",
    "ConstantAcceleration",
    "ConstantVelocity",
    "CoordinatedTurn",
    "CoordinatedTurnRate",
    "Langevin",
    "LinearGaussianMotion",
    "ManeuverTurn",
    "MarkovSwitching",
    "RandomWalk",
    "ScalarBenchmark",
    "WaypointRegimeDynamics",
    "kinematic_noise",
    "kinematic_transition",
]

from .benchmark import ScalarBenchmark as ScalarBenchmark
from .maneuver import ManeuverTurn as ManeuverTurn
from .walking_person import WalkingPerson as WalkingPerson
from .walking_person import WalkingPersonCA as WalkingPersonCA
from .waypoint_regime import WaypointRegimeDynamics as WaypointRegimeDynamics
