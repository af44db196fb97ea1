"""One simulated run of Ercan et al. 2013, Algorithm 3: world, priors, selection, readings, ASIR.

:func:`run_tracking` is the pure Monte Carlo run function ``(config, seed) -> rows`` every
experiment of this paper uses. The random streams are split by purpose (truth, occluder priors,
camera noise, filter, random selection), so two configurations with the same seed see the same
people walking and the same camera noise: differences between them are the method's alone.

Config keys (defaults in :data:`DEFAULTS`): ``scene`` (name or a :class:`Scene`), ``n_occluders``,
``prior`` ("perfect", "gaussian", "none"), ``sigma_psi``, ``prior_filter`` (how Gaussian priors are
made: :data:`~fusetrack.world.occluder_priors.PRIOR_FILTERS`), ``k``, ``method`` (greedy, brute,
fixed, random, closest, all), ``model`` (perspective, weak), ``period`` T, ``steps``,
``particles`` L, ``burn_in``, ``trace`` (keep per-step estimates), ``floor`` (least p(eta | u) of a
particle the reporting cameras can see; 0 = the paper's hard zeros) and ``exclusion`` (the
rectangles of Eq. 7 end this many occluder diameters before the particle; 0 = as printed) and
``tracker_sigma_v`` (the tracker's motion noise sigma_v of Eq. 5, "assumed to be known" by the
paper; None = the walkers' true 0.33 units, spec §8 item 15), ``occlusion_power`` (p(eta | u)
enters the likelihood to this power; 1 = the paper): see
:class:`~fusetrack.sensors.occlusion_aware_camera.OcclusionAwareLikelihood`; ``calibration``
("white": Eq. 2's noise drawn afresh every step, the paper's model; "fixed": each camera's yaw and
position errors drawn once per run, spec §8 item 23, see :func:`camera_readings`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import pickle
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...core import ConfigError, Measurement, invalid
from ...filters import WaypointASIR
from ...management import (
    SELECTION_METHODS,
    SelectionMoments,
    brute_force_selection,
    closest_selection,
    fixed_selection,
    greedy_selection,
    random_selection,
    selection_moments,
    subset_mse,
)
from ...motion import WaypointRegimeDynamics
from ...sensors import (
    CameraArray,
    CameraNetworkReport,
    OcclusionAwareCameraSensor,
    OcclusionAwareLikelihood,
)
from ...world import (
    PRIOR_FILTERS,
    OccluderPriors,
    RandomWalkPriorFilter,
    WaypointWalkers,
    disks_block,
    prior_nees,
    prior_track,
    rmse_per_coordinate,
)
from .scenes import Array, Scene, get_scene

DEFAULTS: dict[str, Any] = {
    "scene": "square",
    "n_occluders": 40,
    "prior": "gaussian",
    "sigma_psi": 17.0,
    "prior_filter": "random-walk",
    "k": 4,
    "method": "fixed",
    "model": "perspective",
    "period": 5,
    "steps": 4000,
    "particles": 1000,
    "burn_in": 0,
    "trace": False,
    "floor": 1e-3,
    "exclusion": 1.0,
    "tracker_sigma_v": None,
    "occlusion_power": 1.0,
    "calibration": "white",
}
CALIBRATIONS = ("white", "fixed")


def _resolve(config: Mapping[str, Any]) -> tuple[dict[str, Any], Scene]:
    cfg = {**DEFAULTS, **config}
    unknown = set(config) - set(DEFAULTS) - {"scene_obj", "label", "metric_gap"}
    if unknown:
        raise ConfigError(invalid("config keys", sorted(unknown), f"keys among {sorted(DEFAULTS)}"))
    scene = cfg.get("scene_obj") or get_scene(cfg["scene"])
    if cfg["prior_filter"] not in PRIOR_FILTERS:
        raise ConfigError(invalid("prior_filter", cfg["prior_filter"], f"one of {PRIOR_FILTERS}"))
    if cfg["calibration"] not in CALIBRATIONS:
        raise ConfigError(invalid("calibration", cfg["calibration"], f"one of {CALIBRATIONS}"))
    if cfg["method"] not in SELECTION_METHODS:
        raise ConfigError(invalid("method", cfg["method"], f"one of {SELECTION_METHODS}"))
    n = len(scene.cameras)
    if cfg["method"] != "all" and not 1 <= int(cfg["k"]) <= n:
        raise ConfigError(invalid("k", cfg["k"], f"a number of cameras in [1, {n}]"))
    if cfg["method"] == "fixed" and int(cfg["k"]) > len(scene.fixed_order):
        raise ConfigError(invalid("k", cfg["k"], f"<= {len(scene.fixed_order)} (the fixed list)"))
    return cfg, scene


_WORLDS: dict[tuple[str, int, int, int, str], tuple[Array, Array, Array]] = {}
_WORLD_CACHE_SIZE = 16
"""Worlds kept per process: more than the 10 runs (seeds) of ``ercan2013-selection``, so that a
worker cycling through the runs of each configuration simulates each world once (with 8 it
simulated every one again); a 4000-step world with 40 occluders is ~3 MB."""


def world_and_readings(
    scene: Scene, n_occluders: int, steps: int, seed: int, calibration: str = "white"
) -> tuple[Array, Array, Array]:
    """:func:`simulate_world` and :func:`camera_readings`, remembered per process: configurations
    that share a seed share the world (common random numbers), so it is simulated once."""
    key = (hashlib.sha1(pickle.dumps(scene)).hexdigest(), n_occluders, steps, seed, calibration)
    if key not in _WORLDS:
        if len(_WORLDS) >= _WORLD_CACHE_SIZE:
            _WORLDS.pop(next(iter(_WORLDS)))
        obj, occ = simulate_world(scene, n_occluders, steps, seed)
        _WORLDS[key] = (obj, occ, camera_readings(scene, obj, occ, seed, calibration))
    return _WORLDS[key]


def simulate_world(scene: Scene, n_occluders: int, steps: int, seed: int) -> tuple[Array, Array]:
    """True object positions ``(steps + 1, 2)`` and occluder positions ``(steps + 1, M, 2)``."""
    rng = np.random.default_rng([seed, 0])
    walkers = WaypointWalkers(scene.room, scene.speed, scene.motion_noise, scene.diameter)
    if scene.object_path is None:
        traj = walkers.trajectory(n_occluders + 1, steps, rng)
        return traj[:, 0], traj[:, 1:]
    path = scene.object_path
    idx = np.arange(steps + 1) % (len(path) - 1)
    occ = (
        walkers.trajectory(n_occluders, steps, rng) if n_occluders else np.zeros((steps + 1, 0, 2))
    )
    return path[idx], occ


def miscalibrated(scene: Scene, seed: int) -> CameraArray:
    """The cameras as they really are in a run with fixed calibration errors (spec §8 item 23):
    each camera's yaw off by ``N(0, sigma_theta^2)`` and its position by ``N(0, sigma_pos^2 I)``,
    drawn once per run (stream ``[seed, 5]``); only the read noise is left white."""
    rng = np.random.default_rng([seed, 5])
    cams = scene.cameras
    n = len(cams)
    return dataclasses.replace(
        cams,
        yaws=cams.yaws + cams.sigma_theta * rng.standard_normal(n),
        positions=cams.positions + cams.sigma_pos[:, None] * rng.standard_normal((n, 2)),
        sigma_theta=np.zeros(n),
        sigma_pos=np.zeros(n),
    )


def camera_readings(
    scene: Scene, obj: Array, occ: Array, seed: int, calibration: str = "white"
) -> Array:
    """Readings of every camera at every step ``(steps + 1, N)``: Eq. 4 with Eq. 2 noise, NaN when
    out of view, behind a wall or static occluder, or behind an occluder disc. ``calibration``
    "fixed": the readings come from the :func:`miscalibrated` cameras with white read noise only
    (the tracker still assumes Eq. 2); which steps a camera sees is decided as for "white", from
    the nominal cameras, so the two differ only in the reading values."""
    rng = np.random.default_rng([seed, 2])
    cams = scene.cameras
    real = cams if calibration == "white" else miscalibrated(scene, seed)
    n_steps = len(obj)
    z = np.full((n_steps, len(cams)), np.nan)
    mean = real.image_coordinate(obj[:, None, :])
    sd = np.sqrt(real.noise_var(obj[:, None, :]))
    noise = rng.standard_normal(mean.shape)
    seen = cams.in_fov(obj[:, None, :]) & ~scene.room.sight_blocked(
        cams.positions[None], obj[:, None, :]
    )
    for t in range(n_steps):
        seen[t] &= ~disks_block(cams.positions, obj[t], occ[t], scene.diameter)[:, 0]
    z[seen] = (mean + sd * noise)[seen]
    return z


@dataclass
class _Clock:
    """Wall seconds spent in the likelihood, in selection epochs, and in the subset search."""

    likelihood: float = 0.0
    selection: float = 0.0
    search: float = 0.0


@dataclass(frozen=True)
class _Priors:
    """The occluder priors of one run (means and variances per step when Gaussian) and their
    accuracy: RMSE_occ and squared error / claimed variance."""

    means: Array | None
    var: Array | None
    rmse_occ: float
    nees: float

    def at(self, prior: str, occ: Array, t: int) -> OccluderPriors | Array | None:
        """What the tracker knows of the occluders at step ``t``."""
        if prior == "gaussian":
            assert self.means is not None and self.var is not None
            return RandomWalkPriorFilter.priors(self.means[t - 1], float(self.var[t - 1]))
        if prior == "perfect":
            return occ[t]
        return None


def _occluder_priors(cfg: dict[str, Any], scene: Scene, occ: Array, seed: int) -> _Priors:
    """Gaussian priors from a Kalman filter on virtual readings, the truth, or none."""
    m, center, prior = int(cfg["n_occluders"]), scene.room.center, cfg["prior"]
    if prior == "gaussian":
        means, var = prior_track(
            cfg["prior_filter"],
            float(cfg["sigma_psi"]),
            scene.prior_q,
            occ[1:],
            center,
            np.random.default_rng([seed, 1]),
            q_cv=scene.prior_q_cv,
        )
        rmse_occ = rmse_per_coordinate(means, occ[1:]) if m else 0.0
        # calibration: squared error over the variance the priors claim (1 = calibrated)
        return _Priors(means, var, rmse_occ, prior_nees(means, var, occ[1:]))
    if prior == "perfect":
        return _Priors(None, None, 0.0, float("nan"))
    rmse_occ = rmse_per_coordinate(np.broadcast_to(center, occ[1:].shape), occ[1:]) if m else 0.0
    return _Priors(None, None, rmse_occ, float("nan"))


def _likelihood(cfg: dict[str, Any], scene: Scene) -> OcclusionAwareLikelihood:
    """The occlusion-aware likelihood with this run's prior level and corrections."""
    return OcclusionAwareLikelihood(
        scene.cameras,
        scene.room,
        scene.diameter,
        cfg["prior"],
        floor=float(cfg["floor"]),
        exclusion=float(cfg["exclusion"]) * scene.diameter,
        occlusion_power=float(cfg["occlusion_power"]),
    )


