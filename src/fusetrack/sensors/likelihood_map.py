"""A sensor whose report is a likelihood map: ``p(report | target in cell i)`` for every cell of a
regular 2-D grid.

Kushwaha 2010 (Ch. III) fuses acoustic beam energies and camera column scores this way: each
detection function is averaged over the arc every cell subtends at the sensor (Eq. 32), floored
and normalised (:func:`fusetrack.sensors.detection_function.normalize_likelihood`), and the grid
filter (:class:`fusetrack.filters.grid.GridFilter`) multiplies or sums these maps. The map is
computed where the report is made (the service's readings, the experiment's fusion node); this
model only interprets it: as a row of cells for the grid, or as ``log p(z | x)`` for any state
array ``x`` (the cell that holds each ``x``; states off the grid take the nearest edge cell).
The report's quality q_k (Eq. 31) travels in the measurement's ``metadata["quality"]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core.errors import MeasurementError, ShapeError, invalid


@dataclass(frozen=True, eq=False)
class LikelihoodMapSensor:
    """``axes``: the cell centres along x and along y (regular spacing); a report has one
    non-negative entry per cell in C order of ``(len(axes[0]), len(axes[1]))`` (x slow).
    ``modality`` groups sensors for hybrid fusion (Kushwaha 2010, Eqs. 36–37)."""

    sensor_id: str
    axes: tuple[NDArray[np.float64], NDArray[np.float64]]
    modality: str = "all"

    def __post_init__(self) -> None:
        axes = tuple(np.asarray(a, float).ravel() for a in self.axes)
        if len(axes) != 2 or any(a.size < 1 for a in axes):
            raise ShapeError(invalid("axes", self.axes, "two non-empty arrays of cell centres"))
        object.__setattr__(self, "axes", axes)

    @property
    def shape(self) -> tuple[int, int]:
        return (self.axes[0].size, self.axes[1].size)

    @property
    def size(self) -> int:
        return self.shape[0] * self.shape[1]

    def cell_likelihood(self, z: ArrayLike) -> NDArray[np.float64]:
        """The report as the grid's per-cell likelihood ``(cells,)`` (checked, not copied)."""
        v = np.asarray(z, float)
        if v.shape != (self.size,):
            raise MeasurementError(
                invalid(f"{self.sensor_id}.value", v.shape, f"({self.size},): one entry per cell")
            )
        if not (v.min() >= 0 and np.isfinite(v.sum())):  # NaN fails the first test
            raise MeasurementError(
                invalid(f"{self.sensor_id}.value", "negative or non-finite", "likelihoods >= 0")
            )
        return v

    def cell_index(self, x: ArrayLike) -> NDArray[np.int64]:
        """The flat index of the cell nearest to each state's position ``x[..., :2]``."""
        p = np.asarray(x, float)
        idx = []
        for k, a in enumerate(self.axes):
            step = a[1] - a[0] if a.size > 1 else 1.0
            i = np.rint((p[..., k] - a[0]) / step).astype(np.int64)
            idx.append(np.clip(i, 0, a.size - 1))
        return np.asarray(idx[0] * self.shape[1] + idx[1], dtype=np.int64)

    def log_likelihood(self, z: ArrayLike, x: ArrayLike) -> NDArray[np.float64]:
        """``log p(z | x)``: the log of the map at the cell holding each state, ``(...)``."""
        lik = self.cell_likelihood(z)
        with np.errstate(divide="ignore"):
            return np.asarray(np.log(lik)[self.cell_index(x)], dtype=np.float64)


def detection_quality(values: ArrayLike) -> float | None:
    """A report's quality q_k = max(λ - min λ) / Σ(λ - min λ) (Kushwaha 2010, Eq. 31 with the
    reliability r_k = 1, spec 003 A-III-11); None when ``values`` are flat (nothing seen)."""
    v = np.asarray(values, float)
    shifted = v - v.min()
    total = shifted.sum()
    if not total > 0:
        return None
    return float(shifted.max() / total)
