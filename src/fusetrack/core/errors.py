"""One error hierarchy for fusetrack; every message names the field, the value and what is valid."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray


class FusetrackError(Exception):
    """Base class of every error fusetrack raises on purpose."""


class ConfigError(FusetrackError, ValueError):
    """A parameter or configuration value is invalid."""


class ShapeError(FusetrackError, ValueError):
    """An array has the wrong shape."""


class MeasurementError(FusetrackError, ValueError):
    """A measurement cannot be used (wrong size, unknown sensor, bad time order)."""


class UnknownSensorError(MeasurementError, KeyError):
    """A measurement names a sensor the filter was not given."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class UnknownExperimentError(FusetrackError, KeyError):
    """``fusetrack run NAME`` was given a name that is not registered."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class DegenerateWeightsWarning(UserWarning):
    """Every particle's likelihood vanished at a step; the filter recovered (see its counters)."""


def invalid(field: str, value: Any, valid: str) -> str:
    """Message for a bad value: ``invalid('dt', -1, 'a finite number > 0')``."""
    shown = repr(value)
    if len(shown) > 80:
        shown = shown[:77] + "..."
    return f"{field}={shown} is invalid: expected {valid}"


def check_positive(field: str, value: float, *, allow_zero: bool = False) -> float:
    """Return ``float(value)`` or raise :class:`ConfigError` if it is not a finite positive number."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ConfigError(invalid(field, value, "a number")) from None
    ok = v >= 0 if allow_zero else v > 0
    if not (ok and v == v and v != float("inf")):
        raise ConfigError(
            invalid(field, value, "a finite number " + (">= 0" if allow_zero else "> 0"))
        )
    return v


def check_probability(field: str, value: float) -> float:
    """Return ``float(value)`` or raise :class:`ConfigError` if it is outside [0, 1]."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ConfigError(invalid(field, value, "a probability in [0, 1]")) from None
    if not 0.0 <= v <= 1.0:
        raise ConfigError(invalid(field, value, "a probability in [0, 1]"))
    return v


def check_points(field: str, value: ArrayLike, dim: int = 2) -> NDArray[np.float64]:
    """``value`` as a C-contiguous float ``(n, dim)`` array of finite coordinates.

    :class:`ShapeError` if its size is not a whole number of points, :class:`ConfigError`
    naming the first point with a NaN or infinite coordinate (a NaN position would otherwise give
    NaN probabilities downstream, silently)."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(invalid(field, value, f"numbers, {dim} per point")) from None
    if a.size % dim:
        raise ShapeError(invalid(f"{field}.shape", a.shape, f"(n, {dim}): {dim} numbers per point"))
    pts = np.ascontiguousarray(a.reshape(-1, dim))
    if not np.isfinite(pts).all():  # one pass on the hot path; the row only when one is bad
        row = int(np.argmax(~np.isfinite(pts).all(axis=1)))
        raise ConfigError(
            invalid(f"{field}[{row}]", pts[row].tolist(), "finite coordinates (no NaN or inf)")
        )
    return pts
