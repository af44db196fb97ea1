"""The best possible beside ``multitarget-benchmark``'s table (issue 19, item 3): the oracle
floor of :mod:`.gospa_floor` and the clairvoyant filter of :mod:`.clairvoyant` on the benchmark's
own worlds, compared with every tracker by :mod:`.best_possible`.

The oracle of a run knows its world's motion model (``sparse`` and ``dense``: nearly constant
velocity, ``q = Q_ACCEL``; ``crossing``: straight lines, ``q = 0``), the two sensors (the
position sensor and the radar, ``P_D`` each), which report is whose and which are clutter, and
when each target is born and dies. Its prior on a target at its first scan is the birth
intensity's covariance (:func:`~.benchmark_scenario.birth_intensity`: the exact prior of a
``sparse`` / ``dense`` target, born from one of its components; a ``crossing`` target starts
about one standard deviation from a component's mean). The clairvoyant filter is the trackers'
extended Kalman filter, one per target, on its own reports (:func:`report_draw`).
"""

from __future__ import annotations

import numpy as np

from ...core import Measurement
from ...filters import ExtendedKalmanFilter
from ...motion import ConstantVelocity
from .benchmark_scenario import DT, Q_ACCEL, SCENARIOS, World, birth_intensity, sensors
from .benchmark_trackers import TRACKERS
from .best_possible import Layout, floor_columns
from .clairvoyant import Draw
from .gospa_floor import Oracle, Path
from .scenario import Array

NEAR = 1.25
"""The clairvoyant filter comes within this factor of the online floor: the model is nearly
linear-Gaussian (the position sensor is linear, the radar's errors, 10 m across 300-1700 m, are
small against its range), so the extended Kalman filter nearly attains the bound; what is left
is the reduction factor's Jensen gap (``P_D`` averaged in the information, not in its inverse)
and the radar's linearisation."""

LAYOUT = Layout(
    by="scenario",
    groups=SCENARIOS,
    unit="",
    method="tracker",
    methods=TRACKERS,
    near=NEAR,
    knows="known association, births and deaths, the truth's motion model",
    clairvoyant="one EKF per target on its own reports",
    row="clairvoyant EKF, own reports",
    datum="report",
    later="MHT and MCMCDA decide with later scans",
)


def oracle(scenario: str, p_detect: float) -> Oracle:
    """The oracle of one configuration (module docstring)."""
    q = 0.0 if scenario == "crossing" else Q_ACCEL
    return Oracle(ConstantVelocity(ndim=2, q=q), list(sensors(p_detect).values()), DT, p_detect)


def report_draw(p_detect: float) -> Draw:
    """One target's reports: per sensor, a report drawn by its model (``P_D``, its noise)."""
    models = sensors(p_detect)

    def draw(x: Array, t: float, rng: np.random.Generator) -> list[Measurement]:
        out = []
        for sid, model in models.items():
            z = model.simulate(x[None], rng)[0]
            if np.all(np.isfinite(z)):
                out.append(Measurement(t, sid, z))
        return out

    return draw


def paths(world: World) -> list[Path]:
    """Each target's scans alive and its true states there."""
    out = []
    for i in range(world.states.shape[1]):
        on = np.flatnonzero(np.all(np.isfinite(world.states[:, i]), axis=1))
        out.append((on, world.states[on, i]))
    return out


def benchmark_floor_columns(
    scenario: str, world: World, p_detect: float, c: float, rng: np.random.Generator
) -> dict[str, float]:
    """One run's floors and the clairvoyant filter's ``mean_t d_t^2`` (m²)."""
    o = oracle(scenario, p_detect)
    ekf = ExtendedKalmanFilter(o.motion, list(o.sensors))
    prior = birth_intensity(1.0).covs[0]
    ps = paths(world)
    priors = [prior] * len(ps)
    return floor_columns(o, ekf, ps, world.truth, c, priors, report_draw(p_detect), rng)


UNBOUNDED = """
Sparse and dense runs share their worlds (the same seed draws the targets first), so their floors
and clairvoyant filter are the same. The floor's Gaussian-error step does not hold where two
targets are within a few bound-σ of each other: in `crossing` at mid-run, for a few scans, and
where targets from opposite sides meet near the centre; there it is a reading, not a theorem.

The floor bounds one number of each row: localisation + missed + false. No bound is given for the
other columns, for these reasons. Localisation, missed and false on their own: a tracker trades
one for another (reporting a target late moves its scans from localisation to missed), so only
their sum is bounded. `gospa`: a mean over runs of per-run roots, which can lie below the root of
the floor (Jensen). OSPA⁽²⁾ (p = 1, over whole tracks): a different metric, whose floor would
need the bound pushed through its track assignment; not derived. `n_tracks`, `count_bias`, MOTA,
identity switches and fragmentations: counts, whose best values (the true number of targets, 0,
1, 0, 0) the oracle attains trivially by knowing the association; they are reported, not
bounded. MOTP: a mean distance over the pairs matched within 30 m only, a selection that cuts
off the large errors, so the bound on all errors does not bound it. The trivial estimator,
reporting no target, is the ceiling of `every_tracker_beats_no_tracker` above.
"""


def oracle_text(opts_p_detect: float) -> str:
    """What the oracle knows and its bound, for the report."""
    return f"""The oracle knows how many targets there are and when each is born and dies, which report is whose
and which are clutter, and the truth's motion model (sparse and dense: nearly constant velocity,
q = {Q_ACCEL:g} m²/s³; crossing: straight lines): its bound on each target's position is the
posterior Cramér-Rao bound of that target's own reports, from both sensors (P_D = {opts_p_detect:g}
each as an information reduction factor, evaluated along the run's true path, the birth
intensity's covariance as its prior at the target's first scan; `multitarget/gospa_floor.py`,
`multitarget/benchmark_best.py`). Whole run: the Rauch-Tung-Striebel backward pass over the
bounds (the bound of a smoother that uses every scan of the target's life)."""


DATA = "each target's own labelled position and radar reports, no clutter, drawn on the run's paths"

__all__ = ["LAYOUT", "benchmark_floor_columns", "oracle", "paths", "report_draw"]
