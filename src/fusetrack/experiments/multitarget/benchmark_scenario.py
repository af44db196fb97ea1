"""The scenario of ``multitarget-benchmark``: 2-D nearly-constant-velocity targets born and
dying in a surveillance square, seen by a position sensor and a range-bearing radar.

* **Square** ``[-500, 500]^2`` m, one scan every ``DT = 1`` s.
* **Targets** (state ``[x, y, vx, vy]``) move by :class:`~fusetrack.motion.ConstantVelocity`
  (white-noise acceleration, PSD :data:`Q_ACCEL`). They are born by a Poisson process whose
  intensity is the Gaussian mixture :func:`birth_intensity` (Vo & Ma 2006, Sec. VI: fixed
  birth regions): four entry regions in the middle of the square's sides, heading inwards at
  10 m/s, so that targets from different sides cross near the centre. Each target survives a
  scan with probability ``P_S`` (a geometric lifetime). The first scan's targets are drawn like
  births, Poisson with the steady-state mean ``birth_rate / (1 - P_S)``. This is exactly the
  multi-target model the PHD filter assumes (Mahler 2007, Ch. 16).
* **Crossing** (:func:`simulate_crossing`): pairs of targets leaving the entry regions on
  straight lines (no process noise) at a shallow angle, crossing at mid-run.
* **Sensors**, each scan, each with ``P_D`` (independently per target and sensor) and Poisson
  clutter: ``pos``, a :class:`~fusetrack.sensors.PositionFix` (``sigma`` = 10 m per axis),
  clutter uniform over the square; ``radar``, a :class:`~fusetrack.sensors.RangeBearing` at
  the south-west corner outside the square (``sigma_r`` = 10 m, ``sigma_b`` = 0.01 rad), clutter
  uniform over the range-bearing box that holds the square (:data:`RADAR_BOX`). The reports of
  one sensor in one scan are shuffled.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ...core import Measurement
from ...filters import PhdIntensity
from ...motion import ConstantVelocity
from ...sensors import PositionFix, RangeBearing
from .scenario import Array, Truth

HALF = 500.0  # the square is [-HALF, HALF]^2 m
AREA = (2 * HALF) ** 2
DT = 1.0
Q_ACCEL = 0.5  # m^2/s^3, white-noise acceleration PSD of truth and trackers
SPEED = 10.0  # m/s, mean speed of a newborn target
BIRTH_POS_STD = 25.0  # m
BIRTH_VEL_STD = 2.0  # m/s
POS_SIGMA = 10.0  # m
RADAR_SITE = (-700.0, -700.0)
RADAR_SIGMA_RANGE = 10.0  # m
RADAR_SIGMA_BEARING = 0.01  # rad
_NEAR, _FAR = -HALF - RADAR_SITE[0], HALF - RADAR_SITE[0]  # 200 m, 1200 m (both axes)
# range [r0, r1] and bearing [b0, b1] of the smallest such box that holds the square
RADAR_BOX = (
    float(np.hypot(_NEAR, _NEAR)),
    float(np.hypot(_FAR, _FAR)),
    float(np.arctan2(_NEAR, _FAR)),
    float(np.arctan2(_FAR, _NEAR)),
)
SENSOR_IDS = ("pos", "radar")
SCENARIOS = ("sparse", "dense", "crossing")  # births and deaths in 2 clutter levels; crossings
ENTRIES = ((-1.0, 0.0), (1.0, 0.0), (0.0, -1.0), (0.0, 1.0))  # W, E, S, N (unit vectors)


@dataclass(frozen=True)
class Setting:
    """What a configuration sets: detection probability, clutter per sensor per scan, survival,
    birth rate per scan (all entry regions together)."""

    p_detect: float = 0.9
    clutter: float = 5.0
    p_survive: float = 0.98
    birth_rate: float = 0.1


def motion() -> ConstantVelocity:
    return ConstantVelocity(ndim=2, q=Q_ACCEL)


def sensors(p_detect: float) -> dict[str, PositionFix | RangeBearing]:
    """The two sensor models (``detection_prob`` = ``p_detect``), by id."""
    return {
        "pos": PositionFix("pos", cov=POS_SIGMA**2 * np.eye(2), detection_prob=p_detect),
        "radar": RangeBearing(
            "radar",
            position=list(RADAR_SITE),
            sigma_range=RADAR_SIGMA_RANGE,
            sigma_bearing=RADAR_SIGMA_BEARING,
            detection_prob=p_detect,
        ),
    }


def clutter_volume(sensor_id: str) -> float:
    """The measurement-space volume clutter is spread over: m^2, or m rad for the radar."""
    if sensor_id == "pos":
        return AREA
    r0, r1, b0, b1 = RADAR_BOX
    return (r1 - r0) * (b1 - b0)


def birth_intensity(birth_rate: float) -> PhdIntensity:
    """Four Gaussian entry regions (400 m from the centre on each axis, heading inwards at
    :data:`SPEED`), weight ``birth_rate / 4`` each."""
    means = []
    for ux, uy in ENTRIES:
        means.append([0.8 * HALF * ux, 0.8 * HALF * uy, -SPEED * ux, -SPEED * uy])
    cov = np.diag([BIRTH_POS_STD**2] * 2 + [BIRTH_VEL_STD**2] * 2)
    return PhdIntensity(np.full(4, birth_rate / 4), np.array(means), np.stack([cov] * 4))


@dataclass(frozen=True)
class World:
    """One run's truth: states ``(K, n, 4)`` (NaN while absent), the scan of each target's
    birth and of its last scan alive."""

    times: Array
    states: Array
    born: Array
    last: Array

    @property
    def truth(self) -> Truth:
        return Truth(self.times, self.states[..., :2])

    @property
    def counts(self) -> Array:
        """True number of targets at each scan ``(K,)``."""
        return np.all(np.isfinite(self.states[..., :2]), axis=2).sum(axis=1)


def _draw_births(intensity: PhdIntensity, n: int, rng: np.random.Generator) -> Array:
    """``n`` states drawn from the normalised birth intensity."""
    w = intensity.weights / intensity.weights.sum()
    k = rng.choice(w.size, size=n, p=w)
    chol = np.linalg.cholesky(intensity.covs)
    e = rng.standard_normal((n, intensity.means.shape[1]))
    return np.asarray(intensity.means[k] + np.einsum("nij,nj->ni", chol[k], e))


def simulate_births_and_deaths(setting: Setting, scans: int, rng: np.random.Generator) -> World:
    """Poisson births from :func:`birth_intensity`, survival ``p_survive`` per scan, motion
    :func:`motion` (module docstring); at scan 0 Poisson(steady state) targets."""
    cv, birth = motion(), birth_intensity(setting.birth_rate)
    times = np.arange(scans, dtype=float) * DT
    rows: list[Array] = []  # per target, its states (scans, 4), NaN while absent
    born: list[int] = []
    alive: list[int] = []
    for k in range(scans):
        for i in list(alive):
            if rng.random() >= setting.p_survive:
                alive.remove(i)
                continue
            rows[i][k] = cv.sample(rows[i][k - 1], DT, rng)
        mean = setting.birth_rate / (1 - setting.p_survive) if k == 0 else setting.birth_rate
        for x in _draw_births(birth, int(rng.poisson(mean)), rng):
            rows.append(np.full((scans, 4), np.nan))
            rows[-1][k] = x
            born.append(k)
            alive.append(len(rows) - 1)
    states = np.stack(rows, axis=1) if rows else np.full((scans, 0, 4), np.nan)
    last = np.array([np.flatnonzero(np.isfinite(r[:, 0]))[-1] for r in rows], dtype=int)
    return World(times, states, np.array(born, dtype=int), last)


CROSSING_SCANS = 31  # a crossing run's length at most: its targets end 100 m from the centre


def simulate_crossing(pairs: int, scans: int, half_angle_deg: float = 10.0) -> World:
    """``pairs`` (1-4) pairs of targets on straight lines (no randomness), present from the
    first scan to the last (at most :data:`CROSSING_SCANS`). Pair ``j`` starts in entry region
    ``j`` (W, E, S, N of :func:`birth_intensity`) heading inwards at :data:`SPEED`, its two
    targets at ``+-half_angle_deg`` to the inward direction, so that they cross at mid-run."""
    scans = min(scans, CROSSING_SCANS)
    times = np.arange(scans, dtype=float) * DT
    t_mid = times[-1] / 2
    states = np.full((scans, 2 * pairs, 4), np.nan)
    a = np.deg2rad(half_angle_deg)
    for j, (ux, uy) in enumerate(ENTRIES[:pairs]):
        inward = -np.array([ux, uy])
        meet = 0.8 * HALF * np.array([ux, uy]) + SPEED * t_mid * inward
        for s, ang in enumerate((a, -a)):
            c, sn = np.cos(ang), np.sin(ang)
            v = SPEED * np.array([c * inward[0] - sn * inward[1], sn * inward[0] + c * inward[1]])
            states[:, 2 * j + s, :2] = meet + np.outer(times - t_mid, v)
            states[:, 2 * j + s, 2:] = v
    n = 2 * pairs
    return World(times, states, np.zeros(n, dtype=int), np.full(n, scans - 1))


def _clutter(sensor_id: str, n: int, rng: np.random.Generator) -> Array:
    """``n`` false reports uniform over the sensor's clutter region."""
    if sensor_id == "pos":
        return rng.uniform(-HALF, HALF, (n, 2))
    r0, r1, b0, b1 = RADAR_BOX
    return np.column_stack([rng.uniform(r0, r1, n), rng.uniform(b0, b1, n)])


