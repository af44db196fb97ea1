"""When to ask the cameras: periodic and triggered visual cooperation (Lee 2009, Secs. 3.2.2-3.3).

One acoustic sensor tracks several objects with one :class:`MultiModelBearingPF` each. A pair of
cameras can localise (and identify) every object in view, at a cost; they are asked

* periodically, every ``period`` steps (Sec. 3.3.1), or
* when a trigger fires (Sec. 3.3.2-3.3.3):

  - (3.14) *count*: the number of bearings differs from the number of tracked objects
    (merged bearings, objects entering or leaving, silence) -- all objects are localised, new
    ones get filters, objects the cameras no longer see are dropped;
  - (3.15) *bearing gate*: no bearing within ``+-gate_k sigma`` of an object's estimated bearing;
  - (3.16) *particle ellipse*: the estimate lies outside every model's 95 % ellipse of its
    predicted particles (chi-square(2) = 5.991; the text says "95 % (2 sigma)", 2 sigma would be
    4.0).

A camera fix resets the object's particles around it (velocities kept) and becomes the step's
estimate. The triggers are pure functions so that each can be tested on its own.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core import ConfigError, invalid
from ..filters import (
    MULTI_MODEL_ESTIMATORS,
    MultiModelBearingPF,
    MultiModelBelief,
    finite_bearings,
    resample_l,
    reset_to_fix,
    take_resampled,
    weigh_every_model,
)
from ..sensors import merge_close, simulate_bearings, true_bearings

Array = np.ndarray

CHI2_2_95 = 5.991464547107979


def count_trigger(n_bearings: int, n_tracked: int) -> bool:
    """Lee 2009, Eq. 3.14: ``N(z(k)) != I(k-1)``."""
    return int(n_bearings) != int(n_tracked)


def bearing_gate_trigger(
    estimate: Array, sensor: tuple[float, float], bearings: Array, sigma: float, k: float = 2.0
) -> bool:
    """Lee 2009, Eq. 3.15: every bearing is farther than ``k sigma`` from the estimate's bearing."""
    z = np.asarray(bearings, float).reshape(-1)
    if z.size == 0:
        return True
    b = math.atan2(estimate[1] - sensor[1], estimate[0] - sensor[0])
    d = np.abs(np.mod(z - b + math.pi, 2 * math.pi) - math.pi)
    return bool(np.all(d > k * sigma))


def ellipse_trigger(estimate: Array, predictions: Array, chi2: float = CHI2_2_95) -> bool:
    """Lee 2009, Eq. 3.16: the estimate is outside the ellipse of every model's predicted positions.

    ``predictions`` ``(J, L, >=2)``; each model's ellipse is ``(p - mu)^T S^-1 (p - mu) <= chi2``
    with the particles' mean and covariance (a singular covariance gets a tiny ridge).
    """
    p = np.asarray(estimate, float)[:2]
    for pts in np.asarray(predictions, float)[..., :2]:
        mu = pts.mean(axis=0)
        cov = _sample_cov(pts) + _RIDGE
        d = p - mu
        if float(d @ np.linalg.solve(cov, d)) <= chi2:
            return False
    return True


_RIDGE = 1e-12 * np.eye(2)


def _sample_cov(pts: Array) -> Array:
    """``np.cov(pts.T)`` for ``pts (L, 2)`` without its argument handling: the same operations
    on the same memory layout (a copy of the transpose, row means, ``dot``, times ``1 / (L - 1)``),
    so the same bits (tested)."""
    X = np.array(pts.T, dtype=float)
    X -= X.mean(axis=1)[:, None]
    c = np.dot(X, X.T.conj())
    c *= np.true_divide(1, X.shape[1] - 1)
    return c


@dataclass(frozen=True)
class CooperationPolicy:
    """Which camera requests are allowed: ``period`` (steps) or any subset of the three triggers."""

    count: bool = False
    gate: bool = False
    ellipse: bool = False
    period: int | None = None
    apply_fixes: bool = True  # False: evaluate the triggers but never use the cameras
    gate_k: float = 2.0
    chi2: float = CHI2_2_95

    def __post_init__(self) -> None:
        if self.period is not None and self.period < 1:
            raise ConfigError(invalid("period", self.period, "an integer >= 1 (steps) or None"))

    @property
    def uses_cameras(self) -> bool:
        return self.apply_fixes and (
            self.count or self.gate or self.ellipse or self.period is not None
        )

    @classmethod
    def triggering(cls, **kw: Any) -> CooperationPolicy:
        return cls(count=True, gate=True, ellipse=True, **kw)


