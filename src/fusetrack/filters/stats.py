"""Bookkeeping shared by every filter: a counter of what went wrong, and measurement checks.

A long run must never die for one bad report. Filters therefore split bad
input in two kinds:

* **Programming errors** raise at once: a measurement from a sensor the filter was not given
  (:class:`~fusetrack.core.UnknownSensorError`, naming the id and the known ids) or a value whose
  size does not match the sensor (:class:`~fusetrack.core.MeasurementError`, naming ``m``).
* **Bad data** is skipped and counted: a value with NaN or infinite entries (a sensor that saw
  nothing, a dropped packet) leaves the belief unchanged and adds one to
  :attr:`FilterStats.skipped_measurements` per run in which it was skipped.

>>> import numpy as np
>>> from fusetrack.core import Measurement
>>> stats = FilterStats()
>>> class Mic:  # any object with sensor_id and dim works here
...     sensor_id, dim = "mic", 1
>>> v = validate_measurement(Measurement(0.0, "mic", [np.nan]), {"mic": Mic()}, stats)
>>> bool(v.usable), stats.skipped_measurements
(False, 1)
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..core import (
    ConfigError,
    DegenerateWeightsWarning,
    Measurement,
    MeasurementError,
    SensorModel,
    UnknownSensorError,
    invalid,
)


@dataclass
class FilterStats:
    """Mutable counters a filter keeps while it runs (``filter.stats``).

    ``skipped_measurements``
        reports ignored because their value was NaN or infinite; with batched values
        ``(R, m)`` each skipped row counts once.
    ``degenerate_steps``
        steps where the filter had to recover: all particle weights vanished, or a Gaussian
        filter met a singular innovation covariance or a covariance that was not positive
        definite (one per step, however many batched runs were affected).
    ``resample_count``
        how many times a particle filter resampled (one per step, however many runs).
    """

    skipped_measurements: int = 0
    degenerate_steps: int = 0
    resample_count: int = 0

    def reset(self) -> None:
        """Set every counter back to zero."""
        self.skipped_measurements = 0
        self.degenerate_steps = 0
        self.resample_count = 0

    def as_dict(self) -> dict[str, int]:
        """The counters as a plain dict (a snapshot: later steps do not change it)."""
        return asdict(self)

    def note_degenerate(self, owner: str, what: str, stacklevel: int = 3) -> None:
        """Count a step whose particle weights vanished (``degenerate_steps``) and warn once
        per stats object with :class:`~fusetrack.core.DegenerateWeightsWarning`; ``what`` says
        what happened and how the filter recovered. The particle filters all report here."""
        self.degenerate_steps += 1
        if self.__dict__.get("_warned"):  # not a dataclass field: not a counter
            return
        self.__dict__["_warned"] = True
        warnings.warn(
            f"{owner}: every particle's likelihood vanished ({what}). Counted in "
            "stats.degenerate_steps; this warning is shown once per filter.",
            DegenerateWeightsWarning,
            stacklevel=stacklevel + 1,
        )


def as_sensor_map(
    sensors: Mapping[str, SensorModel] | Sequence[SensorModel] | SensorModel,
) -> dict[str, SensorModel]:
    """Key sensors by id: a mapping is copied as is; a sequence (or one sensor) is keyed by
    each sensor's ``sensor_id``. Two sensors with the same id raise :class:`ConfigError`."""
    if isinstance(sensors, Mapping):
        return dict(sensors)
    items: Sequence[Any] = [sensors] if hasattr(sensors, "sensor_id") else list(sensors)
    out: dict[str, SensorModel] = {}
    for s in items:
        sid = getattr(s, "sensor_id", None)
        if not isinstance(sid, str):
            raise ConfigError(invalid("sensors", s, "sensor models, each with a str sensor_id"))
        if sid in out:
            raise ConfigError(invalid("sensor_id", sid, "ids that are unique among the sensors"))
        out[sid] = s
    return out


class ValidatedMeasurement(NamedTuple):
    """What :func:`validate_measurement` returns.

    ``usable`` has the shape of the value's leading (batch) axes, ``()`` for a single report:
    True where the row is finite and may be used. ``value`` is the measurement value with the
    unusable rows left as they were (callers must mask them, e.g. with ``np.where``).
    """

    sensor: SensorModel
    value: NDArray[np.float64]
    covariance: NDArray[np.float64] | None
    usable: NDArray[np.bool_]


def validate_measurement(
    measurement: Measurement,
    sensors: Mapping[str, SensorModel],
    stats: FilterStats | None = None,
) -> ValidatedMeasurement:
    """Check ``measurement`` against the filter's sensors; count non-finite rows in ``stats``.

    Raises :class:`UnknownSensorError` if ``measurement.sensor_id`` is not a key of ``sensors``
    and :class:`MeasurementError` if the value's last axis is not the sensor's ``dim``.
    Rows whose value (or given covariance) has a NaN or infinite entry are marked unusable and
    add to ``stats.skipped_measurements``.
    """
    sid = measurement.sensor_id
    try:
        sensor = sensors[sid]
    except KeyError:
        known = sorted(sensors)
        raise UnknownSensorError(
            invalid("sensor_id", sid, f"one of the filter's sensors {known}")
            + f" (measurement at time={measurement.time})"
        ) from None
    value = np.asarray(measurement.value, dtype=float)
    # a sensor whose raw value is not its m-vector (an edge frame read through ``residual`` as a
    # linearised pseudo-measurement) says how long the value is in ``value_size``
    m = int(getattr(sensor, "value_size", sensor.dim))
    if value.shape[-1] != m:
        raise MeasurementError(
            invalid(
                f"value.shape (sensor {sid!r}, time={measurement.time})",
                value.shape,
                f"a last axis of size m={m}, the dimension of sensor {sid!r}",
            )
        )
    usable = np.isfinite(value).all(axis=-1)  # the method: no np.all wrapper per report
    cov = measurement.covariance
    if cov is not None:
        cov = np.asarray(cov, dtype=float)
        cov_ok = np.isfinite(cov).all(axis=(-2, -1))
        usable = usable & cov_ok
    n_bad = int(usable.size - np.count_nonzero(usable))
    if stats is not None and n_bad:
        stats.skipped_measurements += n_bad
    return ValidatedMeasurement(sensor, value, cov, np.asarray(usable, dtype=bool))
