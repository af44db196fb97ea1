"""Potential-field robot navigation, the aligned-obstacle collision and its fix (Lee 2009, Sec. 5.2.2).

A point robot is pulled to a goal and pushed from an obstacle (Lee 2009, Eqs. 5.9-5.15)::

    F_att = -m c_att rho_g^(m-1) grad rho_g
    F_rep =  n c_rep (1/rho_o - 1/rho_0)^(n-1) (1/rho_o)^2 grad rho_o      (rho_o <= rho_0, else 0)

with ``grad rho`` the unit vector from the goal / obstacle to the robot, and moves ``s_r T_s``
along ``F_att + F_rep`` each step. When robot, obstacle and goal are aligned ("CAROG",
Eqs. 5.16-5.18) the attraction wins until the robot steps onto the obstacle. The fix (Eq. 5.24)
pushes the robot straight away from the obstacle whenever it is within ``s_r T_s + r_r + r_o``
while aligned; that makes it oscillate, which Eq. 5.26 detects (successive forces anti-parallel),
and the escape turns the heading by ``theta_osc = arcsin((r_r + r_o)/d_osc)`` (Eqs. 5.27-5.32;
the text prints "csc"), taking the maximum of the applicable range because the exact ``d_osc``
is unknown. Step 3 of the escape is not specified; here the robot turns its last heading by
``+theta_osc`` (anticlockwise) for one step and then follows the field again.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from ..core import ConfigError, invalid

Array = np.ndarray


@dataclass(frozen=True)
class PotentialField:
    """Goal, obstacle and field constants (defaults: the text's example, Eqs. 5.19-5.22)."""

    goal: tuple[float, float] = (6.0, 6.0)
    obstacle: tuple[float, float] = (8.0, 8.0)
    c_att: float = 0.5
    c_rep: float = 5.0
    m: int = 2
    n: int = 2
    rho0: float = 10.0

    def __post_init__(self) -> None:
        if self.rho0 <= 0 or self.c_att < 0 or self.c_rep < 0:
            raise ConfigError(
                invalid("field", (self.rho0, self.c_att, self.c_rep), "rho0 > 0, c >= 0")
            )

    def attractive(self, p: Array) -> Array:
        d = np.asarray(p, float) - np.asarray(self.goal)
        rho = float(np.hypot(*d))
        if rho == 0.0:
            return np.zeros(2)
        return -self.m * self.c_att * rho ** (self.m - 1) * d / rho  # Lee 2009, Eq. 5.11

    def repulsive(self, p: Array) -> Array:
        d = np.asarray(p, float) - np.asarray(self.obstacle)
        rho = float(np.hypot(*d))
        if rho == 0.0 or rho > self.rho0:
            return np.zeros(2)
        mag = self.n * self.c_rep * (1 / rho - 1 / self.rho0) ** (self.n - 1) / rho**2
        return mag * d / rho  # Lee 2009, Eq. 5.12

    def total(self, p: Array) -> Array:
        return self.attractive(p) + self.repulsive(p)  # Lee 2009, Eq. 5.15

    def aligned(self, p: Array, tol: float = 1e-6) -> bool:
        """Robot, obstacle and goal on one line with the obstacle between (Eq. 5.18)."""
        a = np.asarray(p, float) - np.asarray(self.obstacle)
        b = np.asarray(self.goal, float) - np.asarray(self.obstacle)
        na, nb = np.hypot(*a), np.hypot(*b)
        if na == 0 or nb == 0:
            return False
        return bool(np.dot(a, b) / (na * nb) < -1 + tol)

    def zero_force_distance(self) -> float:
        """``delta``: distance from the obstacle, on the far side from the goal, where the force vanishes."""
        u = np.asarray(self.obstacle, float) - np.asarray(self.goal, float)
        u = u / np.hypot(*u)

        def along(t: float) -> float:
            return float(np.dot(self.total(np.asarray(self.obstacle) + t * u), u))

        lo, hi = 1e-6, self.rho0 - 1e-9
        if along(lo) * along(hi) > 0:
            return math.inf
        return float(brentq(along, lo, hi, xtol=1e-12))


@dataclass
class NavigationResult:
    path: Array  # (steps + 1, 2)
    forces: Array  # (steps, 2) force used at each step
    collided_at: int | None
    oscillation_at: int | None
    reached_goal_at: int | None
    events: list[str] = field(default_factory=list)


def navigate(
    fld: PotentialField,
    start: tuple[float, float] = (12.0, 12.0),
    *,
    step: float = math.sqrt(2.0),
    r_robot: float = 0.0,
    r_obstacle: float = 0.0,
    modified: bool = False,
    escape: bool = False,
    max_steps: int = 60,
) -> NavigationResult:
    """Move the robot ``step`` (= ``s_r T_s``) along the force until goal, collision or ``max_steps``.

    ``modified`` applies Eq. 5.24; ``escape`` the oscillation escape. A collision is a position
    within ``r_robot + r_obstacle`` (or exactly on) the obstacle, or a step that passes through it.
    """
    if step <= 0:
        raise ConfigError(invalid("step", step, "s_r T_s > 0"))
    p = np.asarray(start, float)
    obst, goal = np.asarray(fld.obstacle, float), np.asarray(fld.goal, float)
    reach = step + r_robot + r_obstacle  # Lee 2009, Eq. 5.25
    delta = fld.zero_force_distance()
    path, forces, events = [p.copy()], [], []
    collided = oscillation = reached = None
    prev_f: Array | None = None
    for k in range(1, max_steps + 1):
        f = fld.total(p)
        d_obs = float(np.hypot(*(p - obst)))
        if modified and fld.aligned(p) and delta < reach and d_obs <= reach:
            f = (p - obst) / d_obs  # Lee 2009, Eq. 5.24: a unit push away from the obstacle
        heading = f / max(float(np.hypot(*f)), 1e-300)
        if prev_f is not None and oscillation is None:
            cos = float(np.dot(prev_f, f)) / max(np.hypot(*prev_f) * np.hypot(*f), 1e-300)
            if cos < -1 + 1e-9:  # Lee 2009, Eq. 5.26: anti-parallel successive forces
                oscillation = k
                events.append(f"step {k}: oscillation detected at {p.round(3).tolist()}")
                if escape:
                    inside = d_obs <= reach
                    if inside:
                        theta = math.pi / 2  # sup of [arcsin((r_r+r_o)/reach), pi/2) (Eq. 5.30)
                    else:
                        theta = math.asin(min(1.0, (r_robot + r_obstacle) / reach))  # Eq. 5.31
                    prev_h = prev_f / np.hypot(*prev_f)
                    c, s = math.cos(theta), math.sin(theta)
                    heading = np.array(
                        [c * prev_h[0] - s * prev_h[1], s * prev_h[0] + c * prev_h[1]]
                    )
                    events.append(
                        f"step {k}: escape, heading turned by {math.degrees(theta):.1f} deg"
                    )
        prev_f = f
        new = p + step * heading
        forces.append(f)
        # collision: end point within the radii, or the segment passing through the obstacle
        seg = new - p
        t = float(np.clip(np.dot(obst - p, seg) / np.dot(seg, seg), 0.0, 1.0))
        closest = float(np.hypot(*(p + t * seg - obst)))
        p = new
        path.append(p.copy())
        if closest <= r_robot + r_obstacle + 1e-9:
            collided = k
            events.append(f"step {k}: collision at {p.round(3).tolist()}")
            break
        if float(np.hypot(*(p - goal))) <= step:
            path.append(goal.copy())
            reached = k + 1
            events.append(f"step {k + 1}: goal reached")
            break
    return NavigationResult(
        np.array(path), np.array(forces), collided, oscillation, reached, events
    )