@dataclass(frozen=True)
class AcousticTracker:
    """The per-object multi-model bearing PF of Lee 2009 Sec. 3.3 and how objects are started.

    ``sigma_filter`` (default: the measurement's ``sigma``) is the bearing std the filter assumes;
    ``sigma_r`` the std of a camera fix; ``dz_critical`` the separation below which two bearings
    merge (Eq. 3.4); ``known_initial_velocity``: filters started at step 0 or by an oracle birth
    begin at the true velocity (the text's "initial state given"), camera-started ones never;
    ``engine`` "numba": the fused kernel, "numpy": the reference (same draws, equal to rounding);
    ``estimator`` "consistent" (convex JPDA average) or "literal" (the printed chain (3.7)-(3.11),
    :class:`MultiModelBearingPF`).
    """

    models: tuple
    dt: float
    n_particles: int = 500
    sigma_filter: float | None = None
    sigma_r: float = 0.1
    dz_critical: float = math.radians(2.0)
    init_velocity_std: float = 0.3
    known_initial_velocity: bool = False
    engine: str = "numba"
    estimator: str = "consistent"

    def __post_init__(self) -> None:
        if self.engine not in ("numba", "numpy"):
            raise ConfigError(invalid("engine", self.engine, "'numba' or 'numpy'"))
        if self.estimator not in MULTI_MODEL_ESTIMATORS:
            raise ConfigError(
                invalid("estimator", self.estimator, f"one of {MULTI_MODEL_ESTIMATORS}")
            )

    def build(self, sensor: tuple[float, float], sigma: float) -> MultiModelBearingPF:
        """The filter for a sensor at ``sensor`` whose bearings have std ``sigma``."""
        return MultiModelBearingPF(
            self.models, sensor, self.sigma_filter or sigma, self.n_particles,
            estimator=self.estimator, engine=self.engine,
        )  # fmt: skip

    @property
    def start_std(self) -> Array:
        """Std of a new filter's particles around a camera fix: ``(x, y, vx, vy)``."""
        r, v = self.sigma_r, self.init_velocity_std
        return np.array([r, r, v, v])


@dataclass
class CooperationResult:
    estimates: Array  # (T, O, 4) NaN when the object is not tracked
    tracked: Array  # (T, O) bool
    camera_updates: Array  # (T, O) bool: the object got a camera fix
    fired: Array  # (T, 3) bool: count, gate, ellipse fired (any object) at the step
    fired_any: Array  # (T,) bool
    n_bearings: Array  # (T,)
    degenerate_steps: int = 0
    notes: list[str] = field(default_factory=list)


