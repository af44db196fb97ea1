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
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core.errors import ConfigError, invalid
from ..filters.multi_model_pf import MultiModelBearingPF
from ..sensors.unlabelled_bearings import simulate_bearings

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
        cov = np.cov(pts.T) + 1e-12 * np.eye(2)
        d = p - mu
        if float(d @ np.linalg.solve(cov, d)) <= chi2:
            return False
    return True


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
    *,
    models: tuple,
    dt: float,
    n_particles: int = 500,
    sigma_filter: float | None = None,
    sigma_r: float = 0.1,
    dz_critical: float = math.radians(2.0),
    init_velocity_std: float = 0.3,
    oracle_births: bool | None = None,
    camera_available: Array | None = None,
    known_initial_velocity: bool = False,
) -> CooperationResult:
    """Track ``O`` objects over ``T`` steps with one acoustic sensor and camera cooperation.

    ``truth`` ``(T, O, 4)``; ``present`` ``(T, O)``: the object is in the sensor's range (the
    cameras see it); ``audible`` ``(T, O)``: it emits a bearing (present and not silent).
    At step 0 the cameras localise every present object. When the policy cannot discover objects
    (no cameras, or neither the count trigger nor a period; ``oracle_births`` defaults to True
    then) objects are started from a noisy camera-like fix when they appear and dropped when
    they leave, so that errors are defined and comparable.
    ``camera_available`` ``(T,)`` False: the cameras do not answer at that step (request lost).
    ``known_initial_velocity``: filters started at step 0 or by an oracle birth begin at the
    true velocity (the text's "initial state given"); camera-started filters never know it.
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
    filt = MultiModelBearingPF(models, sensor, sigma_filter or sigma, n_particles)
    parts: dict[int, Array] = {}
    res = CooperationResult(
        np.full((T, O, 4), np.nan),
        np.zeros((T, O), bool),
        np.zeros((T, O), bool),
        np.zeros((T, 3), bool),
        np.zeros(T, bool),
        np.zeros(T, int),
    )

    def start(o: int, k: int, known: bool = False) -> tuple[Array, Array]:
        fix = truth[k, o, :2] + sigma_r * rng.standard_normal(2)
        v0 = truth[k, o, 2:] if known else np.zeros(2)
        mean = np.array([fix[0], fix[1], v0[0], v0[1]])
        std = np.array([sigma_r, sigma_r, init_velocity_std, init_velocity_std])
        return filt.initialize(mean, std, rng), fix

    for o in range(O):  # step 0: the cameras find every present object
        if present[0, o]:
            parts[o], _ = start(o, 0, known_initial_velocity)
    n_tracked_prev = len(parts)
    for k in range(T):
        z = simulate_bearings(truth[k, :, :2], audible[k], sensor, sigma, rng, dz_critical)
        res.n_bearings[k] = len(z)
        est: dict[int, Array] = {}
        steps = {}
        if k > 0:
            for o, p in list(parts.items()):
                parts[o], st = filt.step(p, z, dt, rng)
                est[o], steps[o] = st.estimate, st
        else:
            for o, p in parts.items():
                est[o] = p.mean(axis=0)
        # --- triggers
        fire_count = policy.count and count_trigger(len(z), n_tracked_prev)
        fire_obj: set[int] = set()
        gate_any = ell_any = False
        if k > 0:
            for o in est:
                g = policy.gate and bearing_gate_trigger(est[o], sensor, z, sigma, policy.gate_k)
                e = policy.ellipse and ellipse_trigger(est[o], steps[o].predictions, policy.chi2)
                gate_any |= g
                ell_any |= e
                if g or e:
                    fire_obj.add(o)
        periodic = policy.period is not None and k > 0 and k % policy.period == 0
        res.fired[k] = (fire_count, gate_any, ell_any)
        res.fired_any[k] = fire_count or bool(fire_obj) or periodic
        # --- camera cooperation
        if policy.apply_fixes and answer[k] and (fire_count or periodic or fire_obj):
            everyone = fire_count or periodic
            targets = range(O) if everyone else sorted(fire_obj)
            for o in targets:
                if present[k, o]:
                    if o in parts:
                        fix = truth[k, o, :2] + sigma_r * rng.standard_normal(2)
                        parts[o] = filt.reset_to_fix(parts[o], fix, sigma_r, rng)
                        vel = est[o][2:] if o in est else parts[o][:, 2:].mean(0)
                    else:
                        parts[o], fix = start(o, k)
                        vel = np.zeros(2)
                    est[o] = np.array([fix[0], fix[1], vel[0], vel[1]])
                    res.camera_updates[k, o] = True
                elif o in parts:  # the cameras no longer see it
                    del parts[o]
                    est.pop(o, None)
        if births:
            for o in range(O):
                if present[k, o] and o not in parts:
                    parts[o], fix = start(o, k, known_initial_velocity)
                    est[o] = parts[o].mean(axis=0)
                    est[o][:2] = fix
                elif not present[k, o] and o in parts:
                    del parts[o]
                    est.pop(o, None)
        for o, e_o in est.items():
            if o in parts:
                res.estimates[k, o] = e_o
                res.tracked[k, o] = True
        n_tracked_prev = len(parts)
    res.degenerate_steps = filt.degenerate_steps
    return res
