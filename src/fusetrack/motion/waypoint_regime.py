"""Random-waypoint particle dynamics with three regimes (Ercan et al. 2013, Sec. 4.1, Eq. 5).

State of a particle: ``u = [x, y, tau_x, tau_y, s]`` (position, destination, speed). Each step a
regime is drawn: move toward the destination (MTD) with probability ``beta``, change destination
(CD) with probability ``lambda``, wait (W) otherwise, where ``(beta, lambda) = (0.9, 0.05)`` while
the destination is not reached and ``(0.05, 0.9)`` once it is (``|tau - x| < s``). Then

    MTD: x <- x + s (tau - x)/|tau - x| + v,  v ~ N(0, sigma_v^2 I)      # Ercan et al. 2013, Eq. 5
         s <- (1 - phi) s + phi |x_new - x_old|,  phi = 0.7
    CD:  tau <- uniform over the room, then one MTD step
    W:   nothing changes.

A move that would leave the room or enter a static occluder is rejected (the particle stays;
spec §8 item 17). ``mean`` is the point ``kappa = E[u(t) | u(t-1)]`` of the auxiliary filter's first
stage: the noise-free MTD step, or no move once the destination is reached (spec §8 item 6).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import NDArray

from ..core import ConfigError, check_positive, check_probability, invalid

Array = NDArray[np.float64]


@numba.njit(cache=True, nogil=True)
def regime_move_kernel(
    u: np.ndarray, cd: np.ndarray, dest: np.ndarray, noise: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover - jit
    """A copy of ``u`` with the new destinations ``dest`` on the rows ``cd`` (in order), and for
    every particle the MTD step of Eq. 5 towards its (new) destination: the new position and the
    step length ``|s (tau - x)/|tau - x| + v|``."""
    n = u.shape[0]
    out = u.copy()
    new = np.empty((n, 2))
    travelled = np.empty(n)
    c = 0
    for i in range(n):
        if cd[i]:
            out[i, 2] = dest[c, 0]
            out[i, 3] = dest[c, 1]
            c += 1
        tx, ty = out[i, 2] - out[i, 0], out[i, 3] - out[i, 1]
        dist = math.hypot(tx, ty)
        if dist > 0.0:
            tx, ty = tx / dist, ty / dist
        sx = out[i, 4] * tx + noise[i, 0]
        sy = out[i, 4] * ty + noise[i, 1]
        new[i, 0] = out[i, 0] + sx
        new[i, 1] = out[i, 1] + sy
        travelled[i] = math.hypot(sx, sy)
    return out, new, travelled


@numba.njit(cache=True, nogil=True)
def regime_mean_kernel(u: np.ndarray) -> np.ndarray:  # pragma: no cover - jit
    """``kappa``: a copy of ``u`` with every particle moved one noise-free MTD step towards its
    destination, or left in place once it is within one step of it (``|tau - x| < s``)."""
    out = u.copy()
    for i in range(u.shape[0]):
        tx, ty = u[i, 2] - u[i, 0], u[i, 3] - u[i, 1]
        dist = math.hypot(tx, ty)
        safe = dist if dist > 0.0 else 1.0
        step = 0.0 if dist < u[i, 4] else u[i, 4]
        out[i, 0] = u[i, 0] + step * (tx / safe)
        out[i, 1] = u[i, 1] + step * (ty / safe)
    return out


@numba.njit(cache=True, nogil=True)
def regimes_kernel(
    u: np.ndarray, r: np.ndarray, beta: tuple, lam: tuple
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - jit
    """Each particle's regime from its uniform draw ``r``: MTD (``r < beta``) or CD (``beta <=
    r < beta + lambda``), with ``(beta, lambda)`` = ``(beta[0], lam[0])`` while moving and
    ``(beta[1], lam[1])`` once the destination is reached (``|tau - x| < s``)."""
    n = u.shape[0]
    mtd = np.empty(n, dtype=np.bool_)
    cd = np.empty(n, dtype=np.bool_)
    for i in range(n):
        reached = math.hypot(u[i, 2] - u[i, 0], u[i, 3] - u[i, 1]) < u[i, 4]
        b = beta[1] if reached else beta[0]
        lm = lam[1] if reached else lam[0]
        mtd[i] = r[i] < b
        cd[i] = (r[i] >= b) & (r[i] < b + lm)
    return mtd, cd


@numba.njit(cache=True, nogil=True)
def apply_moves_kernel(
    out: np.ndarray, new: np.ndarray, travelled: np.ndarray, move: np.ndarray, phi: float
) -> None:  # pragma: no cover - jit
    """Moving particles take their new position and speed ``(1 - phi) s + phi |step|`` (in place)."""
    for i in range(out.shape[0]):
        if move[i]:
            out[i, 0] = new[i, 0]
            out[i, 1] = new[i, 1]
            out[i, 4] = (1.0 - phi) * out[i, 4] + phi * travelled[i]


DestinationSampler = Callable[[np.random.Generator, int], Array]
FreeTest = Callable[[Array], NDArray[np.bool_]]


@dataclass(frozen=True)
class WaypointRegimeDynamics:
    """The tracker's transition density ``f(u(t) | u(t-1))`` of Sec. 4.1 (vectorised over particles)."""

    sigma_v: float = 0.33
    phi: float = 0.7
    beta_moving: float = 0.9
    lambda_moving: float = 0.05
    beta_reached: float = 0.05
    lambda_reached: float = 0.9
    dim: int = 5
    position_index: tuple[int, ...] = (0, 1)

    def __post_init__(self) -> None:
        check_positive("sigma_v", self.sigma_v, allow_zero=True)
        check_probability("phi", self.phi)
        for b, lam, name in (
            (self.beta_moving, self.lambda_moving, "moving"),
            (self.beta_reached, self.lambda_reached, "reached"),
        ):
            check_probability(f"beta_{name}", b)
            check_probability(f"lambda_{name}", lam)
            if b + lam > 1 + 1e-12:
                raise ConfigError(invalid(f"beta_{name} + lambda_{name}", b + lam, "<= 1"))

    def initial(
        self, n: int, rng: np.random.Generator, sample_free: DestinationSampler, speed: float
    ) -> Array:
        """``n`` particles: positions and destinations uniform, speed ``speed`` (spec §8 item 16)."""
        u = np.empty((n, 5))
        u[:, :2] = sample_free(rng, n)
        u[:, 2:4] = sample_free(rng, n)
        u[:, 4] = speed
        return u

    @staticmethod
    def _direction(u: Array) -> tuple[Array, Array]:
        to = u[:, 2:4] - u[:, :2]
        dist = np.hypot(to[:, 0], to[:, 1])
        safe = np.where(dist > 0, dist, 1.0)
        return to / safe[:, None], dist

    def mean(self, u: Array) -> Array:
        """``kappa``: the noise-free MTD step, or stay once the destination is reached (one Numba
        pass, :func:`regime_mean_kernel`; :meth:`mean_reference` is the NumPy reference)."""
        return np.asarray(regime_mean_kernel(np.ascontiguousarray(u, dtype=float)))

    def mean_reference(self, u: Array) -> Array:
        """NumPy reference of :meth:`mean` (same result, bit for bit)."""
        direction, dist = self._direction(u)
        reached = dist < u[:, 4]
        out = u.copy()
        out[:, :2] += np.where(reached, 0.0, u[:, 4])[:, None] * direction
        return out

    def sample(
        self,
        u: Array,
        rng: np.random.Generator,
        sample_free: DestinationSampler,
        free: FreeTest | None = None,
    ) -> Array:
        """Draw ``u(t) ~ f(u | u(t-1))`` for every particle (Sec. 4.1).

        The random draws are made here, in the order of :meth:`sample_reference` (regimes, new
        destinations, motion noise); the regimes (:func:`regimes_kernel`) and the moves
        (:func:`regime_move_kernel`) are Numba passes, then the free-floor test, then
        :func:`apply_moves_kernel`.
        """
        n = len(u)
        u = np.ascontiguousarray(u, dtype=float)
        mtd, cd = regimes_kernel(
            u,
            rng.random(n),
            (float(self.beta_moving), float(self.beta_reached)),
            (float(self.lambda_moving), float(self.lambda_reached)),
        )
        dest = sample_free(rng, int(cd.sum())) if cd.any() else np.zeros((0, 2))
        noise = self.sigma_v * rng.standard_normal((n, 2))
        out, new, travelled = regime_move_kernel(
            u, cd, np.ascontiguousarray(dest, dtype=float), noise
        )
        move = mtd | cd
        if free is not None:
            move &= free(new)
        apply_moves_kernel(out, new, travelled, move, float(self.phi))
        return out

    def sample_reference(
        self,
        u: Array,
        rng: np.random.Generator,
        sample_free: DestinationSampler,
        free: FreeTest | None = None,
    ) -> Array:
        """NumPy reference of :meth:`sample` (same random draws, same result)."""
        n = len(u)
        out = u.copy()
        _, dist = self._direction(u)
        reached = dist < u[:, 4]
        beta = np.where(reached, self.beta_reached, self.beta_moving)
        lam = np.where(reached, self.lambda_reached, self.lambda_moving)
        r = rng.random(n)
        mtd = r < beta
        cd = (r >= beta) & (r < beta + lam)
        if cd.any():
            out[cd, 2:4] = sample_free(rng, int(cd.sum()))
        move = mtd | cd
        noise = self.sigma_v * rng.standard_normal((n, 2))
        direction, _ = self._direction(out)
        step = out[:, 4:5] * direction + noise
        new = out[:, :2] + step
        if free is not None:
            move &= free(new)
        out[move, :2] = new[move]
        travelled = np.hypot(step[:, 0], step[:, 1])
        out[move, 4] = (1 - self.phi) * out[move, 4] + self.phi * travelled[move]
        return out