def run_cooperation(
    truth: Array,
    present: Array,
    audible: Array,
    sensor: tuple[float, float],
    sigma: float,
    policy: CooperationPolicy,
    rng: np.random.Generator,
    tracker: AcousticTracker,
    *,
    oracle_births: bool | None = None,
    camera_available: Array | None = None,
) -> CooperationResult:
    """Track ``O`` objects over ``T`` steps with one acoustic sensor and camera cooperation.

    ``truth`` ``(T, O, 4)``; ``present`` ``(T, O)``: the object is in the sensor's range (the
    cameras see it); ``audible`` ``(T, O)``: it emits a bearing (present and not silent).
    At step 0 the cameras localise every present object. When the policy cannot discover objects
    (no cameras, or neither the count trigger nor a period; ``oracle_births`` defaults to True
    then) objects are started from a noisy camera-like fix when they appear and dropped when
    they leave, so that errors are defined and comparable.
    ``camera_available`` ``(T,)`` False: the cameras do not answer at that step (request lost).
    ``tracker``: the filter and how objects start (:class:`AcousticTracker`).
    """
    truth = np.asarray(truth, float)
    T, O = truth.shape[:2]
    present = np.asarray(present, bool)
    audible = np.asarray(audible, bool) & present
    if present.shape != (T, O) or audible.shape != (T, O):
        raise ConfigError(invalid("present/audible shape", present.shape, f"({T}, {O})"))
    # A policy that can never look for new objects (no count trigger, no period) gets them from
    # an oracle, so that its other conditions are compared on the same objects.
    can_discover = policy.apply_fixes and (policy.count or policy.period is not None)
    births = (not can_discover) if oracle_births is None else oracle_births
    answer = np.ones(T, bool) if camera_available is None else np.asarray(camera_available, bool)
    filt = tracker.build(sensor, sigma)
    res = CooperationResult(
        np.full((T, O, 4), np.nan),
        np.zeros((T, O), bool),
        np.zeros((T, O), bool),
        np.zeros((T, 3), bool),
        np.zeros(T, bool),
        np.zeros(T, int),
    )
    parts: dict[int, MultiModelBelief] = {}
    for o in range(O):  # step 0: the cameras find every present object
        if present[0, o]:
            parts[o], _ = _start(filt, tracker, truth[0, o], rng, tracker.known_initial_velocity)
    n_tracked_prev = len(parts)
    for k in range(T):
        z = simulate_bearings(truth[k, :, :2], audible[k], sensor, sigma, rng, tracker.dz_critical)
        res.n_bearings[k] = len(z)
        bearings = finite_bearings(z)  # what filt.step makes of one measurement per bearing
        est: dict[int, Array] = {}
        steps = {}
        if k > 0:
            for o, b in list(parts.items()):
                parts[o] = steps[o] = filt.step_bearings(b, tracker.dt, bearings, rng)
                est[o] = steps[o].mean
                res.degenerate_steps += steps[o].degenerate
        else:
            for o, b in parts.items():
                est[o] = b.states.mean(axis=0)
        fire_count = policy.count and count_trigger(len(z), n_tracked_prev)
        fire_obj, gate_any, ell_any = _object_triggers(policy, est, steps, z, sensor, sigma, k)
        periodic = policy.period is not None and k > 0 and k % policy.period == 0
        res.fired[k] = (fire_count, gate_any, ell_any)
        res.fired_any[k] = fire_count or bool(fire_obj) or periodic
        if policy.apply_fixes and answer[k] and (fire_count or periodic or fire_obj):
            targets = range(O) if fire_count or periodic else sorted(fire_obj)
            _camera_fixes(filt, tracker, truth[k], present[k], targets, parts, est, rng)
            res.camera_updates[k, list(targets)] = [present[k, o] for o in targets]
        if births:
            _oracle_births(filt, tracker, truth[k], present[k], parts, est, rng)
        for o, e_o in est.items():
            if o in parts:
                res.estimates[k, o] = e_o
                res.tracked[k, o] = True
        n_tracked_prev = len(parts)
    return res


def _start(
    filt: MultiModelBearingPF,
    tracker: AcousticTracker,
    truth: Array,
    rng: np.random.Generator,
    known: bool = False,
) -> tuple[MultiModelBelief, Array]:
    """A new object's particles around a camera fix of its true state ``truth (4,)``; the
    velocity is the true one when ``known``, else zero. Returns (belief, fix)."""
    fix = truth[:2] + tracker.sigma_r * rng.standard_normal(2)
    v0 = truth[2:] if known else np.zeros(2)
    mean = np.array([fix[0], fix[1], v0[0], v0[1]])
    return filt.initial_belief(mean, tracker.start_std, rng), fix


def _object_triggers(
    policy: CooperationPolicy,
    est: Mapping[int, Array],
    steps: Mapping[int, MultiModelBelief],
    z: Array,
    sensor: tuple[float, float],
    sigma: float,
    k: int,
) -> tuple[set[int], bool, bool]:
    """Objects whose bearing-gate (Eq. 3.15) or ellipse (Eq. 3.16) trigger fires at step ``k``,
    and whether each trigger fired for any object."""
    fire_obj: set[int] = set()
    gate_any = ell_any = False
    if k > 0:
        for o in est:
            g = policy.gate and bearing_gate_trigger(est[o], sensor, z, sigma, policy.gate_k)
            pred = steps[o].predictions
            e = policy.ellipse and pred is not None and ellipse_trigger(est[o], pred, policy.chi2)
            gate_any |= g
            ell_any |= e
            if g or e:
                fire_obj.add(o)
    return fire_obj, gate_any, ell_any


def _camera_fixes(
    filt: MultiModelBearingPF,
    tracker: AcousticTracker,
    truth: Array,
    present: Array,
    targets: Iterable[int],
    parts: dict[int, MultiModelBelief],
    est: dict[int, Array],
    rng: np.random.Generator,
) -> None:
    """The cameras localise ``targets`` (``truth (O, 4)`` at this step): a tracked object's
    particles are reset around its fix, a new one is started, one the cameras no longer see is
    dropped. Updates ``parts`` and ``est`` in place."""
    for o in targets:
        if present[o]:
            if o in parts:
                fix = truth[o, :2] + tracker.sigma_r * rng.standard_normal(2)
                parts[o] = reset_to_fix(parts[o], fix, tracker.sigma_r, rng)
                vel = est[o][2:] if o in est else parts[o].states[:, 2:].mean(0)
            else:
                parts[o], fix = _start(filt, tracker, truth[o], rng)
                vel = np.zeros(2)
            est[o] = np.array([fix[0], fix[1], vel[0], vel[1]])
        elif o in parts:  # the cameras no longer see it
            del parts[o]
            est.pop(o, None)


