"""A clairvoyant filter beside :mod:`.gospa_floor`'s floor: the oracle's knowledge, run.

Each target is tracked by its own unscented Kalman filter (nearly constant velocity with ``q = 0``:
it knows the paths are straight; unscented, as an extended Kalman filter linearised at the first
scans' wide prior, 4 m across the field, loses some targets for good) on its *own* bearings: every array hears it with probability
``P_D`` and reports its bearing with noise ``sigma``, labelled, with no clutter and no merging --
the data of the floor's oracle, drawn from the run's true paths. It starts at the target's first
scan from ``N(x_0 + w, P_0)``, ``w ~ N(0, P_0)``, ``P_0`` the floor's prior
(:func:`.gospa_floor.entry_prior_cov`), and reports one estimate per present target. Its mean
GOSPA² can be no lower than the online floor (a filter sees the bearings up to the scan only):
the check that the floor is not too high, and how close a filter comes to it.
"""

from __future__ import annotations

import numpy as np

from ...core import Gaussian, Measurement, Track
from ...filters import UnscentedKalmanFilter
from ...motion import ConstantVelocity
from ...sensors import Bearing, true_bearings
from .gospa_floor import states
from .scenario import Array, Scene, Truth


def clairvoyant_tracks(
    scene: Scene, truth: Truth, prior_covs: Array, rng: np.random.Generator
) -> list[Track]:
    """One track per target (module docstring), estimates at the scans it is present."""
    sensors = [Bearing(sid, position=[x, y], sigma=scene.sigma) for sid, x, y in scene.arrays]
    ukf = UnscentedKalmanFilter(ConstantVelocity(ndim=2, q=0.0), sensors)
    out = []
    for i in range(truth.positions.shape[1]):
        on, x = states(truth.positions[:, i], scene.dt)
        if len(on) == 0:
            continue
        P0 = prior_covs[i]
        belief = Gaussian(x[0] + np.linalg.cholesky(P0) @ rng.standard_normal(4), P0)
        means = []
        for j, k in enumerate(on):
            if j:
                belief = ukf.predict(belief, scene.dt)
            t = float(truth.times[k])
            zs = [
                Measurement(t, sid, true_bearings(x[j : j + 1, :2], (sx, sy)) + noise)
                for sid, sx, sy in scene.arrays
                for noise in [scene.sigma * rng.standard_normal(1)]
                if rng.random() < scene.p_detect
            ]
            belief = ukf.update(belief, zs)
            means.append(belief.mean)
        out.append(Track(truth.times[on], np.array(means), label=f"clairvoyant {i}", id=i))
    return out
