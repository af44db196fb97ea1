"""What no filter can beat on Lee 2009 Ch. 3's simulated model (issue 19, item 3): the Cramér-Rao
bound on each object's position from the acoustic bearings and the camera fixes of a run.

**The model the runs simulate** (:mod:`.camera_triggering`): each object moves deterministically,
constant velocity except at the scheduled steps where it turns with centripetal acceleration
``alpha`` (:class:`~fusetrack.motion.AccelTurn`, Eqs. 3.12-3.13); a sensor at ``s`` measures its
bearing with Gaussian noise of std ``sigma`` (the sweep's ``sigma^2``, or 3 deg^2 in E3.3/E3.4);
a camera fix, when the cameras are used, is the true position plus ``N(0, sigma_r^2 I)``
(``sigma_r`` = 0.1 m). A filter starts from a camera fix (its prior: the fix, std ``sigma_r``)
and, at step 0 and at an oracle birth, the true velocity (its particles spread by
``init_velocity_std`` = 0.02 m/s); a camera-started object gets velocity 0. The bound's prior at
every start is the fix and the velocity to ``init_velocity_std`` about the truth: what the
step-0 filters are told. A vague velocity prior would make a bound for unbiased estimators
only, which a filter guessing "standing still" for a slow object beats; a prior that tells more
can only lower the bound, so it holds for the camera-started filters too.

**The bound.** The truth has no process noise (``Q = 0``), so the bound is the deterministic
CRLB of the start state propagated along the true trajectory (Taylor 1979; Ristic, Arulampalam &
Gordon 2004, Ch. 4; :func:`~fusetrack.evaluation.deterministic_crlb`)::

    J_{k+1} = F_k^-T J_k F_k^-1 + q_b(k+1) I_b(x_{k+1}) + q_c(k+1) I_c
    I_b = u u^T / (sigma^2 r^2)  (u: the unit vector across the line of sight, r: the range)
    I_c = I / sigma_r^2 on the position

with ``F_k`` the Jacobian of the true step's map at the true state (the scheduled turn, central
differences; passed as ``jacobians=``, the motion argument only gives the state's size), ``q_b = 1`` wherever the object is audible after its start step and ``q_c = 1`` at
the steps its camera fix was used (periodic every ``T_v``, or the run's own triggered steps). The
bound is for an estimator told the manoeuvre schedule and the association: every object has its
own bearing at every audible step (merged bearings, Eq. 3.4, and association errors are
ignored), so it is below what any filter of these runs can reach. It bounds the mean-square
error; a run's RMS over its steps is compared with ``sqrt(mean_k trace B_k[pos])`` over the same
steps (the root of the mean over runs when the camera steps differ between runs). A triggered
run's camera steps depend on its measurements; its bound treats them as a schedule fixed in
advance.

At ``sigma^2 = 0`` the bearings are exact (infinite information): no bound is computed there.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ...core import ConfigError, invalid
from ...evaluation import deterministic_crlb
from ...motion import AccelTurn, ConstantVelocity
from ...sensors import Bearing, PositionFix

Array = np.ndarray
Schedule = Sequence[tuple[float, float, float]]
JACOBIAN_EPS = 1e-6
"""Central-difference step (m, m/s) of the turn steps' Jacobians."""


def turn_alpha(schedule: Schedule, t: float) -> float:
    """The turn acceleration of the step starting at time ``t``: the ``alpha`` of the
    ``(t_start, t_end, alpha)`` window holding it, 0 (constant velocity) outside every window."""
    return next((al for a, b, al in schedule if a <= t + 1e-9 < b), 0.0)


def step_model(alpha: float) -> AccelTurn:
    """The map of one step: constant velocity, or a turn on (x, y) at acceleration ``alpha``."""
    return AccelTurn(2, (0.0, 0.0), (0, 1), alpha) if alpha else AccelTurn(2)


def step_alphas(schedule: Schedule, dt: float, steps: int) -> Array:
    """``(steps - 1,)``: the turn acceleration of each step ``k -> k + 1``."""
    return np.array([turn_alpha(schedule, k * dt) for k in range(steps - 1)], dtype=float)


def transition_jacobians(truth: Array, alphas: Array, dt: float) -> Array:
    """``(T - 1, 4, 4)``: the Jacobian of each step's map at the true state ``truth[k]``
    (``truth`` ``(T, 4)``); constant velocity exactly, a turn by central differences."""
    T = len(truth)
    F = np.broadcast_to(np.eye(4), (T - 1, 4, 4)).copy()
    F[:, 0, 2] = F[:, 1, 3] = dt
    eye = JACOBIAN_EPS * np.eye(4)
    for k in np.flatnonzero(alphas):
        model = step_model(float(alphas[k]))
        plus = model.mean(truth[k] + eye, dt)  # row j: x + eps e_j
        minus = model.mean(truth[k] - eye, dt)
        F[k] = ((plus - minus) / (2 * JACOBIAN_EPS)).T
    return F


