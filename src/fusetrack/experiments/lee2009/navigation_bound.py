"""The best possible beside Lee 2009's robot-navigation example (Sec. 5.2.2; issue 19, item 3).

The example estimates nothing: the field is evaluated at the robot's exact position, with no
sensor and no noise, so there is no estimation error and no Cramér-Rao bound. What it does
measure is how many steps of ``s_r T_s`` the robot needs to reach the goal, and that has a
best possible: no planner moving at most ``s_r T_s`` per step reaches the goal in fewer than
``L / (s_r T_s)`` steps, ``L`` the shortest path from start to goal that keeps the robot's
centre ``r_r + r_o`` away from the obstacle's (:func:`shortest_path_length`): the straight line
where it clears the obstacle, else tangent, arc of the clearance circle, tangent.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from ...core import ConfigError, invalid


def shortest_path_length(
    start: ArrayLike, goal: ArrayLike, obstacle: ArrayLike, clearance: float
) -> float:
    """Length of the shortest path from ``start`` to ``goal`` outside the open disc of radius
    ``clearance`` about ``obstacle`` (both ends outside it). With distances ``d_1, d_2`` from
    the obstacle and angle ``θ`` between them seen from it: ``|goal - start|`` when
    ``θ <= acos(c / d_1) + acos(c / d_2)`` (the segment clears the disc), else
    ``sqrt(d_1² - c²) + sqrt(d_2² - c²) + c (θ - acos(c / d_1) - acos(c / d_2))``."""
    s, g, o = (np.asarray(v, dtype=float) for v in (start, goal, obstacle))
    d1, d2 = float(np.hypot(*(s - o))), float(np.hypot(*(g - o)))
    c = float(clearance)
    if c < 0 or min(d1, d2) < c:
        raise ConfigError(invalid("clearance", clearance, f"0 <= clearance <= {min(d1, d2):.3g}"))
    straight = float(np.hypot(*(g - s)))
    if c == 0.0:
        return straight  # the infimum: a path may pass arbitrarily close to a point
    cos = float(np.dot(s - o, g - o)) / (d1 * d2)
    theta = math.acos(max(-1.0, min(1.0, cos)))
    a1, a2 = math.acos(c / d1), math.acos(c / d2)
    if theta <= a1 + a2:
        return straight
    return math.sqrt(d1 * d1 - c * c) + math.sqrt(d2 * d2 - c * c) + c * (theta - a1 - a2)


def min_steps(length: float, step: float) -> int:
    """Fewest moves of at most ``step`` covering ``length`` (a small tolerance for rounding)."""
    if not step > 0:
        raise ConfigError(invalid("step", step, "s_r T_s > 0"))
    return max(0, math.ceil(length / step - 1e-9))


__all__ = ["min_steps", "shortest_path_length"]
