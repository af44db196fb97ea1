"""A measurement series prepared once for many log-likelihood evaluations.

Parameter estimation evaluates ``log p(z_1:T | theta)`` for hundreds of parameter values on the
same measurements. :func:`prepare_series` does the per-series work once: time order, the steps
of :func:`~fusetrack.filters.run_filter` (measurements within 1e-9 s applied together, the
``dt`` predicted over before each), and, when every value is a plain finite vector without its
own covariance, the layout of the stacked measurement vector of each step (which rows each
sensor's report fills) that the whole-run kernels of :mod:`.linear_gaussian` read.

Per model, :func:`linear_gaussian_arrays` turns a linear-Gaussian motion model
(``fused_transition(dt) -> (F, G)``, ``G G^T = Q``) and linear-Gaussian sensors
(``z = H x + v``, ``v ~ N(0, R)``) into whitened arrays: with ``L L^T = R``, the rows of step
``k`` are ``L^-1 z`` and ``L^-1 H`` so that ``log N(z; H x, R) = c_k - |L^-1 z - L^-1 H x|^2 / 2``
with ``c_k = -(m log 2 pi + log det R) / 2`` summed over the step's reports. Rows a step does
not fill are zero and add nothing.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..core import (
    ConfigError,
    Measurement,
    MeasurementError,
    as_measurements,
    group_by_time,
    invalid,
    order_by_time,
)
from ..sensors import LinearGaussianSensor

Array = NDArray[np.float64]
TIME_TOLERANCE = 1e-9  # as run_filter: reports closer than this are one step

__all__ = ["LinearGaussianArrays", "Series", "linear_gaussian_arrays", "prepare_series"]


@dataclass(frozen=True, eq=False)
class _SensorRows:
    """Where one sensor's reports go: their steps ``(K,)``, first rows ``(K,)``, values
    ``(K, m)`` and how many it makes at each step ``(T,)``."""

    steps: NDArray[np.intp]
    rows: NDArray[np.intp]
    values: Array
    per_step: Array


@dataclass(frozen=True, eq=False)
class Series:
    """Time-ordered measurements grouped into filter steps (see the module docstring).

    ``measurements`` in time order; ``t0`` the prior's time (None: the first step's);
    ``dts`` ``(T,)`` the interval predicted over before step ``k`` (0: no prediction), the
    distinct positive ones ``moving_dts`` ``(U,)`` and ``step_dt`` ``(T,)`` the index of step
    ``k``'s among them (-1: no prediction);
    ``layout`` per sensor id the rows of its reports and ``n_rows`` the longest stacked vector,
    or None when some report is not a finite vector without its own covariance (then only the
    generic filter loop applies).
    """

    measurements: tuple[Measurement, ...]
    t0: float | None
    dts: Array
    moving_dts: Array
    step_dt: NDArray[np.intp]
    layout: Mapping[str, _SensorRows] | None
    n_rows: int

    @property
    def n_steps(self) -> int:
        return int(self.dts.size)


def _step_dts(groups: list[tuple[float, list[Measurement]]], t0: float | None) -> Array:
    """``dt`` before each step, as :func:`~fusetrack.filters.run_filter` steps."""
    if t0 is not None:
        t0 = float(t0)
        if not math.isfinite(t0):
            raise ConfigError(invalid("t0", t0, "a finite time (seconds) or None"))
        if groups and groups[0][0] < t0 - TIME_TOLERANCE:
            raise MeasurementError(
                invalid("t0", t0, f"a time <= the first measurement's time {groups[0][0]}")
            )
    t_prev = t0 if t0 is not None else (groups[0][0] if groups else 0.0)
    dts = np.zeros(len(groups))
    for k, (t, _) in enumerate(groups):
        if t - t_prev > TIME_TOLERANCE:
            dts[k] = t - t_prev
            t_prev = t
    return dts


def _vector(m: Measurement) -> Array | None:
    """The report as a finite 1-D float vector, or None (batched, raw, NaN, own covariance)."""
    if m.covariance is not None or not isinstance(m.value, np.ndarray):
        return None
    v = m.value
    if v.ndim != 1 or v.dtype.kind != "f" or not np.all(np.isfinite(v)):
        return None
    return v


def _layout(groups: list[tuple[float, list[Measurement]]]) -> tuple[dict[str, _SensorRows], int]:
    """Each sensor's rows in the stacked vector of each step (reports in the order given)."""
    by_sensor: dict[str, tuple[list[int], list[int], list[Array]]] = {}
    width = 0
    for k, (_, group) in enumerate(groups):
        row = 0
        for m in group:
            v = _vector(m)
            if v is None:
                raise _NotPlain
            steps, rows, values = by_sensor.setdefault(m.sensor_id, ([], [], []))
            if values and values[0].size != v.size:
                raise _NotPlain  # inconsistent sizes: the generic path reports it
            steps.append(k)
            rows.append(row)
            values.append(v)
            row += v.size
        width = max(width, row)
    layout = {
        sid: _SensorRows(
            np.array(s, dtype=np.intp),
            np.array(r, dtype=np.intp),
            np.stack(v).astype(float),
            np.bincount(s, minlength=len(groups)).astype(float),
        )
        for sid, (s, r, v) in by_sensor.items()
    }
    return layout, width


