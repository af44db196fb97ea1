"""Track births from a GM-PHD intensity over the measurements no track took (a PHD-driven
initiator, after Panta, Vo & Singh 2009, "Data association and track management for the
Gaussian mixture probability hypothesis density filter", IEEE TAES 45(3), where the PHD filter
proposes the tracks; here it runs on the leftovers only).

The initiator keeps a :class:`~fusetrack.filters.GMPHDFilter` intensity of the targets that no
track explains yet (:class:`PHDBirthState`, carried in the tracker's state). Every scan, for
each sensor that looked:

1. the intensity is predicted to the scan time (once per scan; the PHD's birth intensity is
   added there, Vo & Ma 2006 Eq. 21);
2. it is updated with the sensor's measurements that no track took (none: the missed-detection
   term only, the PHD filter's "looked and saw nothing" report);
3. every component whose weight exceeds ``threshold`` leaves the intensity and becomes a
   tentative track with its mean and covariance; the measurement it is credited with is the
   leftover nearest to it (squared Mahalanobis distance,
   :func:`~fusetrack.association.mahalanobis_squared`).

A false alarm alone lifts a birth component's weight to about ``p_D w_b q(z) / kappa`` (small
for a wide birth intensity), while a second detection that fits its motion lifts it near 1, so
tracks start from consistent pairs of detections, not from every unassociated measurement, and a
scan of thousands of false alarms starts almost none. Tentative tracks are then confirmed by the
M-of-N rule (:class:`~fusetrack.tracking.MofNInitiator`'s), counting the birth scan as a hit.

A wide birth component and Vo & Ma's merging do not mix well: the merge test
``(m_i - m_j)^T P_i^-1 (m_i - m_j) <= U`` uses the candidate's own covariance, so the wide
(missed) birth component is folded into every tight component within ``U`` of it and drags
its mean towards the birth mean. With a wide birth intensity build the PHD with
``merge_threshold=0`` (each component stays apart; ``max_components`` keeps the heaviest).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..association import mahalanobis_squared
from ..core import ConfigError, Gaussian, Measurement, check_probability, invalid
from ..filters import GMPHDFilter, PhdIntensity
from .initiators import MofNInitiator, Status
from .state import LiveTrack


@dataclass(frozen=True, eq=False)
class PHDBirthState:
    """The intensity of the targets no track explains yet, at ``time`` (None before the first
    scan), and ``saturated``: how many sensor scans had more leftovers than the initiator's
    ``max_measurements`` (they started nothing)."""

    intensity: PhdIntensity
    time: float | None = None
    saturated: int = 0


@dataclass(frozen=True, eq=False)
class PHDInitiator:
    """A scan-level initiator (module docstring) for
    :class:`~fusetrack.tracking.MultiTargetTracker` and :class:`~fusetrack.tracking.MHTTracker`.

    ``phd``: a :class:`~fusetrack.filters.GMPHDFilter` whose birth intensity covers where
    targets appear (its sensors: those that may start tracks; other sensors' leftovers are
    ignored). ``threshold``: the weight above which a component becomes a track (Vo & Ma's
    extraction threshold 0.5). ``m``, ``n``: a tentative track is confirmed when detected in
    ``m`` of its first ``n`` scans. ``existence``: a new track's existence probability.
    ``max_measurements``: a sensor scan with more leftovers than this (a flood of false alarms)
    updates the intensity as if the sensor saw nothing and starts no track, counted in
    ``PHDBirthState.saturated`` (the GM-PHD update and its merging grow with the number of
    detections times components: a flood would cost seconds).
    """

    phd: GMPHDFilter
    threshold: float = 0.5
    m: int = 2
    n: int = 3
    existence: float = 0.5
    max_measurements: int = 500
    _rule: MofNInitiator = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.phd, GMPHDFilter):
            raise ConfigError(invalid("phd", self.phd, "a GMPHDFilter"))
        threshold = check_probability("threshold", self.threshold)
        if threshold == 0.0:
            raise ConfigError(invalid("threshold", self.threshold, "a weight in (0, 1]"))
        cap = self.max_measurements
        if isinstance(cap, bool) or not isinstance(cap, int | np.integer) or cap < 1:
            raise ConfigError(invalid("max_measurements", cap, "an integer >= 1"))
        # the M-of-N rule and existence checks of MofNInitiator
        object.__setattr__(self, "_rule", MofNInitiator(self.m, self.n, _no_prior, self.existence))

    def initial_state(self) -> PHDBirthState:
        return PHDBirthState(PhdIntensity.empty(self.phd.motion.dim))

    def birth(self, measurement: Measurement) -> None:
        """None: this initiator starts tracks from the intensity (:meth:`births`), never from one
        measurement alone."""
        return None

    def status(self, track: LiveTrack) -> Status:
        return self._rule.status(track)

    def births(
        self,
        state: PHDBirthState,
        time: float,
        sensor_id: str,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> tuple[PHDBirthState, list[tuple[Gaussian, int | None]]]:
        """The new state and the tracks started by one sensor's ``measurements`` (those no
        track took) at ``time``: ``(belief, index of the measurement credited or None)``."""
        if sensor_id not in self.phd.sensors:
            return state, []
        intensity = state.intensity
        if state.time is None or time > state.time:
            dt = 0.0 if state.time is None else time - state.time
            intensity = self.phd.predict(intensity, dt)
        saturated = len(measurements) > self.max_measurements
        scan = [] if saturated else list(measurements)
        nothing = Measurement(time, sensor_id, np.full(self.phd.sensors[sensor_id].dim, np.nan))
        intensity = self.phd.update(intensity, scan or [nothing])
        heavy = intensity.weights > self.threshold
        started = [
            (Gaussian(mean, cov), self._credited(sensor_id, mean, cov, scan))
            for mean, cov in zip(intensity.means[heavy], intensity.covs[heavy], strict=True)
        ]
        light = ~heavy
        rest = PhdIntensity(
            intensity.weights[light],
            intensity.means[light],
            intensity.covs[light],
            intensity.labels[light],
            intensity.next_label,
        )
        return PHDBirthState(rest, time, state.saturated + saturated), started

    def _credited(
        self, sensor_id: str, mean: Any, cov: Any, measurements: Sequence[Measurement]
    ) -> int | None:
        if not measurements:
            return None
        sensor = self.phd.sensors[sensor_id]
        d2 = mahalanobis_squared(sensor, [Gaussian(mean, cov)], measurements)
        return int(np.argmin(d2[0]))


def _no_prior(measurement: Measurement) -> None:
    return None
