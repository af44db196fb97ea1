"""Time-stamped measurements, the values that flow from sensors to trackers."""

from __future__ import annotations

import itertools
import math
import numbers
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import MeasurementError, invalid

_VECTOR_TYPES = (np.ndarray, np.generic, numbers.Number, list, tuple)


@dataclass(frozen=True, eq=False)
class Measurement:
    """One sensor report.

    ``value`` has shape ``(m,)`` for one run, or ``(..., m)`` when the leading axes are batched
    Monte Carlo runs (one report per run at the same time). A report that is not a vector (a
    video frame's features, a detection list) is any other object, kept as given and read by
    its sensor model. ``covariance`` overrides the sensor's own noise when given. ``metadata``
    carries anything else (frame index, SNR, ...).

    >>> Measurement(0.5, "mic1", [0.3]).value
    array([0.3])
    """

    time: float
    sensor_id: str
    value: Any  # NDArray[np.float64] (m,) or (..., m), or a non-vector report (see above)
    covariance: NDArray[np.float64] | None = None
    metadata: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        try:
            t = float(self.time)
        except (TypeError, ValueError):
            raise MeasurementError(
                invalid("time", self.time, "a finite number (seconds)")
            ) from None
        if not math.isfinite(t):
            raise MeasurementError(invalid("time", self.time, "a finite number (seconds)"))
        object.__setattr__(self, "time", t)
        if not isinstance(self.sensor_id, str) or not self.sensor_id:
            raise MeasurementError(invalid("sensor_id", self.sensor_id, "a non-empty string"))
        if not isinstance(self.value, _VECTOR_TYPES):
            if self.covariance is not None:
                raise MeasurementError(
                    invalid("covariance", self.covariance, "None when the value is not a vector")
                )
            return
        v = self.value
        if type(v) is not np.ndarray or v.dtype != np.float64 or v.ndim == 0:
            v = np.atleast_1d(np.asarray(v, dtype=float))  # (an (m,) float array is kept as is)
            object.__setattr__(self, "value", v)
        if self.covariance is not None:
            c = np.atleast_2d(np.asarray(self.covariance, dtype=float))
            m = v.shape[-1]
            if c.shape[-2:] != (m, m):
                raise MeasurementError(
                    invalid(
                        "covariance", c.shape, f"shape (..., {m}, {m}) to match value of size {m}"
                    )
                )
            object.__setattr__(self, "covariance", c)

    @property
    def is_finite(self) -> bool:
        """False when any entry of the value is NaN or infinite (such reports are skipped)."""
        if not isinstance(self.value, np.ndarray):
            return True  # a non-vector report: its sensor model judges it
        return bool(np.all(np.isfinite(self.value)))


def as_measurements(items: Iterable[Measurement | tuple[Any, ...]]) -> list[Measurement]:
    """Accept measurements or ``(time, sensor_id, value[, covariance])`` tuples."""
    out = []
    for item in items:
        out.append(item if isinstance(item, Measurement) else Measurement(*item))
    return out


def order_by_time(
    measurements: Iterable[Measurement], policy: Literal["reject", "reorder"] = "reject"
) -> list[Measurement]:
    """Return measurements in time order.

    ``policy='reject'`` raises :class:`MeasurementError` on the first out-of-order timestamp;
    ``'reorder'`` sorts stably by time.
    """
    ms = list(measurements)
    if policy == "reorder":
        return sorted(ms, key=lambda m: m.time)
    if policy != "reject":
        raise MeasurementError(invalid("policy", policy, "'reject' or 'reorder'"))
    for prev, cur in itertools.pairwise(ms):
        if cur.time < prev.time:
            raise MeasurementError(
                f"measurement from {cur.sensor_id!r} at time={cur.time} comes after one at "
                f"time={prev.time}: timestamps must not decrease (pass order='reorder' to sort them)"
            )
    return ms


def group_by_time(
    measurements: Iterable[Measurement], tolerance: float = 1e-9
) -> Iterator[tuple[float, list[Measurement]]]:
    """Yield ``(time, [measurements at that time])`` from a time-ordered sequence."""
    group: list[Measurement] = []
    t0 = 0.0
    for m in measurements:
        if group and m.time - t0 > tolerance:
            yield t0, group
            group = []
        if not group:
            t0 = m.time
        group.append(m)
    if group:
        yield t0, group


def stack_values(measurements: Iterable[Measurement]) -> NDArray[np.float64]:
    """Stack measurement values along a new first axis."""
    return np.stack([np.asarray(m.value, float) for m in measurements])


def measurement(time: float, sensor_id: str, value: ArrayLike, **kw: Any) -> Measurement:
    """Shorthand constructor."""
    return Measurement(time, sensor_id, np.asarray(value, dtype=float), **kw)
