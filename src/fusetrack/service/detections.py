"""Where readings put a target: the position (and its covariance) a single reading implies, and a
tick's position detections for MCMCDA.

* a ``position_fix`` reading is its position, with its own covariance or the sensor's;
* a ``range_bearing`` plot is ``s + r [cos a, sin a]``, ``a = b + heading``, with covariance
  ``J R J^T``, ``J = [[cos a, -r sin a], [sin a, r cos a]]`` (the polar-to-Cartesian Jacobian;
  Bar-Shalom, Li & Kirubarajan 2001, Sec. 10.4.3);
* any other reading (a bearing, a range, a DOA, an image position) implies no position alone.

:func:`implied_position` starts tracks (:class:`ReadingBirth`); :func:`position_detections`
gives MCMCDA its detections, with the grid tracker also the peaks of the tick's other readings
fused on the grid without a temporal prior (Kushwaha 2010, Ch. III: "raw observations obtained
from the multimodal sensor fusion and peak detection", :func:`~fusetrack.association.
likelihood_peaks`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ..association import likelihood_peaks
from ..core import Gaussian, Measurement
from .alignment import Reading
from .config import NetworkConfig, SensorConfig
from .grid_cells import CellLikelihoods

Array = NDArray[np.float64]

POSITION_KINDS: tuple[str, ...] = ("position_fix", "range_bearing")
"""Reading kinds that put a target at a position on their own."""


def implied_position(
    sensor: SensorConfig, value: Array, covariance: Array | None = None
) -> tuple[Array, Array] | None:
    """``(position, covariance)`` that one reading of ``sensor`` implies (module docstring), or
    None for a kind that implies none."""
    z = np.asarray(value, dtype=float)
    if sensor.kind == "position_fix":
        cov = sensor.cov if covariance is None else covariance
        return z.copy(), np.asarray(cov, dtype=float)
    if sensor.kind != "range_bearing":
        return None
    assert sensor.position is not None  # validated: a range_bearing sensor has one
    r, a = float(z[0]), float(z[1]) + sensor.heading
    c, s = math.cos(a), math.sin(a)
    where = np.array([sensor.position[0] + r * c, sensor.position[1] + r * s])
    noise = (
        np.diag([float(sensor.sigma_range or 0.0) ** 2, float(sensor.sigma_bearing or 0.0) ** 2])
        if covariance is None
        else np.asarray(covariance, dtype=float)
    )
    jac = np.array([[c, -r * s], [s, r * c]])
    cov = jac @ noise @ jac.T
    return where, 0.5 * (cov + cov.T)


class ReadingBirth:
    """The belief of a track started by a reading (``prior_from`` of an
    :class:`~fusetrack.tracking.Initiator`): the position the reading implies
    (:func:`implied_position`), every other state entry (velocities) from the tracker's
    ``prior_mean``/``prior_std``, uncorrelated; None for readings that imply no position."""

    def __init__(self, cfg: NetworkConfig) -> None:
        self.sensors = {s.id: s for s in cfg.sensors}
        self.position_index = list(cfg.tracker.motion.build().position_index)
        self.prior = cfg.tracker.prior()

    def __call__(self, measurement: Measurement) -> Gaussian | None:
        implied = implied_position(
            self.sensors[measurement.sensor_id], measurement.value, measurement.covariance
        )
        if implied is None:
            return None
        p, cov_p = implied
        idx = self.position_index[: p.size]
        mean, cov = self.prior.mean.copy(), self.prior.cov.copy()
        mean[idx] = p
        cov[idx, :] = 0.0
        cov[:, idx] = 0.0
        cov[np.ix_(idx, idx)] = cov_p
        return Gaussian(mean, cov)


def position_detections(
    cfg: NetworkConfig, readings: Sequence[Reading], cells: CellLikelihoods | None
) -> Array:
    """The tick's position detections ``(k, 2)`` (module docstring), in reading order, then the
    grid peaks."""
    sensors = {s.id: s for s in cfg.sensors}
    out: list[list[float]] = []
    rest: list[Reading] = []
    for r in readings:
        s = sensors[r.sensor]
        if s.kind in POSITION_KINDS:
            implied = implied_position(s, r.value, r.covariance)
            assert implied is not None
            out.append([float(implied[0][0]), float(implied[0][1])])
        else:
            rest.append(r)
    if cells is not None and rest:
        fused = cells.fused(rest, cfg.tracker.grid.fusion)
        if fused is not None:
            g = cells.grid
            peaks = likelihood_peaks(fused, g.x, g.y, 0.3, 4.0 / g.size)
            out.extend(peaks.tolist())
    return np.array(out, dtype=float).reshape(-1, 2)
