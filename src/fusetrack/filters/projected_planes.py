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

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..core import ConfigError, Measurement, Particles, ShapeError, invalid
from ..motion import AccelTurn
from ..sensors import (
    PLANE_AXES,
    PLANES,
    DoaCone,
    DoaSensor3D,
    ProjectedPlaneBearing,
    check_angles,
    literal_second_plane,
    projected_variance,
)
from .particle import ParticleFilter
from .weighting import draw_ancestors, particle_weights

Array = np.ndarray
Pair = tuple[int, str]  # (sensor index, plane)

SELECTIONS = ("literal", "minvar")


def plane_state_index(plane: str) -> list[int]:
    """Indices of a plane's ``[p_a, p_b, v_a, v_b]`` in the 3-D state ``[x, y, z, vx, vy, vz]``."""
    a, b = PLANE_AXES[plane]
    return [a, b, a + 3, b + 3]


@dataclass(frozen=True)
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
    pw = particle_weights(log_lik)
    if pw.any_degenerate:
        return particles, SirStep(particles.mean(axis=0), -np.inf, True)
    mean = pw.weights @ particles
    return particles[draw_ancestors(pw, rng)], SirStep(mean, float(pw.log_sum), False)


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


@dataclass(frozen=True, eq=False)
class PlanesBelief:
    """What :class:`ProjectedPlanesTracker` carries from step to step.

    ``planes`` holds the particles ``(N, 4)`` of every running plane filter (key: sensor index,
    plane); ``fused`` the weighted fused state ``[x, y, z, vx, vy, vz]`` (Eqs. 2.17-2.20; the given
    initial state before the first update) and ``equal`` the equal-weight one (Eq. 2.21);
    ``step`` the index of the step the filters are at (0: the initial state's time) and ``dt``
    the last prediction's interval. ``pairs``, ``log_weight_sums``, ``estimates`` and
    ``degenerate`` report the last update.
    """

    planes: Mapping[Pair, Array]
    fused: Array
    equal: Array
    step: int = 0
    dt: float = 0.0
    pairs: tuple[Pair, Pair] | None = None
    log_weight_sums: Mapping[Pair, float] = field(default_factory=dict)
    estimates: Mapping[Pair, Array] = field(default_factory=dict)
    degenerate: int = 0

    @property
    def mean(self) -> Array:
        return self.fused

    @property
    def cov(self) -> Array:
        """Diagonal: each coordinate's spread in the first running plane filter that has it
        (the plane filters are separate filters; their cross terms are not modelled)."""
        var = np.full(6, np.nan)
        for (_, plane), parts in self.planes.items():
            for j, axis in enumerate(PLANE_AXES[plane]):
                if np.isnan(var[axis]):
                    var[axis], var[axis + 3] = parts[:, j].var(), parts[:, j + 2].var()
        return np.diag(var)


@dataclass
class PpsResult:
    """Per-step output of :meth:`ProjectedPlanesTracker.run`."""

    weighted: Array  # (T, 6)
    equal: Array  # (T, 6)
    pairs: list[tuple[Pair, Pair]]
    log_weight_sums: list[dict[Pair, float]]
    plane_estimates: list[dict[Pair, Array]]
    degenerate_steps: int = 0


def _angles(measurements: Array, n_sensors: int) -> Array:
    z_all = np.asarray(measurements, dtype=float)
    if z_all.ndim != 3 or z_all.shape[1:] != (n_sensors, 2):
        raise ShapeError(invalid("measurements.shape", z_all.shape, f"(T, {n_sensors}, 2)"))
    return z_all