class _NotPlain(Exception):
    """A report the whole-run kernels cannot take."""


def prepare_series(
    measurements: Iterable[Measurement | tuple[Any, ...]] | Series, t0: float | None = None
) -> Series:
    """The measurements as a :class:`Series` (a :class:`Series` is returned as it is).

    ``t0`` is the prior's time as in :func:`~fusetrack.filters.run_filter` (default: the
    first measurement's time, no prediction before the first update). Measurements must be in
    time order (:class:`~fusetrack.core.MeasurementError` otherwise).
    """
    if isinstance(measurements, Series):
        if t0 is not None and t0 != measurements.t0:
            raise ConfigError(invalid("t0", t0, f"None or the series' own t0 {measurements.t0}"))
        return measurements
    ms = order_by_time(as_measurements(measurements), "reject")
    if not ms:
        raise MeasurementError(invalid("measurements", "[]", "at least one measurement"))
    groups = list(group_by_time(ms, tolerance=TIME_TOLERANCE))
    dts = _step_dts(groups, t0)
    try:
        layout: dict[str, _SensorRows] | None
        layout, width = _layout(groups)
    except _NotPlain:
        layout, width = None, 0
    moving, step_dt = np.unique(dts[dts > 0], return_inverse=True)
    index = np.full(dts.size, -1, dtype=np.intp)
    index[dts > 0] = step_dt
    return Series(tuple(ms), None if t0 is None else float(t0), dts, moving, index, layout, width)


@dataclass(frozen=True, eq=False)
class LinearGaussianArrays:
    """A linear-Gaussian model on a series, as the whole-run kernels read it.

    ``F``, ``G`` ``(U, d, d)``: the transition and noise factor for each distinct ``dt``
    (``U >= 1``: zeros when no step predicts);
    ``step_dt`` ``(T,)`` which of them step ``k`` predicts with (-1: no prediction);
    ``WH`` ``(T, M, d)``, ``Wz`` ``(T, M)``, ``c`` ``(T,)``: the whitened rows and constants
    (module docstring); ``mean0`` ``(d,)``, ``cov0`` ``(d, d)``: the prior.
    """

    F: Array
    G: Array
    step_dt: NDArray[np.intp]
    WH: Array
    Wz: Array
    c: Array
    mean0: Array
    cov0: Array


def _transitions(motion: Any, dts: Array, d: int) -> tuple[Array, Array] | None:
    """``(F, G)`` ``(U, d, d)`` of ``motion`` at each of ``dts``, or None."""
    offer = getattr(motion, "fused_transition", None)
    if not callable(offer):
        return None
    F = np.zeros((max(dts.size, 1), d, d))  # one unused entry when nothing is predicted
    G = np.zeros_like(F)
    for u, dt in enumerate(dts):
        fg = offer(float(dt))
        if fg is None:
            return None
        F[u], G[u] = fg
    return F, G


def linear_gaussian_arrays(
    motion: Any, sensors: Mapping[str, Any], prior: Any, series: Series
) -> LinearGaussianArrays | None:
    """The kernels' arrays for ``motion``, ``sensors`` and a Gaussian ``prior`` on ``series``;
    None when the models or the series are not of that form (then the generic loop runs, and
    reports any error there)."""
    mean0 = np.asarray(getattr(prior, "mean", None), dtype=float)
    d = int(getattr(motion, "dim", -1))
    if series.layout is None or mean0.shape != (d,):
        return None
    tr = _transitions(motion, series.moving_dts, d)
    if tr is None:
        return None
    T, M = series.n_steps, series.n_rows
    WH = np.zeros((T, M, d))
    Wz = np.zeros((T, M))
    c = np.zeros(T)
    for sid, rows in series.layout.items():
        sensor = sensors.get(sid)
        if type(sensor) is not LinearGaussianSensor:
            return None
        H = np.asarray(sensor.H, dtype=float)
        m = rows.values.shape[1]
        if H.shape != (m, d):
            return None
        chol = np.linalg.cholesky(np.asarray(sensor.R, dtype=float))
        white = np.linalg.inv(chol)
        wh = white @ H
        wz = rows.values @ white.T
        for j in range(m):
            WH[rows.steps, rows.rows + j] = wh[j]
            Wz[rows.steps, rows.rows + j] = wz[:, j]
        const = -0.5 * (m * math.log(2.0 * math.pi)) - float(np.log(np.diag(chol)).sum())
        c += const * rows.per_step
    cov0 = np.asarray(prior.cov, dtype=float)
    return LinearGaussianArrays(tr[0], tr[1], series.step_dt, WH, Wz, c, mean0, cov0)