@dataclass(frozen=True)
class Scans:
    """Every report of a run (scan by scan, sensor by sensor, shuffled), and each report's
    origin: the target index, or -1 for clutter."""

    measurements: list[Measurement]
    origins: Array

    def by_sensor(self, sensor_id: str) -> list[Measurement]:
        return [m for m in self.measurements if m.sensor_id == sensor_id]


def simulate_scans(
    world: World, setting: Setting, rng: np.random.Generator, sensor_ids: Sequence[str] = SENSOR_IDS
) -> Scans:
    """Per scan, per sensor: every present target detected with ``P_D`` (sensor noise), plus
    Poisson(``clutter``) false reports (module docstring)."""
    models = sensors(setting.p_detect)
    out: list[Measurement] = []
    origins: list[int] = []
    for k, t in enumerate(world.times):
        present = np.flatnonzero(np.all(np.isfinite(world.states[k]), axis=1))
        for sid in sensor_ids:
            z = models[sid].simulate(world.states[k, present], rng)
            seen = np.all(np.isfinite(z), axis=1)
            values = np.concatenate(
                [z[seen], _clutter(sid, int(rng.poisson(setting.clutter)), rng)]
            )
            origin = np.concatenate([present[seen], np.full(len(values) - int(seen.sum()), -1)])
            order = rng.permutation(len(values))
            out += [Measurement(float(t), sid, values[j]) for j in order]
            origins += origin[order].tolist()
    return Scans(out, np.array(origins, dtype=int))


def scenario_stats(
    world: World, scans: Scans, n_sensors: int = len(SENSOR_IDS)
) -> dict[str, float]:
    """What the simulation drew: births after the first scan, clutter reports per sensor per
    scan, and the fraction of (present target, scan, sensor) triples detected."""
    present = int(world.counts.sum())
    detected = int(np.sum(scans.origins >= 0))
    return {
        "births": float(np.sum(world.born > 0)),
        "clutter_per_scan": float(np.sum(scans.origins < 0)) / (world.times.size * n_sensors),
        "detected_fraction": detected / (present * n_sensors) if present else float("nan"),
    }