@dataclass(frozen=True)
class _TimedSensor:
    """The camera-network sensor, adding its wall time to ``clock.likelihood``."""

    sensor: OcclusionAwareCameraSensor
    clock: _Clock

    @property
    def sensor_id(self) -> str:
        return self.sensor.sensor_id

    def log_likelihood(self, z: CameraNetworkReport, x: Array) -> Array:
        t0 = time.perf_counter()
        out = self.sensor.log_likelihood(z, x)
        self.clock.likelihood += time.perf_counter() - t0
        return out


def _filter(cfg: dict[str, Any], scene: Scene, clock: _Clock) -> WaypointASIR:
    """Algorithm 1's ASIR with the tracker's motion noise sigma_v (Eq. 5) reading the camera
    network through the occlusion-aware likelihood (timed into ``clock``)."""
    sigma_v = (
        scene.motion_noise if cfg["tracker_sigma_v"] is None else float(cfg["tracker_sigma_v"])
    )
    dynamics = WaypointRegimeDynamics(sigma_v=sigma_v)
    sensor = _TimedSensor(OcclusionAwareCameraSensor(_likelihood(cfg, scene)), clock)
    return WaypointASIR(scene.room, dynamics, int(cfg["particles"]), scene.speed, sensors=(sensor,))


def _select(
    cfg: dict[str, Any],
    scene: Scene,
    predicted: Array,
    w: Array,
    occluders: OccluderPriors | Array | None,
    exclusion: float,
    rng_s: np.random.Generator,
    clock: _Clock,
) -> tuple[Array, SelectionMoments | None]:
    """One selection epoch (Algorithm 2 or a heuristic) on the predicted cloud; the subset and,
    for greedy with ``metric_gap``, its subset MSE over brute force's (a check, not timed)."""
    method, k, n_cams = cfg["method"], int(cfg["k"]), len(scene.cameras)
    if method == "random":
        return np.array(random_selection(n_cams, k, rng_s)), None
    if method == "closest":
        return np.array(closest_selection(scene.cameras.positions, w @ predicted[:, :2], k)), None
    mom = selection_moments(
        scene.cameras,
        scene.room,
        predicted[:, :2],
        w,
        occluders,
        scene.diameter,
        cfg["prior"],
        (cfg["model"],),
        exclusion=exclusion,
    )
    pick = greedy_selection if method == "greedy" else brute_force_selection
    t_search = time.perf_counter()
    selected = np.array(pick(mom, k, cfg["model"]))
    clock.search += time.perf_counter() - t_search
    return selected, mom


