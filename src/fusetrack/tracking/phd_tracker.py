"""The GM-PHD filter as a tracker (Vo & Ma 2006): its labelled components above a weight
threshold are the tracks, behind the tracker interface (:class:`~.protocol.Tracker`); with the
GM-CPHD filter (Vo, Vo & Cantoni 2007) the tracks are the most probable number's heaviest
components."""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core import ConfigError, Gaussian, Measurement, invalid
from ..filters import (
    CphdBelief,
    GMCPHDFilter,
    GMPHDFilter,
    PhdIntensity,
    extract_cphd_states,
    extract_states,
)
from .protocol import TrackView
from .recording import RecordingRunner, predict_and_update


@dataclass(frozen=True)
class PHDTrackerState:
    """The PHD intensity (with the CPHD filter: the intensity and the count distribution) after
    the scan at ``time``, its tracks, and the public id of every label ever extracted (ids
    count from 0 in order of first extraction)."""

    intensity: PhdIntensity | CphdBelief
    time: float | None = None
    confirmed: tuple[TrackView, ...] = ()
    ids: Mapping[int, int] = field(default_factory=dict)


class PHDTracker(RecordingRunner):
    """The GM-PHD filter as a tracker: predict to the scan, update with the scan's readings
    (every sensor in ``scanned``, default all, that sent nothing looked and saw nothing: a NaN
    reading, the missed-detection term only), then the components of weight above
    ``threshold`` are the tracks (Vo & Ma 2006, Table III). A label shared by several of them
    stays with the heaviest; the others get fresh labels, kept from then on.

    With a :class:`~fusetrack.filters.GMCPHDFilter` the tracks are the ``map_count`` heaviest
    components (Vo, Vo & Cantoni 2007, Sec. IV-C) and ``threshold`` is not used; the initial
    state is "no target, for certain" over counts ``0..max_count``."""

    def __init__(
        self, phd: GMPHDFilter | GMCPHDFilter, threshold: float = 0.5, *, max_count: int = 100
    ) -> None:
        if not isinstance(phd, GMPHDFilter | GMCPHDFilter):
            raise ConfigError(invalid("phd", phd, "a GMPHDFilter or a GMCPHDFilter"))
        self.filter = phd
        self.threshold = float(threshold)
        self.max_count = int(max_count)

    @property
    def _phd(self) -> GMPHDFilter:
        """The PHD filter itself (the CPHD filter's intensity part): models and sensors."""
        return self.filter.phd if isinstance(self.filter, GMCPHDFilter) else self.filter

    def initial_state(self) -> PHDTrackerState:
        dim = self._phd.motion.dim
        if isinstance(self.filter, GMCPHDFilter):
            return PHDTrackerState(CphdBelief.empty(dim, self.max_count))
        return PHDTrackerState(PhdIntensity.empty(dim))

    def step(
        self,
        state: PHDTrackerState,
        time: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
        *,
        scanned: Collection[str] | None = None,
    ) -> PHDTrackerState:
        v: Any = predict_and_update(
            self.filter,
            state.intensity,
            state.time,
            time,
            measurements,
            self._phd.sensors,
            scanned,
            rng,
        )
        if isinstance(v, CphdBelief):
            v = CphdBelief(_distinct_labels(v.intensity, top=v.map_count), v.cardinality)
            extracted = extract_cphd_states(v)
        else:
            v = _distinct_labels(v, threshold=self.threshold)
            extracted = extract_states(v, self.threshold)
        ids = dict(state.ids)
        tracks: dict[int, TrackView] = {}
        for label, mean, cov in extracted:
            ident = ids.setdefault(label, len(ids))
            tracks.setdefault(ident, TrackView(ident, Gaussian(mean, cov)))
        return PHDTrackerState(v, time, tuple(tracks[i] for i in sorted(tracks)), ids)


def _distinct_labels(
    v: PhdIntensity, *, threshold: float = -np.inf, top: int | None = None
) -> PhdIntensity:
    """``v`` with a fresh label on every extracted component (weight above ``threshold``,
    among the ``top`` heaviest) whose label a heavier extracted one already has (two targets
    born of one birth component share its label)."""
    labels, nxt, seen = v.labels.copy(), int(v.next_label), set()
    order = np.argsort(-v.weights, kind="stable")
    for i in order if top is None else order[:top]:
        if v.weights[i] <= threshold:
            break
        if labels[i] in seen:
            labels[i], nxt = nxt, nxt + 1
        seen.add(int(labels[i]))
    if nxt == v.next_label:
        return v
    return PhdIntensity(v.weights, v.means, v.covs, labels, nxt)