def start_cov(sigma_r: float, velocity_std: float) -> Array:
    """The bound's prior at an object's start: a camera fix (std ``sigma_r``) and the velocity
    to ``velocity_std``."""
    if not (sigma_r > 0 and velocity_std > 0):
        valid = "stds > 0 (m, m/s): the prior must be proper"
        raise ConfigError(invalid("sigma_r, velocity_std", (sigma_r, velocity_std), valid))
    return np.diag([sigma_r**2, sigma_r**2, velocity_std**2, velocity_std**2])


def position_bound(
    truth: Array,
    alphas: Array,
    dt: float,
    sensor: tuple[float, float],
    sigma: float,
    bearings: Array,
    camera: Array,
    prior_cov: Array,
    sigma_r: float,
) -> Array:
    """``(T,)``: ``trace B_k[pos]`` (m^2) of one object along ``truth`` ``(T, 4)`` from its
    start (step 0 of the arrays: the prior ``prior_cov``, no measurement), with a bearing at
    the steps ``bearings`` ``(T,)`` and a camera fix at ``camera`` ``(T,)``."""
    if not (sigma > 0 and math.isfinite(sigma)):
        raise ConfigError(invalid("sigma", sigma, "a bearing noise std > 0 (rad)"))
    truth = np.asarray(truth, dtype=float)
    sensors = [
        Bearing("doa", position=list(sensor), sigma=sigma),
        PositionFix("camera", cov=sigma_r**2 * np.eye(2)),
    ]
    info = np.stack([s.fisher_information(truth) for s in sensors], axis=1)  # (T, 2, 4, 4)
    mask = np.column_stack([bearings, camera]).astype(float)
    mask[0] = 0.0  # the start: the prior is the fix; the filter does not update there
    B = deterministic_crlb(
        ConstantVelocity(ndim=2, q=0.0), sensors, truth, dt, prior_cov, mask=mask, information=info,
        jacobians=transition_jacobians(truth, alphas, dt),
    )  # fmt: skip
    return np.asarray(np.trace(B[:, :2, :2], axis1=-2, axis2=-1))


def run_bound_ms(
    truth: Array,
    alphas: Array,
    dt: float,
    sensor: tuple[float, float],
    sigma: float,
    tracked: Array,
    audible: Array,
    camera: Array,
    sigma_r: float,
    velocity_std: float,
) -> Array:
    """``(O,)``: each object's bound on its mean square position error over its tracked steps
    (m^2) in one run: ``truth`` ``(T, O, 4)``, ``alphas`` ``(T - 1, O)``, ``tracked``,
    ``audible``, ``camera`` ``(T, O)`` (the run's own camera-use mask); the prior at each
    object's first tracked step is :func:`start_cov`. NaN for an object never tracked, and for
    ``sigma = 0`` (exact bearings)."""
    O = truth.shape[1]
    out = np.full(O, np.nan)
    if sigma <= 0:
        return out
    prior = start_cov(sigma_r, velocity_std)
    for o in range(O):
        steps = np.flatnonzero(tracked[:, o])
        if len(steps) == 0:
            continue
        s, e = int(steps[0]), int(steps[-1]) + 1
        ms = position_bound(
            truth[s:e, o], alphas[s : e - 1, o], dt, sensor, sigma, audible[s:e, o],
            camera[s:e, o], prior, sigma_r,
        )  # fmt: skip
        out[o] = float(ms[tracked[s:e, o]].mean())
    return out


def periodic_bound_ms(
    truth: Array,
    alphas: Array,
    dt: float,
    sensor: tuple[float, float],
    sigma: float,
    period: int,
    sigma_r: float,
    velocity_std: float,
) -> Array:
    """:func:`run_bound_ms` of a run in which every object is tracked and audible throughout
    from step 0 (velocity known to ``velocity_std``) and the cameras fix every object every
    ``period`` steps from step ``period`` on (0: never; E3.1/E3.2)."""
    T, O = truth.shape[:2]
    every = np.ones((T, O), bool)
    camera = np.zeros((T, O), bool)
    if period > 0:
        camera[period::period] = True
    return run_bound_ms(
        truth, alphas, dt, sensor, sigma, every, every, camera, sigma_r, velocity_std
    )