def _metric_gap(cfg: dict[str, Any], mom: SelectionMoments | None, selected: Array) -> float:
    """Greedy's subset MSE over the brute-force optimum's at one epoch."""
    k = int(cfg["k"])
    assert mom is not None  # greedy always computes the moments
    best = brute_force_selection(mom, k, cfg["model"])
    e = subset_mse(mom, np.array([selected, best]), cfg["model"])
    return float(e[0] / max(e[1], 1e-300))


@dataclass(frozen=True)
class _Track:
    """What the tracking loop produced: estimates, readings used, timings and metric gaps."""

    est: Array
    n_seen: int
    clock: _Clock
    gaps: list[float]


def _track(
    cfg: dict[str, Any],
    scene: Scene,
    occ: Array,
    z_all: Array,
    pri: _Priors,
    asir: WaypointASIR,
    clock: _Clock,
    seed: int,
) -> _Track:
    """Algorithm 3's loop: (every T steps) select cameras, read them, one ASIR step."""
    exclusion = float(cfg["exclusion"]) * scene.diameter
    steps, prior = int(cfg["steps"]), cfg["prior"]
    rng_f = np.random.default_rng([seed, 3])
    rng_s = np.random.default_rng([seed, 4])
    belief = asir.initialize(rng_f)
    n_cams = len(scene.cameras)
    method, k, period = cfg["method"], int(cfg["k"]), int(cfg["period"])
    selected = (
        np.arange(n_cams)
        if method == "all"
        else np.array(fixed_selection(scene.fixed_order, k) if method == "fixed" else [])
    )
    est = np.empty((steps, 2))
    n_seen = 0
    gaps: list[float] = []
    for t in range(1, steps + 1):
        occluders = pri.at(prior, occ, t)
        if method in ("greedy", "brute", "random", "closest") and (t - 1) % period == 0:
            t0 = time.perf_counter()
            predicted = asir.propagate(belief.particles, rng_f)
            selected, mom = _select(
                cfg, scene, predicted, belief.weights, occluders, exclusion, rng_s, clock
            )
            clock.selection += time.perf_counter() - t0
            if cfg.get("metric_gap") and method == "greedy":  # not timed: a check, not the method
                gaps.append(_metric_gap(cfg, mom, selected))
        z = z_all[t, selected]
        n_seen += int(np.isfinite(z).sum())
        report = CameraNetworkReport(z, selected, occluders)
        belief = asir.step(belief, 1.0, [Measurement(float(t), "cameras", report)], rng_f)
        est[t - 1] = belief.position
    return _Track(est, n_seen, clock, gaps)


