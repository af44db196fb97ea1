"""3-D tracking from 2-D plane filters: Projected Planes Selection (Lee 2009, Ch. 2, Algorithm 1).

Instead of one particle filter on the 6-D state, the azimuth/polar-angle measurement of an
acoustic sensor is projected on the xy, yz and zx planes (:mod:`fusetrack.sensors.doa_projection`),
and two 2-D bearings-only SIR filters run on the two selected planes. Their estimates are fused:
each coordinate comes from the plane that has it, and the coordinate both planes share is the
average weighted by the filters' unnormalised weight sums ``W`` (Lee 2009, Eqs. 2.17-2.20) or the
plain average (Eq. 2.21). A plane filter whose model is wrong sees small likelihoods, so its
``W`` is small and it is down-weighted automatically.

Selection rules:

* ``"literal"`` -- as published and applied in all the dissertation's scenarios: xy plus yz when
  ``45 deg <= phi <= 135 deg``, else xy plus zx; with several sensors each proposes its literal
  plane, and if all propose the same one xy of the primary sensor is the second plane
  (the reading that reproduces the text's Scenario 4).
* ``"minvar"`` -- what the method intends: with one sensor xy plus the one of yz, zx with the
  smaller projected variance; with several sensors (Lee 2009, Sec. 2.2.3) the (sensor, plane)
  pair of lowest variance, then the lowest-variance pair on another plane.

Filters run in the global frame (each predicts its sensor's plane bearing through the sensor's
offset and axis polarities), which is Lee 2009, Eqs. 2.22-2.27 with the corrected transform.
When the selection changes, a newly selected plane filter is started by copying, axis by axis,
the particles of filters that were running (the text only says the idle plane "is waiting").

Likelihoods are the unnormalised kernel ``exp(-r^2 / (2 sigma_P^2))`` so that weight sums of
different planes can be compared (Lee 2009, Eq. 2.16 and Sec. 2.2.2); ``sigma_P^2`` is the
projected variance at the measured angles. Weight sums are kept as logarithms; a step whose
weights all underflow is counted in ``degenerate_steps`` and keeps the predicted particles.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.special import logsumexp

from ..core.angles import wrap_angle_inplace
from ..core.errors import ConfigError, ShapeError, invalid
from ..core.resampling import systematic
from ..motion.accel_turn import AccelTurn
from ..sensors.doa_projection import (
    PLANE_AXES,
    PLANES,
    DoaSensor3D,
    check_angles,
    literal_second_plane,
    projected_angles,
    projected_variance,
)

Array = np.ndarray
Pair = tuple[int, str]  # (sensor index, plane)

SELECTIONS = ("literal", "minvar")


def plane_state_index(plane: str) -> list[int]:
    """Indices of a plane's ``[p_a, p_b, v_a, v_b]`` in the 3-D state ``[x, y, z, vx, vy, vz]``."""
    a, b = PLANE_AXES[plane]
    return [a, b, a + 3, b + 3]


@dataclass
class SirStep:
    """What one SIR step reports: the posterior mean and the log of the unnormalised weight sum."""

    mean: Array
    log_weight_sum: float
    degenerate: bool


def sir_update(particles: Array, log_lik: Array, rng: np.random.Generator) -> tuple[Array, SirStep]:
    """Weight, estimate, resample (systematic) -- Lee 2009, Sec. 1.3 steps 2-4.

    ``log_lik`` is the log of the unnormalised kernel of each particle. Returns the resampled
    particles and the step's report. If every weight is zero the predicted particles are kept
    with equal weights and the step is marked degenerate (never NaN).
    """
    log_w_sum = float(logsumexp(log_lik))
    if not np.isfinite(log_w_sum):
        return particles, SirStep(particles.mean(axis=0), -np.inf, True)
    w = np.exp(log_lik - log_w_sum)
    mean = w @ particles
    idx = systematic(w, rng)
    return particles[idx], SirStep(mean, log_w_sum, False)


def select_pairs(
    z: Array, sensors: list[DoaSensor3D], rule: str
) -> tuple[tuple[Pair, Pair], Array]:
    """The two (sensor, plane) pairs to run at this step, and every pair's projected variance ``(K, 3)``."""
    thetas, phis = z[:, 0], z[:, 1]
    var = projected_variance(thetas, phis, np.array([s.sigma**2 for s in sensors]))
    k_count = len(sensors)
    if rule == "literal":
        proposals = [str(p) for p in literal_second_plane(phis)]
        if k_count == 1:
            return ((0, "xy"), (0, proposals[0])), var
        first = (0, proposals[0])
        for k in range(1, k_count):
            if proposals[k] != first[1]:
                return (first, (k, proposals[k])), var
        return (first, (0, "xy")), var
    if rule == "minvar":
        if k_count == 1:
            second = "yz" if var[0, 1] <= var[0, 2] else "zx"
            return ((0, "xy"), (0, second)), var
        order = np.argsort(var, axis=None, kind="stable")
        k1, p1 = np.unravel_index(order[0], var.shape)
        pair1: Pair = (int(k1), PLANES[int(p1)])
        for flat in order[1:]:
            k2, p2 = np.unravel_index(flat, var.shape)
            if int(p2) != int(p1):
                return (pair1, (int(k2), PLANES[int(p2)])), var
    raise ConfigError(invalid("selection", rule, f"one of {SELECTIONS}"))


