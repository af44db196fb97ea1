"""What no multi-target tracker can beat on ``multitarget-bearings``' simulated model (issue 19,
item 3): a floor on the mean over scans of GOSPA², from each target's Cramér-Rao bound.

**The oracle.** It knows the number of targets, which bearing is whose and which are clutter,
and that every target moves on a straight line at constant speed (the truth has no process
noise). Its information about target ``i`` is then that of its own bearings alone: the
deterministic CRLB of :func:`~fusetrack.evaluation.deterministic_crlb` (Taylor 1979; Ristic,
Arulampalam & Gordon 2004, Ch. 4) with ``Q = 0``, one :class:`~fusetrack.sensors.Bearing` per
array and the information reduction factor ``P_D`` per bearing (missed detections; Hernandez,
Farina & Ristic 2006). Its prior at the target's first scan is Gaussian with the covariance of
the model's own entry draws (:func:`entry_prior_cov`: the state at the first scan over many
:func:`~.scenario.simulate_truth` draws). ``online``: the bound at scan ``k`` from the bearings up
to ``k`` (a filter); ``whole_run``: from every bearing of the run, ``B_k = G B_last G^T`` with
``G = F(-(last - k) dt)`` (no process noise: the state at ``k`` is the last one run backwards),
the bound of any estimate made after the run, such as a tracker's retrospective confirmations or
MCMCDA's fixed-lag decisions. Unlabelled, merged and cluttered bearings are a garbling of the
oracle's data (merging ignored, as in Lee 2009's bound, :mod:`..lee2009.bearing_bound`), so a
tracker can only do worse. Two readings, as in that bound: the bound is evaluated along each
run's true path (not averaged over the prior first, as the Van Trees bound would be), and the
prior is a Gaussian stand-in for the model's uniform draws (an estimator using the draws' edges
could do a little better in a target's first scans, before its bearings dominate).

**From the bound to GOSPA** (``p = 2``, ``alpha = 2``, cut-off ``c``). For any estimate set of
``m`` points and ``n`` targets, with ``D_i`` target ``i``'s distance to its nearest estimate::

    d_t^2 >= sum_i min(D_i^2, c^2 / 2) + (c^2 / 2) max(m - n, 0)                 (1)

(a pair of the optimal assignment costs ``D^2`` at least, an unassigned target ``c^2 / 2``, an
estimate beyond ``n`` ``c^2 / 2``). If ``D_i`` errs at least like a centred Gaussian with
covariance ``P >= B`` (the bound's position block; exact for an efficient estimator of the
linearised model, as :mod:`..lee2009.best_possible` assumes), ``D_i`` is stochastically larger
than ``|g|``, ``g ~ N(0, B)`` (Anderson's inequality), and with ``Q = |g|^2``,
``min(Q, b) >= Q - Q^2 / (4 b)`` and ``E Q^2 = (tr B)^2 + 2 tr B^2``::

    E min(D_i^2, b) >= tr B - ((tr B)^2 + 2 tr B^2) / (4 b),     b = c^2 / 2       (2)

(:func:`truncated_square_floor`). The floor is the mean over scans of the sum of (2) over the
targets present: a bound on ``E[mean_t d_t^2]``, the sum of a tracker's time-averaged GOSPA
components (localisation + missed + false, m²), compared as a mean over runs (linear: no RMS
versus mean of roots question; the table's ``gospa`` column, a mean of per-run roots, is not
what it bounds). For the oracle, which reports one estimate per target, all of it is
localisation. Where the assumption of (2) fails: two targets within a few bound-σ of each other
(at a crossing), whose nearest estimate may be the other's; an estimate added to bring a
target's nearest one closer costs ``c^2 / 2`` in (1), more than the floor of a whole scan.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from ...evaluation import deterministic_crlb
from ...motion import ConstantVelocity
from ...sensors import Bearing
from .scenario import Scene, Truth, simulate_truth

Array = NDArray[np.float64]
PRIOR_DRAWS = 4000
"""Draws of :func:`~.scenario.simulate_truth` behind :func:`entry_prior_cov`."""
PRIOR_SEED = 20261203


def truncated_square_floor(cov: Array, b: float) -> Array:
    """Eq. (2): a lower bound on ``E min(|e|^2, b)`` for ``e ~ N(0, P)``, ``P >= cov``
    ``(..., 2, 2)``, clipped at 0: ``(...)``."""
    B = np.asarray(cov, dtype=float)
    tr = np.trace(B, axis1=-2, axis2=-1)
    tr2 = np.einsum("...ij,...ji->...", B, B)
    return np.asarray(np.clip(tr - (tr**2 + 2.0 * tr2) / (4.0 * b), 0.0, None))


def states(positions: Array, dt: float) -> tuple[NDArray[np.intp], Array]:
    """The scans where one target is present ``(T,)`` and its states ``(T, 4)`` there (velocity:
    the constant one, from the first two positions; 0 for a single scan)."""
    on = np.flatnonzero(np.all(np.isfinite(positions), axis=1))
    p = positions[on]
    v = (p[1] - p[0]) / dt if len(on) > 1 else np.zeros(2)
    return on, np.column_stack([p, np.broadcast_to(v, p.shape)])


@lru_cache(maxsize=8)
def entry_prior_cov(scene: Scene, n_targets: int, duration: float) -> Array:
    """``(n_targets, 4, 4)``: the covariance of each target's state at its first scan under the
    model (:data:`PRIOR_DRAWS` draws at a fixed seed; target ``i``'s direction is its parity)."""
    rng = np.random.default_rng(PRIOR_SEED)
    draws: list[list[Array]] = [[] for _ in range(n_targets)]
    for _ in range(PRIOR_DRAWS):
        truth = simulate_truth(scene, n_targets, duration, rng)
        for i in range(n_targets):
            on, x = states(truth.positions[:, i], scene.dt)
            if len(on) > 1:
                draws[i].append(x[0])
    return np.stack([np.cov(np.array(d), rowvar=False) for d in draws])


def position_bounds(scene: Scene, x: Array, prior_cov: Array) -> tuple[Array, Array]:
    """``(online, whole_run)`` position bounds ``(T, 2, 2)`` of one target along its states
    ``x`` ``(T, 4)`` (module docstring)."""
    sensors = [Bearing(sid, position=[sx, sy], sigma=scene.sigma) for sid, sx, sy in scene.arrays]
    motion = ConstantVelocity(ndim=2, q=0.0)
    mask = np.full((len(x), len(sensors)), scene.p_detect)
    B = deterministic_crlb(motion, sensors, x, scene.dt, prior_cov, mask=mask)
    back = np.arange(len(x))[::-1] * scene.dt  # time from scan k to the last one
    G = np.broadcast_to(np.eye(4), (len(x), 4, 4)).copy()
    G[:, 0, 2] = G[:, 1, 3] = -back
    S = G @ B[-1] @ np.swapaxes(G, -1, -2)
    return B[:, :2, :2], S[:, :2, :2]


def run_floors(scene: Scene, truth: Truth, c: float, prior_covs: Array) -> dict[str, float]:
    """The floors of one run (m²): the mean over its scans of the sum over the targets present of
    Eq. (2), ``online`` and ``whole_run``."""
    K, n = truth.positions.shape[:2]
    out = {"online": np.zeros(K), "whole_run": np.zeros(K)}
    for i in range(n):
        on, x = states(truth.positions[:, i], scene.dt)
        if len(on) == 0:
            continue
        for name, B in zip(out, position_bounds(scene, x, prior_covs[i])):
            out[name][on] += truncated_square_floor(B, c**2 / 2.0)
    return {name: float(v.mean()) for name, v in out.items()}