@dataclass
class ProjectedPlanesTracker:
    """PPS with one or several sensors (Lee 2009, Algorithm 1 and Sec. 2.2.3), a
    :class:`~fusetrack.core.models.Filter` over :class:`PlanesBelief`.

    ``predict`` moves every running plane filter; ``update`` takes one ``(theta, phi)``
    :class:`Measurement` per sensor (``sensor_id`` of the sensor), selects the two planes, starts
    a newly selected one, weights each with :class:`ProjectedPlaneBearing` and fuses. ``model``
    is the 3-D motion model; each plane filter uses ``model.restrict(plane axes)`` unless
    ``plane_model_override`` gives another one for a range of steps (to mismatch a filter).
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

    def initial_belief(self, x0: ArrayLike) -> PlanesBelief:
        """The given initial state (the text: "initial object state is given"); the plane
        filters start at the first update, around it."""
        x = np.asarray(x0, dtype=float)
        return PlanesBelief({}, x.copy(), x.copy())

    def measurements(self, time: float, z: Array) -> list[Measurement]:
        """One step's ``(K, 2)`` angles as one measurement per sensor."""
        return [Measurement(time, s.sensor_id, zk) for s, zk in zip(self.sensors, z)]

    def predict(
        self, belief: PlanesBelief, dt: float, rng: np.random.Generator | None = None
    ) -> PlanesBelief:
        """Predict every plane filter that ran at the last step by ``dt``."""
        gen = np.random.default_rng() if rng is None else rng
        n = belief.step + 1
        planes = {
            (k, plane): self.plane_model(n, plane, belief.fused).sample(parts, dt, gen)
            for (k, plane), parts in belief.planes.items()
        }
        return replace(belief, planes=planes, step=n, dt=dt)

    def _angles_of(self, measurements: Sequence[Measurement]) -> Array:
        by_id = {m.sensor_id: m.value for m in measurements}
        missing = [s.sensor_id for s in self.sensors if s.sensor_id not in by_id]
        if missing:
            raise ShapeError(
                invalid("measurements", sorted(by_id), f"one (theta, phi) from each of {missing}")
            )
        z = np.array([by_id[s.sensor_id] for s in self.sensors], dtype=float)
        for zk in z:
            check_angles(zk)
        return z

    def update(
        self,
        belief: PlanesBelief,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> PlanesBelief:
        """Select two planes, weight and resample their filters, fuse (Lee 2009, Algorithm 1)."""
        gen = np.random.default_rng() if rng is None else rng
        z = self._angles_of(measurements)
        pairs, var = select_pairs(z, self.sensors, self.selection)
        new: dict[Pair, Array] = {}
        for pair in pairs:
            if pair in belief.planes:
                new[pair] = belief.planes[pair]
            elif belief.step == 0:
                new[pair] = self._init_particles(belief.fused, pair[1], gen)
            else:
                new[pair] = self._start_from(belief.planes, pair[1], belief.fused, gen, belief.dt)
        est: dict[Pair, Array] = {}
        logw: dict[Pair, float] = {}
        degenerate = 0
        for pair in pairs:
            k, plane = pair
            lik = ProjectedPlaneBearing(self.sensors[k], plane)
            log_lik = lik.log_likelihood(z[k], new[pair], var[k, PLANES.index(plane)])
            new[pair], step = sir_update(new[pair], log_lik, gen)
            degenerate += step.degenerate
            est[pair], logw[pair] = step.mean, step.log_weight_sum
        return replace(
            belief,
            planes=new,
            fused=fuse_planes(est, logw, pairs, weighted=True),
            equal=fuse_planes(est, logw, pairs, weighted=False),
            pairs=pairs,
            log_weight_sums=logw,
            estimates=est,
            degenerate=degenerate,
        )

    def run(self, measurements: Array, dt: float, x0: Array, rng: np.random.Generator) -> PpsResult:
        """Track over ``measurements`` ``(T, K, 2)`` (azimuth, polar per sensor, radians).

        Particles start at ``x0`` plus ``init_std`` noise. Step 0 is an update at ``x0``'s time,
        later steps predict by ``dt`` first.
        """
        z_all = _angles(measurements, len(self.sensors))
        belief = self.initial_belief(x0)
        res = PpsResult(np.zeros((len(z_all), 6)), np.zeros((len(z_all), 6)), [], [], [])
        for n, z in enumerate(z_all):
            if n > 0:
                belief = self.predict(belief, dt, rng)
            belief = self.update(belief, self.measurements(n * dt, z), rng)
            assert belief.pairs is not None
            res.weighted[n], res.equal[n] = belief.fused, belief.equal
            res.degenerate_steps += belief.degenerate
            res.pairs.append(belief.pairs)
            res.log_weight_sums.append(dict(belief.log_weight_sums))
            res.plane_estimates.append(dict(belief.estimates))
        return res

    def _init_particles(self, x: Array, plane: str, rng: np.random.Generator) -> Array:
        idx = plane_state_index(plane)
        std = np.array([self.init_std[0]] * 2 + [self.init_std[1]] * 2)
        return x[idx] + std * rng.standard_normal((self.n_particles, 4))

    def _start_from(
        self,
        running: Mapping[Pair, Array],
        plane: str,
        fused: Array,
        rng: np.random.Generator,
        dt: float,
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


class Direct3DFilter(ParticleFilter):
    """The baseline: one SIR filter on ``[x, y, z, vx, vy, vz]`` with both angles (Lee 2009,
    Sec. 2.2.2): the shared particle engine (:class:`~.particle.ParticleFilter`) weighting by
    :class:`DoaCone` (a likelihood-only sensor) and resampling (systematic) before every
    prediction. A step is degenerate only when every weight vanished (``min_log_evidence``
    is ``-inf``): it then keeps the predicted particles, as :func:`sir_update` does."""

    def __init__(
        self,
        sensor: DoaSensor3D,
        model: AccelTurn,
        n_particles: int = 1000,
        init_std: tuple[float, float] = (0.1, 0.05),
    ) -> None:
        cone: Any = DoaCone(sensor)  # a likelihood-only sensor
        motion: Any = model  # the engine only samples it
        super().__init__(
            motion, {sensor.sensor_id: cone}, n_particles, ess_threshold=1.0,
            min_log_evidence=-np.inf,
        )  # fmt: skip
        self.sensor, self.model, self.init_std = sensor, model, init_std

    def initial_belief(self, x0: ArrayLike, rng: np.random.Generator) -> Particles:
        """``N`` equally weighted particles around ``x0`` (``init_std``: position, velocity)."""
        std = np.array([self.init_std[0]] * 3 + [self.init_std[1]] * 3)
        states = np.asarray(x0, float) + std * rng.standard_normal((self.n_particles, 6))
        return self._particles(states, self._uniform(1, self.n_particles))

    def run(
        self, measurements: Array, dt: float, x0: Array, rng: np.random.Generator
    ) -> Direct3DResult:
        """Track over ``measurements`` ``(T, 2)`` or ``(T, K, 2)`` (the first sensor's angles)."""
        z_all = np.asarray(measurements, dtype=float)
        if z_all.ndim == 3:
            z_all = z_all[:, 0]
        if z_all.ndim != 2 or z_all.shape[1] != 2:
            raise ShapeError(invalid("measurements.shape", z_all.shape, "(T, 2) or (T, K, 2)"))
        belief = self.initial_belief(x0, rng)
        out = Direct3DResult(np.zeros((len(z_all), 6)), np.zeros(len(z_all)))
        log_n = np.log(self.n_particles)
        for n, z in enumerate(z_all):
            check_angles(z)
            if n > 0:
                belief = self.predict(belief, dt, rng)
            before = self.stats.degenerate_steps
            measurement = Measurement(n * dt, self.sensor.sensor_id, z)
            belief, increment = self.update_with_likelihood(belief, [measurement], rng)
            out.estimates[n] = self.mean(belief)
            out.log_weight_sums[n] = float(increment) + log_n  # log W of the unnormalised weights
            out.degenerate_steps += self.stats.degenerate_steps - before
        return out