def fuse_planes(
    estimates: dict[Pair, Array], log_w: dict[Pair, float], pairs: tuple[Pair, Pair], weighted: bool
) -> Array:
    """Assemble the 3-D state ``[x, y, z, vx, vy, vz]`` from two plane estimates (Lee 2009, Eqs. 2.17-2.21).

    A coordinate only one plane has is taken from it; the shared coordinate (position and
    velocity) is averaged with weights ``W_1 : W_2`` (weighted) or ``1 : 1`` (equal).
    """
    (pa, pb) = pairs
    la, lb = log_w[pa], log_w[pb]
    if weighted and np.isfinite(max(la, lb)):
        wa = 1.0 / (1.0 + np.exp(np.clip(lb - la, -700, 700)))
    else:
        wa = 0.5
    out = np.full(6, np.nan)
    for axis in range(3):
        got = []
        for pair, w in ((pa, wa), (pb, 1.0 - wa)):
            axes = PLANE_AXES[pair[1]]
            if axis in axes:
                j = axes.index(axis)
                got.append((w, estimates[pair][[j, j + 2]]))
        if len(got) == 2:
            tot = got[0][0] + got[1][0]
            val = (got[0][0] * got[0][1] + got[1][0] * got[1][1]) / tot
        elif got:
            val = got[0][1]
        else:  # both planes identical and missing this axis: cannot happen with the selection rules
            continue
        out[axis], out[axis + 3] = val
    return out


@dataclass
class PpsResult:
    """Per-step output of :class:`ProjectedPlanesTracker`."""

    weighted: Array  # (T, 6)
    equal: Array  # (T, 6)
    pairs: list[tuple[Pair, Pair]]
    log_weight_sums: list[dict[Pair, float]]
    plane_estimates: list[dict[Pair, Array]]
    degenerate_steps: int = 0