def _oracle_births(
    filt: MultiModelBearingPF,
    tracker: AcousticTracker,
    truth: Array,
    present: Array,
    parts: dict[int, MultiModelBelief],
    est: dict[int, Array],
    rng: np.random.Generator,
) -> None:
    """Start a filter for every object that appeared, drop those that left (policies that
    cannot discover objects). Updates ``parts`` and ``est`` in place."""
    for o in range(len(present)):
        if present[o] and o not in parts:
            parts[o], fix = _start(filt, tracker, truth[o], rng, tracker.known_initial_velocity)
            est[o] = parts[o].states.mean(axis=0)
            est[o][:2] = fix
        elif not present[o] and o in parts:
            del parts[o]
            est.pop(o, None)


@dataclass
class PeriodicBatchResult:
    estimates: Array  # (T, B, O, 4)
    camera_updates: Array  # (T, B, O) bool
    degenerate_steps: int = 0

    def rms(self, truth: Array) -> Array:
        """``(B, O)`` RMS position error over all steps (objects tracked throughout)."""
        err2 = np.sum((self.estimates[..., :2] - np.asarray(truth)[:, None, :, :2]) ** 2, axis=-1)
        return np.sqrt(err2.mean(axis=0))


def run_periodic_batch(
    truth: Array,
    sensor: tuple[float, float],
    sigma: float,
    periods: Array,
    rng: np.random.Generator,
    tracker: AcousticTracker,
) -> PeriodicBatchResult:
    """:func:`run_cooperation` for ``B`` independent runs at once, periodic cameras only.

    The case of Lee 2009's periodic sweep (Sec. 3.3.1, E3.1/E3.2): every object present and
    audible throughout, the cameras asked every ``periods[b]`` steps (0: never). Each run's
    filters are the same multi-model PF (:class:`MultiModelBearingPF`), with every array
    carrying the batch axis; the law of each run equals :func:`run_cooperation` with
    ``CooperationPolicy(period=periods[b])`` (tested), not its random stream. ``tracker.engine``
    "numba" fuses prediction, weights and estimate in one kernel; "numpy" is the reference
    (same draws, results equal to rounding).
    """
    truth = np.asarray(truth, float)
    periods = np.asarray(periods, int).reshape(-1)
    T, O = truth.shape[:2]
    B, L = len(periods), tracker.n_particles
    filt = tracker.build(sensor, sigma)
    v0 = truth[0, :, 2:] if tracker.known_initial_velocity else np.zeros((O, 2))
    fix = truth[0, :, :2] + tracker.sigma_r * rng.standard_normal((B, O, 2))
    mean = np.concatenate([fix, np.broadcast_to(v0, (B, O, 2))], axis=-1)
    std = tracker.start_std
    parts = mean[:, :, None, :] + std * rng.standard_normal((B, O, L, 4))
    res = PeriodicBatchResult(np.zeros((T, B, O, 4)), np.zeros((T, B, O), bool))
    res.estimates[0] = parts.mean(axis=2)
    all_audible = np.ones(O, bool)
    for k in range(1, T):
        b = merge_close(true_bearings(truth[k, :, :2], sensor)[all_audible], tracker.dz_critical)
        z = b + sigma * rng.standard_normal((B, len(b)))  # order is irrelevant to the filter
        pred, w_ml, est, degenerate = weigh_every_model(filt, parts, z, tracker.dt, rng)
        res.degenerate_steps += degenerate
        idx = resample_l(w_ml, L, rng)  # (B, O, L) indices into J*L
        parts = take_resampled(pred, idx)
        ask = (periods > 0) & (k % np.maximum(periods, 1) == 0)
        if ask.any():  # every run draws; only the asking ones use the draws
            fixes = truth[k, :, :2] + tracker.sigma_r * rng.standard_normal((B, O, 2))
            noise = rng.standard_normal((B, O, L, 2))
            parts[ask, :, :, :2] = fixes[ask][:, :, None, :] + tracker.sigma_r * noise[ask]
            est[ask, :, :2] = fixes[ask]
            res.camera_updates[k, ask] = True
        res.estimates[k] = est
    return res
