"""The track-oriented Poisson multi-Bernoulli filter as a tracker (Williams 2015,
:mod:`~fusetrack.tracking.pmb`): its probable Bernoullis are the tracks, each keeping the
identity of the measurement that created it, behind the tracker interface
(:class:`~.protocol.Tracker`)."""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..core import ConfigError, Gaussian, Measurement, check_probability, invalid
from .pmb import PMBDensity, PMBFilter
from .protocol import TrackView
from .recording import RecordingRunner, predict_and_update

EXTRACTIONS = ("threshold", "map")


@dataclass(frozen=True)
class PMBTrackerState:
    """The PMB density after the scan at ``time``, its tracks, and the public id of every
    Bernoulli label ever extracted (ids count from 0 in order of first extraction)."""

    density: PMBDensity
    time: float | None = None
    confirmed: tuple[TrackView, ...] = ()
    ids: Mapping[int, int] = field(default_factory=dict)


class PMBTracker(RecordingRunner):
    """The PMB filter as a tracker: predict to the scan, update with the scan's readings (every
    sensor in ``scanned``, default all, that sent nothing looked and saw nothing: a NaN
    reading, the missed-detection terms only), then the tracks are the Bernoullis with
    existence above ``threshold`` (``extraction="threshold"``), or the ``n`` most probable
    ones where ``n`` maximises the multi-Bernoulli cardinality distribution
    (``extraction="map"``). A track's id stays with its Bernoulli's label."""

    def __init__(
        self, pmb: PMBFilter, threshold: float = 0.5, extraction: str = "threshold"
    ) -> None:
        if not isinstance(pmb, PMBFilter):
            raise ConfigError(invalid("pmb", pmb, "a PMBFilter"))
        if extraction not in EXTRACTIONS:
            raise ConfigError(invalid("extraction", extraction, f"one of {EXTRACTIONS}"))
        self.filter = pmb
        self.threshold = check_probability("threshold", threshold)
        self.extraction = extraction

    def initial_state(self) -> PMBTrackerState:
        return PMBTrackerState(PMBDensity.empty(self.filter.motion.dim))

    def step(
        self,
        state: PMBTrackerState,
        time: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
        *,
        scanned: Collection[str] | None = None,
    ) -> PMBTrackerState:
        density: PMBDensity = predict_and_update(
            self.filter,
            state.density,
            state.time,
            time,
            measurements,
            self.filter.sensors,
            scanned,
            rng,
        )
        ids = dict(state.ids)
        tracks = []
        for i in self.extracted(density):
            label = int(density.tracks.labels[i])
            ident = ids.setdefault(label, len(ids))
            tracks.append(
                TrackView(ident, Gaussian(density.tracks.means[i], density.tracks.covs[i]))
            )
        tracks.sort(key=lambda t: t.id)
        return PMBTrackerState(density, time, tuple(tracks), ids)

    def extracted(self, density: PMBDensity) -> NDArray[np.intp]:
        """The indices of the Bernoullis reported as tracks, most probable first."""
        r = density.existence
        order = np.argsort(-r, kind="stable")
        if self.extraction == "threshold":
            return order[r[order] > self.threshold]
        return order[: int(np.argmax(cardinality_distribution(r)))]


def cardinality_distribution(existence: NDArray[np.float64]) -> NDArray[np.float64]:
    """``P(n targets)``, ``n = 0..N``, of independent Bernoullis with existence ``r_i``: the
    coefficients of ``prod_i (1 - r_i + r_i x)`` (Mahler 2007, Eq. 11.131)."""
    p = np.ones(1)
    for r in np.asarray(existence, dtype=float):
        p = np.convolve(p, [1.0 - r, r])
    return p