def _row(
    cfg: dict[str, Any],
    scene: Scene,
    obj: Array,
    pri: _Priors,
    tr: _Track,
    asir: WaypointASIR,
    cpu0: float,
) -> dict[str, Any]:
    """The run's result row: RMSEs after burn-in, prior accuracy, timings, filter statistics."""
    steps, period, method = int(cfg["steps"]), int(cfg["period"]), cfg["method"]
    center, est, clock = scene.room.center, tr.est, tr.clock
    b = int(cfg["burn_in"])
    err = est[b:] - obj[1 + b :]
    row: dict[str, Any] = {
        "scene": scene.name,
        "rmse_tr": rmse_per_coordinate(est[b:], obj[1 + b :]),
        "rmse_tr_euclid": float(np.sqrt(np.mean(np.sum(err**2, axis=1)))),
        "rmse_occ": pri.rmse_occ,
        "prior_nees": pri.nees,
        "rmse_max": rmse_per_coordinate(np.broadcast_to(center, obj[1 + b :].shape), obj[1 + b :]),
        "likelihood_ms_per_step": 1e3 * clock.likelihood / steps,
        "selection_ms_per_epoch": 1e3 * clock.selection / max(1, -(-steps // period))
        if method not in ("fixed", "all")
        else 0.0,
        "search_ms_per_epoch": 1e3 * clock.search / max(1, -(-steps // period)),
        "readings_per_step": tr.n_seen / steps,
        "fallbacks": asir.stats.first_stage_fallbacks,
        "ignored_steps": asir.stats.ignored_steps,
        "reinitialisations": asir.stats.reinitialisations,
        "cpu_seconds": time.process_time() - cpu0,
    }
    if tr.gaps:
        row["greedy_over_brute_mse"] = float(np.mean(tr.gaps))
        row["greedy_equals_brute"] = float(np.mean(np.isclose(tr.gaps, 1.0)))
    if cfg["trace"]:
        row["trace_est"] = est.tolist()
        row["trace_true"] = obj[1:].tolist()
    return row


def run_tracking(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    """One run of Algorithm 3; one row with the run's RMSEs, costs and counters."""
    cpu0 = time.process_time()
    cfg, scene = _resolve(config)
    steps, m = int(cfg["steps"]), int(cfg["n_occluders"])
    obj, occ, z_all = world_and_readings(scene, m, steps, seed, cfg["calibration"])
    pri = _occluder_priors(cfg, scene, occ, seed)
    clock = _Clock()
    asir = _filter(cfg, scene, clock)
    tr = _track(cfg, scene, occ, z_all, pri, asir, clock, seed)
    return [_row(cfg, scene, obj, pri, tr, asir, cpu0)]
