"""What a multi-target tracker carries from one scan to the next: immutable values only."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True, eq=False)
class LiveTrack:
    """One live track after a scan.

    ``belief`` is the filter's belief at ``time``; ``born`` the time of the measurement that
    started it and ``last_hit`` the last scan in which it was detected. ``scans`` counts the
    scans since its birth (the birth scan is 1), ``hits`` those in which it was detected,
    ``misses`` the missed scans since the last hit. A track is detected in a scan when, for some
    sensor, its association gives it a measurement with probability >= 1/2.
    ``existence`` is its probability of being a real target (:mod:`.existence`).
    ``measurements`` are the indices (into the scan's measurement list) of the measurements its
    hypotheses used in the last scan, with their association ``probabilities``.
    """

    id: int
    belief: Any
    time: float
    born: float
    last_hit: float
    confirmed: bool = False
    scans: int = 1
    hits: int = 1
    misses: int = 0
    existence: float = 0.5
    measurements: tuple[int, ...] = ()
    probabilities: tuple[float, ...] = ()


@dataclass(frozen=True, eq=False)
class TrackerState:
    """The tracker's state after a scan at ``time`` (None before the first): the live tracks,
    tentative and confirmed, in id order, and the id the next new track will take."""

    tracks: tuple[LiveTrack, ...] = ()
    time: float | None = None
    next_id: int = 0

    @property
    def confirmed(self) -> tuple[LiveTrack, ...]:
        return tuple(t for t in self.tracks if t.confirmed)

    @property
    def tentative(self) -> tuple[LiveTrack, ...]:
        return tuple(t for t in self.tracks if not t.confirmed)
