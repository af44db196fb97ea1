"""Track initiation: which unassociated measurements start tracks, with what belief, and when a
tentative track becomes confirmed (or is dropped).

An initiator has ``existence`` (the existence probability of a new track), ``birth(measurement)
-> belief | None`` (the belief of a track started by a measurement, at its time and already
conditioned on it; None: this measurement starts no track) and ``status(track)``, called after
every scan on each tentative track: ``"confirmed"``, ``"tentative"`` or ``"dropped"``.

* :class:`MofNInitiator` -- the M-of-N rule (Blackman & Popoli 1999, Sec. 3.2.3; Bar-Shalom,
  Willett & Tian 2011, Sec. 3.4): a track is confirmed when it has been detected in ``m`` of its
  first ``n`` scans (its birth scan counts as one), dropped as soon as that can no longer happen.
* :class:`SinglePointInitiator` -- every unassociated measurement starts a confirmed track
  (M-of-N with ``m = n = 1``); leave the rest to the deleters.
* :class:`~fusetrack.tracking.PHDInitiator` -- a *scan-level* initiator: instead of
  ``birth(measurement)`` per measurement it has ``initial_state()`` and ``births(state, time,
  sensor_id, measurements, rng) -> (state, [(belief, measurement index or None)])``, sees one
  sensor's leftovers of a scan at once and keeps its own state (a GM-PHD intensity) in the
  tracker's state (:mod:`.phd_initiator`).

The belief of a new track comes from ``prior_from(measurement)``: any function, or
:class:`InverseMeasurementPrior`, which inverts a linear sensor (a position fix, a
:class:`~fusetrack.sensors.LinearGaussianSensor`): the state components the sensor sees come from
the measurement, the others (velocity) from a wide prior.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from ..core import ConfigError, Gaussian, Measurement, SensorModel, check_probability, invalid
from .state import LiveTrack

Status = Literal["confirmed", "tentative", "dropped"]
PriorFrom = Callable[[Measurement], Any]


@runtime_checkable
class Initiator(Protocol):
    """Starts tracks from unassociated measurements and confirms them (module docstring)."""

    @property
    def existence(self) -> float: ...

    def birth(self, measurement: Measurement) -> Any: ...

    def status(self, track: LiveTrack) -> Status: ...


@dataclass(frozen=True)
class MofNInitiator:
    """Confirm a track detected in ``m`` of its first ``n`` scans; drop it when it can no
    longer be (``hits + scans left < m``). New tracks get ``prior_from(measurement)`` (a belief
    at the measurement's time that includes it, or None for no track) and existence
    probability ``existence``."""

    m: int
    n: int
    prior_from: PriorFrom
    existence: float = 0.5

    def __post_init__(self) -> None:
        for name in ("m", "n"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
                raise ConfigError(invalid(name, value, "an integer >= 1"))
        if self.m > self.n:
            raise ConfigError(
                invalid("m", self.m, f"at most n={self.n} (m hits in the first n scans)")
            )
        if not callable(self.prior_from):
            raise ConfigError(
                invalid("prior_from", self.prior_from, "a function measurement -> belief or None")
            )
        existence = check_probability("existence", self.existence)
        if existence == 0.0:
            raise ConfigError(invalid("existence", self.existence, "a probability in (0, 1]"))

    def birth(self, measurement: Measurement) -> Any:
        return self.prior_from(measurement)

    def status(self, track: LiveTrack) -> Status:
        if track.confirmed or (track.hits >= self.m and track.scans <= self.n):
            return "confirmed"
        if track.hits + (self.n - track.scans) < self.m:
            return "dropped"
        return "tentative"


class SinglePointInitiator(MofNInitiator):
    """Every unassociated measurement starts a confirmed track with ``prior_from(measurement)``
    (:class:`MofNInitiator` with ``m = n = 1``)."""

    def __init__(self, prior_from: PriorFrom, *, existence: float = 0.5) -> None:
        super().__init__(1, 1, prior_from, existence)


@dataclass(frozen=True)
class _Inverse:
    """A linear sensor ``z = H x + c + v`` solved for the components it sees."""

    observed: NDArray[np.intp]  # the state indices the sensor sees
    pinv: NDArray[np.float64]  # (k, m): H_o^+
    offset: NDArray[np.float64]  # (m,): c = h(0)
    noise: NDArray[np.float64]  # (m, m): R


def _invert_linear(sensor: SensorModel, dim: int) -> _Inverse:
    """``H``, ``c`` and ``R`` of ``sensor`` if it is linear and not angular, else ConfigError."""
    sid = sensor.sensor_id
    zero = np.zeros(dim)
    try:
        h = np.asarray(sensor.jacobian(zero), float).reshape(-1, dim)
        c = np.asarray(sensor.predict(zero), float).reshape(-1)
        probe = np.linspace(1.0, 2.0, dim) * 3.7
        linear = np.allclose(sensor.predict(probe), h @ probe + c, rtol=1e-9, atol=1e-9)
        linear = linear and np.allclose(sensor.jacobian(probe), h, rtol=1e-12, atol=1e-12)
        r = np.asarray(sensor.noise_cov(zero), float).reshape(h.shape[0], h.shape[0])
    except Exception as err:  # a sensor that fails on these probes cannot be inverted here
        raise ConfigError(
            invalid("sensors", sid, f"a linear sensor for a {dim}-dimensional state ({err})")
        ) from err
    if any(sensor.angular) or not linear:
        raise ConfigError(
            invalid(
                "sensors",
                sid,
                "a linear sensor z = H x + c + v (pass your own prior_from for other sensors)",
            )
        )
    observed = np.flatnonzero(np.any(h != 0.0, axis=0))
    h_o = h[:, observed]
    if observed.size == 0 or np.linalg.matrix_rank(h_o) < observed.size:
        raise ConfigError(
            invalid("sensors", sid, "a sensor that determines the state components it sees")
        )
    return _Inverse(observed, np.linalg.pinv(h_o), c, r)


@dataclass(frozen=True, eq=False)
class InverseMeasurementPrior:
    """``prior_from`` for linear sensors: the belief of a track started by a measurement ``z``.

    For a sensor ``z = H x + c + v``, ``v ~ N(0, R)`` (``R`` the measurement's own covariance
    when it has one) the components ``o`` it sees (the nonzero columns of ``H``) are the least
    squares solution ``x_o = H_o^+ (z - c)`` with covariance ``H_o^+ R H_o^+T``; the other
    components (a position fix's velocity) keep the mean and covariance of ``unobserved``, a
    wide Gaussian over the whole state, and are uncorrelated with ``x_o``. Measurements of
    sensors not in ``sensors`` start no track (None): e.g. give only the position sensors, not
    the bearing ones.

    >>> from fusetrack.sensors import PositionFix
    >>> prior = InverseMeasurementPrior([PositionFix("tag", cov=np.eye(2))],
    ...                                 Gaussian(np.zeros(4), 100.0 * np.eye(4)))
    >>> prior(Measurement(0.0, "tag", [3.0, 4.0])).mean.tolist()
    [3.0, 4.0, 0.0, 0.0]
    """

    sensors: Mapping[str, SensorModel] | Sequence[SensorModel]
    unobserved: Gaussian
    _inverses: dict[str, _Inverse] = field(init=False, repr=False)
    _covs: dict[str, NDArray[np.float64]] = field(init=False, repr=False)  # with the sensor's R

    def __post_init__(self) -> None:
        if not isinstance(self.unobserved, Gaussian) or self.unobserved.mean.ndim != 1:
            raise ConfigError(
                invalid("unobserved", self.unobserved, "a Gaussian over one state (d,)")
            )
        items = list(self.sensors.values() if isinstance(self.sensors, Mapping) else self.sensors)
        dim = self.unobserved.dim
        inverses = {str(s.sensor_id): _invert_linear(s, dim) for s in items}
        object.__setattr__(self, "_inverses", inverses)
        covs = {sid: self._covariance(inv, inv.noise) for sid, inv in inverses.items()}
        object.__setattr__(self, "_covs", covs)

    def _covariance(self, inv: _Inverse, r: NDArray[np.float64]) -> NDArray[np.float64]:
        """The new track's covariance for a measurement with noise covariance ``r``."""
        cov = self.unobserved.cov.copy()
        o = inv.observed
        cov[o, :] = 0.0
        cov[:, o] = 0.0
        cov[np.ix_(o, o)] = inv.pinv @ r @ inv.pinv.T
        return np.asarray(0.5 * (cov + cov.T))

    def __call__(self, measurement: Measurement) -> Gaussian | None:
        sid = measurement.sensor_id
        inv = self._inverses.get(sid)
        if inv is None:
            return None
        own = measurement.covariance
        cov = self._covs[sid].copy() if own is None else self._covariance(inv, own)
        mean = self.unobserved.mean.copy()
        mean[inv.observed] = inv.pinv @ (np.asarray(measurement.value, float) - inv.offset)
        return Gaussian(mean, cov)
