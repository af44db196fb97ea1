"""What no multi-target tracker can beat on a simulated model with known target paths (issue 19,
item 3): a floor on the mean over scans of GOSPA², from each target's Cramér-Rao bound. Used by
``multitarget-bearings`` (bearings of 2-3 arrays, straight paths) and ``multitarget-benchmark``
(position sensor and radar, nearly constant velocity, births and deaths).

**The oracle.** It knows the number of targets, which report is whose and which are clutter,
and the motion model of the truth (for straight paths: that they are straight, ``Q = 0``). Its
information about target ``i`` is then that of its own reports alone: the posterior CRLB of
:func:`~fusetrack.evaluation.posterior_crlb` (Tichavský, Muravchik & Nehorai 1998; for ``Q = 0``
the deterministic bound of Taylor 1979; Ristic, Arulampalam & Gordon 2004, Ch. 4) along the
target's true path, one sensor model per sensor and the information reduction factor ``P_D`` per
report (missed detections; Hernandez, Farina & Ristic 2006; the expected information, a lower
bound on the mean over detection sequences by Jensen's inequality). Its prior at the target's
first scan is a Gaussian ``P_0`` given by the experiment (``multitarget-bearings``: the
covariance of the model's own entry draws, :func:`entry_prior_cov`; ``multitarget-benchmark``:
the birth intensity's covariance). ``online``: the bound at scan ``k`` from the reports up to
``k`` (a filter); ``whole_run``: from every report of the target's life, the bound of any
estimate made after the run (a tracker's retrospective confirmations, MCMCDA's fixed-lag
decisions): the Rauch-Tung-Striebel backward pass over the bounds (:func:`smoothed_bounds`; the
diagonal blocks of the inverse of the whole path's block-tridiagonal information, exact for
linear motion), with ``Q = 0`` the last scan's bound run backwards, ``F^-1 B F^-T``.
Unlabelled, merged and cluttered reports are a garbling of the oracle's data (merging ignored,
as in Lee 2009's bound, :mod:`..lee2009.bearing_bound`), so a tracker can only do worse. Two
readings, as in that bound: the bound is evaluated along each run's true path (not averaged over
the prior first, as the Van Trees bound would be), and the prior is a Gaussian (for
``multitarget-bearings`` a stand-in for the model's uniform draws: an estimator using the draws'
edges could do a little better in a target's first scans, before its bearings dominate).

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

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from ...core import MotionModel, SensorModel
from ...evaluation import posterior_crlb
from ...motion import ConstantVelocity
from ...sensors import Bearing
from .scenario import Scene, simulate_truth

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


def smoothed_bounds(online: Array, F: Array, Q: Array) -> Array:
    """The whole-run bounds ``(T, d, d)`` from the online ones ``(T, d, d)`` of a linear motion
    ``x_{k+1} = F x_k + w``, ``w ~ N(0, Q)``: the Rauch-Tung-Striebel backward pass
    ``S_k = B_k + C_k (S_{k+1} - F B_k F^T - Q) C_k^T``, ``C_k = B_k F^T (F B_k F^T + Q)^-1``
    (``Q = 0``: ``S_k = F^-1 S_{k+1} F^-T``)."""
    S = np.array(online, dtype=float, copy=True)
    for k in range(len(S) - 2, -1, -1):
        B = S[k]
        P = F @ B @ F.T + Q
        C = np.linalg.solve(P, F @ B).T  # B F^T P^-1 (P, B symmetric)
        D = C @ (S[k + 1] - P) @ C.T
        S[k] = B + 0.5 * (D + D.T)
    return S


@dataclass(frozen=True)
class Oracle:
    """The oracle's model of one target: the truth's motion, the sensors (the order of their
    reports), the scan interval and the detection probability of every sensor."""

    motion: MotionModel
    sensors: Sequence[SensorModel]
    dt: float
    p_detect: float

    def position_bounds(self, x: Array, prior_cov: Array) -> tuple[Array, Array]:
        """``(online, whole_run)`` position bounds ``(T, 2, 2)`` of one target along its states
        ``x`` ``(T, d)`` at consecutive scans (module docstring)."""
        mask = np.full((len(x), len(self.sensors)), self.p_detect)
        B = posterior_crlb(self.motion, list(self.sensors), x, self.dt, prior_cov, mask=mask)
        F = self.motion.jacobian(x[0], self.dt)
        S = smoothed_bounds(B, F, self.motion.noise_cov(self.dt))
        return B[:, :2, :2], S[:, :2, :2]


def bearing_oracle(scene: Scene) -> Oracle:
    """``multitarget-bearings``' oracle: straight paths (``q = 0``), one bearing per array."""
    sensors = [Bearing(sid, position=[sx, sy], sigma=scene.sigma) for sid, sx, sy in scene.arrays]
    return Oracle(ConstantVelocity(ndim=2, q=0.0), sensors, scene.dt, scene.p_detect)


Path = tuple[NDArray[np.intp], Array]
"""One target's scans ``(T,)`` (consecutive) and its true states there ``(T, d)``."""


def run_floors(
    oracle: Oracle, paths: Sequence[Path], n_scans: int, c: float, prior_covs: Sequence[Array]
) -> dict[str, float]:
    """The floors of one run (m²): the mean over its ``n_scans`` scans of the sum over the
    targets present (``paths``, each with its prior ``prior_covs[i]``) of Eq. (2), ``online``
    and ``whole_run``."""
    out = {"online": np.zeros(n_scans), "whole_run": np.zeros(n_scans)}
    for (on, x), prior in zip(paths, prior_covs):
        if len(on) == 0:
            continue
        for name, B in zip(out, oracle.position_bounds(x, prior)):
            out[name][on] += truncated_square_floor(B, c**2 / 2.0)
    return {name: float(v.mean()) for name, v in out.items()}
