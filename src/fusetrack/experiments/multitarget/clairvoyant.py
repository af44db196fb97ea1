"""A clairvoyant filter beside :mod:`.gospa_floor`'s floor: the oracle's knowledge, run.

Each target is tracked by its own Kalman-type filter (the truth's motion model: for straight
paths ``q = 0``, it knows they are straight) on its *own* reports: every sensor sees it with
probability ``P_D`` and reports with its noise, labelled, with no clutter and no merging -- the
data of the floor's oracle, drawn from the run's true paths by the experiment's ``draw``. It
starts at the target's first scan from ``N(x_0 + w, P_0)``, ``w ~ N(0, P_0)``, ``P_0`` the
floor's prior (the error of the prior mean is then distributed as the prior says), and reports
one estimate per present target. Its mean GOSPA² can be no lower than the online floor (a filter
sees the reports up to the scan only): the check that the floor is not too high, and how close a
filter comes to it. ``multitarget-bearings`` runs an unscented filter on the bearings
(:func:`bearing_draw`; an extended Kalman filter linearised at the first scans' wide prior, 4 m
across the field, loses some targets for good), ``multitarget-benchmark`` the trackers' extended
Kalman filter on the position and radar reports.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ...core import Gaussian, Measurement, Track
from ...sensors import true_bearings
from .gospa_floor import Path
from .scenario import Array, Scene

Draw = Callable[[Array, float, np.random.Generator], list[Measurement]]
"""``draw(x, t, rng)``: one target's labelled reports at time ``t`` from its true state ``x``."""


def bearing_draw(scene: Scene) -> Draw:
    """``multitarget-bearings``' reports of one target: per array, a bearing with noise ``sigma``
    heard with probability ``P_D`` (noise drawn first, then the detection)."""

    def draw(x: Array, t: float, rng: np.random.Generator) -> list[Measurement]:
        return [
            Measurement(t, sid, true_bearings(x[None, :2], (sx, sy)) + noise)
            for sid, sx, sy in scene.arrays
            for noise in [scene.sigma * rng.standard_normal(1)]
            if rng.random() < scene.p_detect
        ]

    return draw


def clairvoyant_tracks(
    kf: Any,
    paths: Sequence[Path],
    times: Array,
    dt: float,
    prior_covs: Sequence[Array],
    draw: Draw,
    rng: np.random.Generator,
) -> list[Track]:
    """One track per target of ``paths`` (module docstring), filtered by ``kf`` (``predict``,
    ``update``), estimates at the scans it is present."""
    out = []
    for i, ((on, x), P0) in enumerate(zip(paths, prior_covs)):
        if len(on) == 0:
            continue
        w = np.linalg.cholesky(P0) @ rng.standard_normal(len(P0))
        belief = Gaussian(x[0] + w, P0)
        means = []
        for j, k in enumerate(on):
            if j:
                belief = kf.predict(belief, dt)
            belief = kf.update(belief, draw(x[j], float(times[k]), rng))
            means.append(belief.mean)
        out.append(Track(times[on], np.array(means), label=f"clairvoyant {i}", id=i))
    return out