@dataclass
class ProjectedPlanesTracker:
    """PPS with one or several sensors (Lee 2009, Algorithm 1 and Sec. 2.2.3).

    ``model`` is the 3-D motion model; each plane filter uses ``model.restrict(plane axes)``
    unless ``plane_model(step, plane)`` returns another one (used to mismatch a filter).
    """

    sensors: list[DoaSensor3D]
    model: AccelTurn
    n_particles: int = 1000
    selection: str = "literal"
    init_std: tuple[float, float] = (0.1, 0.05)  # position (m), velocity (m/s)
    plane_model_override: dict[str, tuple[int, int, AccelTurn]] = field(default_factory=dict)
    coupling: str = "fused"  # "fused" | "cv": how a plane models an axis turning with a dropped one

    def __post_init__(self) -> None:
        if not self.sensors:
            raise ConfigError(invalid("sensors", self.sensors, "at least one DoaSensor3D"))
        if self.selection not in SELECTIONS:
            raise ConfigError(invalid("selection", self.selection, f"one of {SELECTIONS}"))
        if self.n_particles < 1:
            raise ConfigError(invalid("n_particles", self.n_particles, "an integer >= 1"))
        if self.coupling not in ("fused", "cv"):
            raise ConfigError(invalid("coupling", self.coupling, "'fused' or 'cv'"))

    def plane_model(self, step: int, plane: str, fused: Array | None = None) -> AccelTurn:
        """The model of ``plane`` at ``step``; with ``coupling="fused"`` an axis that turns with
        an axis outside the plane takes the turn's acceleration from the fused estimate ``fused``."""
        if plane in self.plane_model_override:
            start, stop, model = self.plane_model_override[plane]
            if start <= step < stop:
                return model
        state = fused if self.coupling == "fused" else None
        return self.model.restrict(PLANE_AXES[plane], state)

    def _init_particles(self, x: Array, plane: str, rng: np.random.Generator) -> Array:
        idx = plane_state_index(plane)
        std = np.array([self.init_std[0]] * 2 + [self.init_std[1]] * 2)
        return x[idx] + std * rng.standard_normal((self.n_particles, 4))

    def run(self, measurements: Array, dt: float, x0: Array, rng: np.random.Generator) -> PpsResult:
        """Track over ``measurements`` ``(T, K, 2)`` (azimuth, polar per sensor, radians).

        ``x0`` is the given initial state ``[x, y, z, vx, vy, vz]`` (the text: "initial object
        state is given"); particles start at ``x0`` plus ``init_std`` noise. Step 0 is an
        update at ``x0``'s time, later steps predict by ``dt`` first.
        """
        z_all = np.asarray(measurements, dtype=float)
        if z_all.ndim != 3 or z_all.shape[1:] != (len(self.sensors), 2):
            raise ShapeError(
                invalid("measurements.shape", z_all.shape, f"(T, {len(self.sensors)}, 2)")
            )
        x0 = np.asarray(x0, dtype=float)
        particles: dict[Pair, Array] = {}
        res = PpsResult(np.zeros((len(z_all), 6)), np.zeros((len(z_all), 6)), [], [], [])
        fused = x0.copy()
        for n, z in enumerate(z_all):
            for zk in z:
                check_angles(zk)
            pairs, var = select_pairs(z, self.sensors, self.selection)
            if n > 0:  # predict every filter that ran at n - 1
                for (k, plane), parts in particles.items():
                    particles[(k, plane)] = self.plane_model(n, plane, fused).sample(parts, dt, rng)
            new: dict[Pair, Array] = {}
            for pair in pairs:
                if pair in particles:
                    new[pair] = particles[pair]
                elif n == 0:
                    new[pair] = self._init_particles(x0, pair[1], rng)
                else:
                    new[pair] = self._start_from(particles, pair[1], fused, rng, dt, n)
            est: dict[Pair, Array] = {}
            logw: dict[Pair, float] = {}
            for pair in pairs:
                k, plane = pair
                sensor = self.sensors[k]
                zp = projected_angles(z[k, 0], z[k, 1])[PLANES.index(plane)]
                parts = new[pair]
                r = sensor.plane_bearing_2d(parts[:, 0], parts[:, 1], plane) - zp
                wrap_angle_inplace(r)
                log_lik = -0.5 * r * r / var[k, PLANES.index(plane)]  # Lee 2009, Eq. 2.16
                new[pair], step = sir_update(parts, log_lik, rng)
                res.degenerate_steps += step.degenerate
                est[pair], logw[pair] = step.mean, step.log_weight_sum
            particles = new
            res.weighted[n] = fuse_planes(est, logw, pairs, weighted=True)
            res.equal[n] = fuse_planes(est, logw, pairs, weighted=False)
            fused = res.weighted[n]
            res.pairs.append(pairs)
            res.log_weight_sums.append(logw)
            res.plane_estimates.append(est)
        return res

    def _start_from(
        self,
        running: dict[Pair, Array],
        plane: str,
        fused: Array,
        rng: np.random.Generator,
        dt: float,
        step: int,
    ) -> Array:
        """Particles of a newly selected plane, axis by axis from running filters (else the fused estimate)."""
        out = np.empty((self.n_particles, 4))
        predicted = self.model.mean(fused, dt)
        for j, axis in enumerate(PLANE_AXES[plane]):
            for (_, other), parts in running.items():
                if axis in PLANE_AXES[other]:
                    i = PLANE_AXES[other].index(axis)
                    out[:, j], out[:, j + 2] = parts[:, i], parts[:, i + 2]
                    break
            else:
                out[:, j] = predicted[axis] + self.init_std[0] * rng.standard_normal(
                    self.n_particles
                )
                out[:, j + 2] = predicted[axis + 3] + self.init_std[1] * rng.standard_normal(
                    self.n_particles
                )
        return out


@dataclass
class Direct3DResult:
    estimates: Array  # (T, 6)
    log_weight_sums: Array  # (T,)
    degenerate_steps: int = 0


@dataclass
class Direct3DFilter:
    """The baseline: one SIR filter on ``[x, y, z, vx, vy, vz]`` with both angles (Lee 2009, Sec. 2.2.2).

    Likelihood ``exp(-dtheta^2/(2 s^2)) exp(-dphi^2/(2 s^2))`` (unnormalised, the "cone" of [22])
    with the azimuth residual wrapped.
    """

    sensor: DoaSensor3D
    model: AccelTurn
    n_particles: int = 1000
    init_std: tuple[float, float] = (0.1, 0.05)

    def run(
        self, measurements: Array, dt: float, x0: Array, rng: np.random.Generator
    ) -> Direct3DResult:
        z_all = np.asarray(measurements, dtype=float)
        if z_all.ndim == 3:
            z_all = z_all[:, 0]
        if z_all.ndim != 2 or z_all.shape[1] != 2:
            raise ShapeError(invalid("measurements.shape", z_all.shape, "(T, 2) or (T, K, 2)"))
        std = np.array([self.init_std[0]] * 3 + [self.init_std[1]] * 3)
        parts = np.asarray(x0, float) + std * rng.standard_normal((self.n_particles, 6))
        s2 = self.sensor.sigma**2
        out = Direct3DResult(np.zeros((len(z_all), 6)), np.zeros(len(z_all)))
        for n, z in enumerate(z_all):
            check_angles(z)
            if n > 0:
                parts = self.model.sample(parts, dt, rng)
            theta, phi = self.sensor.angles(parts[:, :3])
            dth = wrap_angle_inplace(theta - z[0])
            dph = phi - z[1]
            log_lik = -0.5 * (dth * dth + dph * dph) / s2
            parts, step = sir_update(parts, log_lik, rng)
            out.estimates[n] = step.mean
            out.log_weight_sums[n] = step.log_weight_sum
            out.degenerate_steps += step.degenerate
        return out
